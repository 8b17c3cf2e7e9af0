"""Hostile input and odd machines (issue 34): what the readers refuse before reading, the bounds on what they allocate,
numbers out of range, and the thread cap. ``docs/input.md`` ("Limits") lists them."""

from __future__ import annotations

import base64
import json
import lzma
import os
import re
import struct
import subprocess
import sys
import tracemalloc
import zlib
from pathlib import Path

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.errors import MeshFormatError
from cvxgeodesic.mesh.formats import tetgen

ROOT = Path(cg.__file__).parents[1]
TETRA_NODE = "4 3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"
TETRA_ELE = "1 4\n1 1 2 3 4\n"


def _env() -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    return env


# ---------------------------------------------------------------------------------------------------------------------
# Item 1: only regular files are read. Without the check a FIFO's open blocks and /dev/zero never ends (it fills the
# memory), so the loads run in a subprocess with a memory limit and a timeout: a regression fails, it does not hang.
# ---------------------------------------------------------------------------------------------------------------------
LOAD_ALL = """
import json, resource, sys, warnings
resource.setrlimit(resource.RLIMIT_AS, (2 << 30, 2 << 30))  # /dev/zero read to the end fails here, not the machine
warnings.simplefilter("ignore")
import cvxgeodesic as cg
out = {}
for path in sys.argv[1:]:
    load = cg.load_distance if path.endswith((".npy", ".csv")) else cg.load_mesh
    try:
        load(path)
        out[path] = "loaded"
    except Exception as exc:
        out[path] = f"{type(exc).__name__}: {exc}"
print(json.dumps(out))
"""


def _load_in_subprocess(paths: list[Path]) -> dict:
    # 120 s: a few imports and stats on a loaded machine take seconds; a blocked open takes forever
    out = subprocess.run([sys.executable, "-c", LOAD_ALL, *map(str, paths)], env=_env(), capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


@pytest.mark.skipif(not hasattr(os, "mkfifo") or not Path("/dev/zero").exists(), reason="needs FIFOs and /dev/zero")
def test_fifos_and_devices_are_refused_before_they_are_opened(tmp_path):
    # a TetGen pair whose .node is a FIFO (its .ele a real file), and a FIFO or a link to /dev/zero in every family
    (tmp_path / "fifo.ele").write_text(TETRA_ELE)
    fifos = [tmp_path / f"fifo{ext}" for ext in (".node", ".obj", ".msh", ".npy")]
    for p in fifos:
        os.mkfifo(p)
    (tmp_path / "zero.node").write_text(TETRA_NODE)
    zeros = [tmp_path / f"zero{ext}" for ext in (".ele", ".ply", ".vtu", ".gltf", ".mesh", ".csv")]
    for p in zeros:
        p.symlink_to("/dev/zero")
    got = _load_in_subprocess([tmp_path / "fifo.ele", *fifos[1:], *zeros])
    assert got[str(tmp_path / "fifo.ele")] == (f"MeshFormatError: {tmp_path / 'fifo.node'}: is a FIFO, not a TetGen "
                                               "file (only regular files are read)")
    for p in fifos[1:]:
        assert got[str(p)].startswith(f"MeshFormatError: {p}: is a FIFO, not a "), got[str(p)]
    for p in zeros:
        assert got[str(p)].startswith(f"MeshFormatError: {p}: is a character device, not a "), got[str(p)]
        assert got[str(p)].endswith("(only regular files are read)")


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs")
def test_the_command_line_refuses_a_fifo(tmp_path):
    fifo = tmp_path / "mesh.obj"
    os.mkfifo(fifo)
    out = subprocess.run([sys.executable, "-m", "cvxgeodesic.cli", "distance", str(fifo), "-s", "0", "-o",
                          str(tmp_path / "d.ply")], env=_env(), capture_output=True, text=True, timeout=120)
    assert out.returncode == 2, out.stderr
    assert f"{fifo}: is a FIFO, not a mesh file (only regular files are read)" in out.stderr
    assert "Traceback" not in out.stderr


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs")
def test_a_fifo_as_the_cost_file_is_refused(tmp_path):
    """--cost is read with np.load: a FIFO there blocked the command as the mesh FIFO did."""
    from cvxgeodesic.cli import main

    cg.save_distance(tmp_path / "m.ply", cg.icosphere(1), np.zeros(42))
    os.mkfifo(tmp_path / "c.npy")
    with pytest.raises(cg.MeshFormatError, match=r"c.npy: is a FIFO, not a .npy file \(--cost\)"):
        from cvxgeodesic.cli._options import cli_cost

        cli_cost(type("Args", (), {"cost": str(tmp_path / "c.npy"), "cost_field": None})(), cg.icosphere(1))
    assert main(["distance", str(tmp_path / "m.ply"), "-s", "0", "--method", "qclp", "--cost",
                 str(tmp_path / "c.npy"), "-o", str(tmp_path / "d.npy"), "-q"]) == 2


def test_a_link_to_a_regular_file_is_read(tmp_path):
    (tmp_path / "m.node").write_text(TETRA_NODE)
    (tmp_path / "m.ele").write_text(TETRA_ELE)
    (tmp_path / "link.node").symlink_to(tmp_path / "m.node")
    (tmp_path / "link.ele").symlink_to(tmp_path / "m.ele")
    assert cg.load_mesh(tmp_path / "link.ele").T.tolist() == [[0, 1, 2, 3]]
    (tmp_path / "dangling.obj").symlink_to(tmp_path / "nothing.obj")
    with pytest.raises(FileNotFoundError, match="dangling.obj: no such file"):
        cg.load_mesh(tmp_path / "dangling.obj")


# ---------------------------------------------------------------------------------------------------------------------
# Item 3: numbers out of range name the file and the line
# ---------------------------------------------------------------------------------------------------------------------
HUGE = "99999999999999999999"  # > 2**63: no int64 holds it


@pytest.mark.parametrize("node, ele, match", [
    (TETRA_NODE, f"1 4\n1 1 2 3 {HUGE}\n", rf"m.ele, line 2: point numbers: {HUGE} is out of range"),
    (TETRA_NODE.replace("4 0 0 1", f"{HUGE} 0 0 1"), TETRA_ELE, rf"m.node, line 5: point numbers: {HUGE} is out of"),
    (f"{HUGE} 3\n1 0 0 0\n", TETRA_ELE, rf"m.node, line 1: the header \(points, .*\): {HUGE} is out of range"),
    (TETRA_NODE, f"{HUGE} 4\n1 1 2 3 4\n", rf"m.ele, line 1: the header \(tetrahedra, .*\): {HUGE} is out of"),
    (TETRA_NODE, "1 4\n1 1 2 3 1e23\n", r"m.ele, line 2: point numbers must be integers, got '1 2 3 1e23'"),
])
def test_tetgen_numbers_out_of_range_name_file_and_line(tmp_path, node, ele, match):
    (tmp_path / "m.node").write_text(node)
    (tmp_path / "m.ele").write_text(ele)
    with pytest.raises(MeshFormatError, match=match):
        tetgen.read_mesh(tmp_path / "m.ele")


@pytest.mark.parametrize("name, text, match", [
    ("f.obj", f"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 {HUGE}\n", rf"line 4: face \('f'\) has a vertex index {HUGE} that"),
    ("f.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 1e23\n", r"line 4: face \('f'\) has a non-integer vertex index '1e23'"),
    ("f.off", f"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 {HUGE}\n", rf"line 6: face has a vertex index {HUGE} that"),
    ("f.off", f"OFF\n{HUGE} 1 0\n0 0 0\n", rf"file ends after 1 of {HUGE} vertices"),
    ("f.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 1e23\n", r"line 6: face has a non-integer vertex index '1e23'"),
])
def test_surface_text_readers_refuse_numbers_out_of_range(tmp_path, name, text, match):
    # already guarded before issue 34 (parse_int_tokens): kept here so that the family stays covered
    (tmp_path / name).write_text(text)
    with pytest.raises(MeshFormatError, match=match):
        cg.load_mesh(tmp_path / name)



# ---------------------------------------------------------------------------------------------------------------------
# Item 4: broken glTF JSON is a format error naming the JSON problem (trimesh reported it as a missing file)
# ---------------------------------------------------------------------------------------------------------------------
def _glb(json_bytes: bytes, declared: int | None = None) -> bytes:
    chunk = struct.pack("<I4s", len(json_bytes) if declared is None else declared, b"JSON") + json_bytes
    return b"glTF" + struct.pack("<II", 2, 12 + len(chunk)) + chunk


@pytest.mark.parametrize("name, make", [
    ("arrays.gltf", lambda: b"[" * 200_000 + b"]" * 200_000),
    ("objects.gltf", lambda: b'{"a":' * 200_000 + b"1" + b"}" * 200_000),
    ("arrays.glb", lambda: _glb(b'{"asset": ' + b"[" * 200_000 + b"]" * 200_000 + b"}")),
], ids=["gltf-arrays", "gltf-objects", "glb-arrays"])
def test_gltf_json_nested_too_deeply_is_a_format_error(tmp_path, name, make):
    """issue 41 (D15): JSON 200,000 levels deep gave a raw RecursionError."""
    pytest.importorskip("trimesh")
    path = tmp_path / name
    path.write_bytes(make())
    with pytest.raises(MeshFormatError) as exc:
        cg.load_mesh(path)
    assert str(exc.value) == f"{path}: not valid glTF JSON (arrays or objects nested too deeply to parse)"


@pytest.mark.parametrize("name, data, message", [
    ("b.gltf", b'{"asset": {"version": "2.0"}, "meshes": [', "not valid glTF JSON (Expecting value at line 1, "
                                                             "column 42)"),
    ("b.gltf", b'{"asset": {"version": "2.0"},\n "meshes": [}]}', "not valid glTF JSON (Expecting value at line 2, "
                                                                  "column 13)"),
    ("b.gltf", b"[1, 2]", "not valid glTF JSON (a glTF file is a JSON object, this one is a list)"),
    ("b.gltf", b'{"a": "\xff"}', "not valid glTF JSON (not UTF-8 text: byte 7)"),
    ("b.glb", _glb(b'{"asset": '), "not valid glTF JSON (Expecting value at line 1, column 11)"),
    ("b.glb", _glb(b'{"asset": {}}', declared=1000), "binary glTF (version 2) whose first chunk is not a complete "
                                                     "JSON chunk"),
    ("b.glb", b"GLTF" + bytes(40), "not a binary glTF file (it does not start with the GLB header 'glTF')"),
])
def test_broken_gltf_json_is_a_format_error_naming_the_problem(tmp_path, name, data, message):
    pytest.importorskip("trimesh")
    path = tmp_path / name
    path.write_bytes(data)
    with pytest.raises(MeshFormatError) as exc:
        cg.load_mesh(path)
    assert str(exc.value) == f"{path}: {message}"
    assert not isinstance(exc.value, FileNotFoundError)
    if name.endswith(".glb"):
        with pytest.raises(MeshFormatError, match=re.escape(message)):
            cg.load_distance(path)


# ---------------------------------------------------------------------------------------------------------------------
# Item 2: what meshio allocates is bounded by the file's size (mesh/formats/_limits.py, _vtu_limits.py)
# ---------------------------------------------------------------------------------------------------------------------
TET_POINTS = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)


def _vtk_blocks(raw: bytes, codec: str, declare: int | None = None) -> tuple[bytes, bytes]:
    """VTK's compressed layout: the header (blocks, block size, last block's size, compressed sizes) and the blocks;
    ``declare``: the block and last block sizes the header declares instead of the true ones."""
    size = 1 << 20  # VTK writes 32 KB blocks; 1 MB ones make the 16 MB arrays below quick to write in LZMA
    chunks = [raw[i:i + size] for i in range(0, len(raw), size)] or [b""]
    packed = [zlib.compress(c) if codec == "zlib" else lzma.compress(c) for c in chunks]
    full, last = (size, len(chunks[-1])) if declare is None else (declare, declare)
    return struct.pack(f"<{3 + len(packed)}I", len(packed), full, last, *map(len, packed)), b"".join(packed)


def _refused_with_peak(path: Path) -> tuple[str, int]:
    """The MeshFormatError's message of loading ``path`` and the peak of the memory Python allocated meanwhile
    (numpy's allocations are traced too)."""
    tracemalloc.start()
    try:
        with pytest.raises(MeshFormatError) as exc:
            cg.load_mesh(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    return str(exc.value), peak


def _write_vtu(path: Path, *, n_points: int = 4, points: bytes | None = None, layout: str = "inline",
               codec: str = "zlib", connectivity: bytes | None = None, declare: int | None = None) -> Path:
    """One tetrahedron as a compressed VTU, its arrays inline, appended in base64 or appended raw; ``connectivity``
    and the inflated size its block header declares (``declare``, one block) may be given."""
    arrays = [("Points", 'type="Float64" NumberOfComponents="3"', TET_POINTS.tobytes() if points is None else points),
              ("Cells", 'type="Int64" Name="connectivity"',
               np.arange(4, dtype=np.int64).tobytes() if connectivity is None else connectivity),
              ("Cells", 'type="Int64" Name="offsets"', np.array([4], dtype=np.int64).tobytes()),
              ("Cells", 'type="UInt8" Name="types"', np.array([10], dtype=np.uint8).tobytes())]
    tags, appended = {"Points": [], "Cells": []}, b""
    for section, attrs, raw in arrays:
        header, blocks = _vtk_blocks(raw, codec, declare if "connectivity" in attrs else None)
        encoded = base64.b64encode(header) + base64.b64encode(blocks) if layout != "raw" else header + blocks
        if layout == "inline":
            tags[section].append(f'<DataArray {attrs} format="binary">'.encode() + encoded + b"</DataArray>")
        else:
            tags[section].append(f'<DataArray {attrs} format="appended" offset="{len(appended)}"/>'.encode())
            appended += encoded
    compressor = {"zlib": "vtkZLibDataCompressor", "lzma": "vtkLZMADataCompressor"}[codec]
    text = (f'<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian" '
            f'header_type="UInt32" compressor="{compressor}">\n<UnstructuredGrid>\n'
            f'<Piece NumberOfPoints="{n_points}" NumberOfCells="1">\n').encode()
    text += b"<Points>" + b"".join(tags["Points"]) + b"</Points>\n<Cells>" + b"".join(tags["Cells"]) + b"</Cells>\n"
    text += b"</Piece>\n</UnstructuredGrid>\n"
    if layout != "inline":
        encoding = "raw" if layout == "raw" else "base64"
        text += f'<AppendedData encoding="{encoding}">\n_'.encode() + appended + b"\n</AppendedData>\n"
    path.write_bytes(text + b"</VTKFile>\n")
    return path


LAYOUTS = [(layout, codec) for layout in ("inline", "base64", "raw") for codec in ("zlib", "lzma")]


@pytest.mark.parametrize("layout, codec", LAYOUTS)
def test_a_genuine_compressed_vtu_passes_the_checks(tmp_path, layout, codec):
    pytest.importorskip("meshio")
    mesh = cg.load_mesh(_write_vtu(tmp_path / "t.vtu", layout=layout, codec=codec))
    np.testing.assert_array_equal(mesh.V, TET_POINTS)
    assert mesh.T.tolist() == [[0, 1, 2, 3]]


@pytest.mark.parametrize("layout, codec", LAYOUTS)
def test_a_compressed_array_larger_than_its_counts_is_refused_before_it_is_inflated(tmp_path, layout, codec):
    pytest.importorskip("meshio")
    # 32 MB of zeros in a few kB, declared as 4 points: meshio inflated it all (twice: blocks, then joined)
    path = _write_vtu(tmp_path / "bomb.vtu", points=bytes(32 << 20), layout=layout, codec=codec)
    message, peak = _refused_with_peak(path)
    assert message == (f"{path}: DataArray 'Points' (piece 0) declares {32 << 20} bytes inflated (its "
                       "compressed-block header), more than the 96 bytes NumberOfPoints 4 allows (4 × 3 "
                       "component(s) × 8 bytes); refused before reading it")
    # the check inflates 1 MB at a time (and LZMA's decoder holds its 8 MB dictionary: measured peaks 1.1 MB with zlib,
    # 10.6 MB with LZMA); without the check meshio held the 32 MB at least once (numpy's allocations are traced too)
    assert peak < 16 << 20, peak


@pytest.mark.parametrize("raw", [True, False])
def test_compressed_arrays_cut_short_or_not_base64_are_refused(raw):
    from cvxgeodesic.mesh.formats._vtu_limits import _Refused, _split_blocks

    header, blocks = _vtk_blocks(bytes(100), "zlib")
    enc = (lambda b: b) if raw else base64.b64encode  # base64: header and blocks encoded apart, as VTK does

    def split(text):
        return _split_blocks(text, (4, "little"), raw=raw)

    assert split(enc(header) + enc(blocks)) == [(100, blocks)]
    with pytest.raises(_Refused, match="^has a compressed-block header cut short$"):
        split(enc(header)[:8])
    with pytest.raises(_Refused, match="^has compressed blocks cut short$"):
        split(enc(header) + enc(blocks)[:-4])
    if not raw:
        with pytest.raises(_Refused, match=r"^is not valid base64 \("):
            split(enc(header) + b"abcde")


class _Inflation:
    """Counts the bytes every zlib and LZMA decompressor gives (the check's and meshio's)."""

    def __init__(self, monkeypatch) -> None:
        self.total = 0
        for module, name in ((zlib, "decompressobj"), (lzma, "LZMADecompressor")):
            monkeypatch.setattr(module, name, self._counting(getattr(module, name)))
        monkeypatch.setattr(zlib, "decompress", self._counted(zlib.decompress))
        monkeypatch.setattr(lzma, "decompress", self._counted(lzma.decompress))

    def _counted(self, fn):
        def wrapper(*args, **kwargs):
            out = fn(*args, **kwargs)
            self.total += len(out)
            return out
        return wrapper

    def _counting(self, make):
        outer = self

        class Counting:
            def __init__(self, *args, **kwargs) -> None:
                self._d = make(*args, **kwargs)

            def decompress(self, *args, **kwargs):
                out = self._d.decompress(*args, **kwargs)
                outer.total += len(out)
                return out

            def __getattr__(self, name):
                return getattr(self._d, name)

        return Counting


@pytest.mark.parametrize("layout, codec", LAYOUTS)
def test_a_block_header_that_declares_more_than_the_file_allows_is_refused_before_inflating(tmp_path, monkeypatch,
                                                                                           layout, codec):
    """issue 41 (D9): an array without a count of its own (connectivity) whose block header declared about 1032 ×
    the file's size was inflated to that much (4.97 GB, 19.8 s) before its refusal; now the header's declaration
    is refused before anything is inflated."""
    pytest.importorskip("meshio")
    declared = 4_000_000_000  # UInt32 headers: at most 2**32 - 1
    path = _write_vtu(tmp_path / "bomb.vtu", layout=layout, codec=codec, declare=declared)
    budget = path.stat().st_size * 1032
    inflation = _Inflation(monkeypatch)
    with pytest.raises(MeshFormatError) as exc:
        cg.load_mesh(path)
    assert inflation.total == 96  # the 4 points before it, nothing of the connectivity
    assert str(exc.value).startswith(f"{path}: DataArray 'connectivity' (piece 0) declares {declared} bytes inflated "
                                     f"(its compressed-block header), more than the ")
    left = re.search(r"more than the (\d+) bytes the file's size allows", str(exc.value))
    assert left is not None and budget - 200 < int(left.group(1)) <= budget, str(exc.value)  # less the points


@pytest.mark.parametrize("layout, codec", LAYOUTS)
def test_a_block_that_inflates_past_its_declared_size_is_refused(tmp_path, layout, codec):
    """A header that declares less than its block holds: the block is refused as soon as it passes the declaration
    (meshio inflates each block whole, whatever the header says)."""
    pytest.importorskip("meshio")
    path = _write_vtu(tmp_path / "liar.vtu", layout=layout, codec=codec, connectivity=bytes(8 << 20), declare=32)
    message, peak = _refused_with_peak(path)
    assert message == (f"{path}: DataArray 'connectivity' (piece 0) has a block (block 0) that inflates to "
                       "more than the 32 bytes its compressed-block header declares; refused before reading it")
    assert peak < 16 << 20, peak


def test_vtu_counts_no_file_of_its_size_could_hold_are_refused(tmp_path):
    pytest.importorskip("meshio")
    path = _write_vtu(tmp_path / "huge.vtu", n_points=10**12)
    size = path.stat().st_size
    with pytest.raises(MeshFormatError) as exc:
        cg.load_mesh(path)
    assert str(exc.value) == (f"{path}: the header declares {10**12} points (NumberOfPoints of piece 0), more than a "
                              f"file of {size} bytes can hold (at most {size * 1032 // 3}: 3 byte(s) each, compressed "
                              "at most 1032:1)")


MSH4_HEAD = b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
MSH4_BINARY_HEAD = b"$MeshFormat\n4.1 1 8\n\x01\x00\x00\x00\n$EndMeshFormat\n"  # the 1 written in binary: byte order


@pytest.mark.parametrize("name, text, declared", [
    ("p.vtk", b"# vtk DataFile Version 4.2\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 100000000 double\n0 0 0\n",
     "100000000 points (POINTS)"),
    ("c.vtk", b"# vtk DataFile Version 4.2\nx\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 1 float\n" + bytes(12)
     + b"\nCELLS 1 50000000\n", "50000000 entries (CELLS)"),
    ("g.vtk", b"# vtk DataFile Version 4.2\nx\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 10000 10000 10000\n",
     f"{10**12} grid points (DIMENSIONS)"),
    ("v2.msh", b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n100000000\n1 0 0 0\n$EndNodes\n",
     "100000000 nodes ($Nodes)"),
    ("v4.msh", MSH4_HEAD + b"$Nodes\n1 100000000 1 100000000\n3 1 0 1\n1\n0 0 0\n$EndNodes\n",
     "100000000 nodes ($Nodes)"),
    ("v4b.msh", MSH4_BINARY_HEAD + b"$Nodes\n" + struct.pack("<4Q", 1, 10**8, 1, 10**8),
     "100000000 nodes ($Nodes)"),
    ("tag.msh", MSH4_HEAD + b"$Nodes\n1 1 1 100000000000\n3 1 0 1\n100000000000\n0 0 0\n$EndNodes\n",
     "100000000000 node tags ($Nodes: the largest tag)"),
    ("e.msh", b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Elements\n100000000\n$EndElements\n",
     "100000000 elements ($Elements)"),
    ("m.mesh", b"MeshVersionFormatted 2\nDimension 3\nVertices\n100000000\n0 0 0 0\nEnd\n",
     "100000000 vertices (Vertices)"),
    ("t.mesh", b"MeshVersionFormatted 2\nDimension\n3\nTetrahedra 100000000\n1 2 3 4 0\nEnd\n",
     "100000000 tetrahedra (Tetrahedra)"),
])
def test_header_counts_past_the_file_size_are_refused_before_meshio_reads(tmp_path, name, text, declared):
    pytest.importorskip("meshio")
    path = tmp_path / name
    path.write_bytes(text)
    with pytest.raises(MeshFormatError, match=re.escape(f"{path}: the header declares {declared}, more than a file of "
                                                        f"{len(text)} bytes can hold")):
        cg.load_mesh(path)


@pytest.mark.parametrize("ext, fmt, binary", [
    (".msh", "gmsh", True), (".msh", "gmsh", False), (".msh", "gmsh22", True), (".vtk", "vtk42", True),
    (".vtk", "vtk51", True), (".vtk", "vtk51", False), (".vtu", "vtu", True), (".mesh", "medit", None),
])
def test_genuine_meshio_files_pass_the_count_checks(tmp_path, ext, fmt, binary):
    meshio = pytest.importorskip("meshio")
    box = cg.tet_box(2, jitter=0.2, seed=3)
    path = tmp_path / f"box{ext}"
    kwargs = {} if binary is None else {"binary": binary}  # medit's writer has no binary option
    meshio.Mesh(box.V, [("tetra", box.T)]).write(path, file_format=fmt, **kwargs)
    mesh = cg.load_mesh(path)
    np.testing.assert_allclose(mesh.V, box.V, atol=1e-12)  # every format here stores float64 (medit version 2)
    np.testing.assert_array_equal(mesh.T, box.T)


def test_the_checks_read_the_file_where_it_cannot_be_mapped(tmp_path, monkeypatch):
    pytest.importorskip("meshio")
    from cvxgeodesic.mesh.formats import _limits

    def no_mmap(*args, **kwargs):
        raise OSError("mmap: operation not supported")  # some FUSE and network file systems

    monkeypatch.setattr(_limits.mmap, "mmap", no_mmap)
    path = _write_vtu(tmp_path / "bomb.vtu", points=bytes(4 << 20))
    with pytest.raises(MeshFormatError, match="DataArray 'Points' \\(piece 0\\) declares 4194304 bytes inflated"):
        cg.load_mesh(path)
    assert cg.load_mesh(_write_vtu(tmp_path / "ok.vtu")).T.tolist() == [[0, 1, 2, 3]]
