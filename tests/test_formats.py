"""The format registry (issue 23 item 5), reading fields back (issue 28 item 9), missing files (item 4) and
open3d's tensor mesh (item 6).

trimesh and meshio are optional (the ``io`` extra): the round trips through them skip without them.
"""

from __future__ import annotations

import errno
import pickle
import re

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.cli import build_parser
from cvxgeodesic.errors import MeshFileNotFoundError, MeshFormatError, ParameterError
from cvxgeodesic.mesh.formats.registry import (
    DISTANCE_EXTENSIONS,
    FORMATS,
    MESH_EXTENSIONS,
    POINT_EXTENSIONS,
    VOLUME_EXTENSIONS,
)

SPHERE = cg.icosphere(2)  # 162 vertices
EXT_RE = re.compile(r"(?<![\w/])\.[a-z0-9]+\b")  # ".obj", not "data/*.obj" or "cvxgeodesic[io]"


def _field(n=SPHERE.n_vertices):
    d = np.linspace(0.0, 2.0, n) / 3.0  # not float32-exact: the GLB's rounding shows
    d[5] = np.inf
    return d


def _needs(ext):
    pkg = FORMATS[ext].package
    if pkg is not None:
        pytest.importorskip(pkg, reason=f"{ext} needs {pkg} (the io extra)")


# ----------------------------------------------------------------------------------------------------------------------
# The registry drives the extension lists, the dispatch and the CLI's help
# ----------------------------------------------------------------------------------------------------------------------


def _subparsers():
    parser = build_parser()
    (sub,) = [a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction"]
    return sub.choices


def _extensions(text):
    return EXT_RE.findall(text)


def test_every_mesh_argument_lists_exactly_the_registry_formats():
    checked = []
    for command, p in _subparsers().items():
        for action in p._actions:
            if action.dest in ("mesh", "meshes"):
                found = _extensions(action.help)
                # the commands that take a volume list the tetrahedral files too (issue 26; batch: issue 41)
                volume = VOLUME_EXTENSIONS if command in ("distance", "compare", "view", "path", "matrix",
                                                          "batch") else ()
                # the commands that read their input with cli/_common.load_input take point files (issue 44)
                points = POINT_EXTENSIONS if command in ("distance", "path", "matrix", "view") else ()
                assert sorted(set(found)) == sorted({*MESH_EXTENSIONS, *volume, *points}), (command, action.help)
                checked.append(command)
    assert sorted(checked) == ["batch", "compare", "distance", "matrix", "path", "view"]
    # what `path --help` printed before: no .glb
    assert ".glb" in _subparsers()["path"].format_help()


def test_the_distance_output_lists_exactly_the_registry_formats():
    (action,) = [a for a in _subparsers()["distance"]._actions if a.dest == "output"]
    assert sorted(set(_extensions(action.help))) == sorted(DISTANCE_EXTENSIONS), action.help
    assert "_DISTANCE" in action.help and "float32" in action.help


def test_the_extension_lists_come_from_the_registry():
    assert MESH_EXTENSIONS == tuple(e for e, f in FORMATS.items() if f.read_mesh and 2 in f.dims)
    assert VOLUME_EXTENSIONS == tuple(e for e, f in FORMATS.items() if f.read_mesh and 3 in f.dims)
    assert set(DISTANCE_EXTENSIONS) == {".ply", ".npy", ".csv", ".glb", ".vtk", ".vtu"}
    for ext in DISTANCE_EXTENSIONS:  # every file save_distance writes, load_distance reads
        assert FORMATS[ext].read_field is not None, ext
    for ext, fmt in FORMATS.items():
        assert ext == ext.lower() and ext.startswith(".") and fmt.package in (None, "trimesh", "meshio", "laspy")
    assert POINT_EXTENSIONS == tuple(e for e, f in FORMATS.items() if f.read_points)
    assert {".xyz", ".pts", ".csv", ".npy", ".ply", ".las", ".laz"} == set(POINT_EXTENSIONS)
    for ext in POINT_EXTENSIONS:  # a format holding meshes and points says which a file holds
        assert (FORMATS[ext].holds_points is not None) == (FORMATS[ext].read_mesh is not None), ext


def test_point_files_are_read_through_the_registry(tmp_path, monkeypatch):
    from cvxgeodesic.mesh.formats._common import RawPoints
    from cvxgeodesic.mesh.formats.registry import Format, is_point_file

    g = np.linspace(0.0, 1.0, 6)
    P = np.c_[np.repeat(g, 6), np.tile(g, 6), np.zeros(36)]
    path = tmp_path / "c.xyz"
    path.write_text("not read\n")
    monkeypatch.setitem(FORMATS, ".xyz", Format(".xyz", "a test's points", dims=(), read_points=lambda p: RawPoints(P)))
    assert is_point_file(path) and not is_point_file(tmp_path / "m.obj")
    np.testing.assert_array_equal(cg.load_point_cloud(path).P, P)
    assert cg.GeodesicSolver(path, "dijkstra").mesh.n_vertices == 36  # as_mesh's dispatch: the same table
    monkeypatch.setitem(FORMATS, ".xyz", Format(".xyz", "a test's mesh-only format", read_mesh=lambda p: None))
    assert not is_point_file(path)


def test_a_point_file_of_an_unknown_extension_lists_the_registry(tmp_path):
    path = tmp_path / "c.obj"
    path.write_text("v 0 0 0\n")
    with pytest.raises(MeshFormatError, match=re.escape("supported: " + ", ".join(POINT_EXTENSIONS))):
        cg.load_point_cloud(path)
    with pytest.raises(MeshFormatError, match=r"\.xyz files hold points: load_point_cloud reads them"):
        cg.load_mesh(tmp_path / "c.xyz")


def test_unsupported_extensions_list_the_registry(tmp_path):
    path = tmp_path / "m.xyz"
    path.write_text("0 0 0\n")
    with pytest.raises(MeshFormatError, match=re.escape("supported: " + ", ".join(MESH_EXTENSIONS))):
        cg.load_mesh(path)
    with pytest.raises(MeshFormatError, match=re.escape("supported: " + ", ".join(DISTANCE_EXTENSIONS))):
        cg.load_distance(path)
    with pytest.raises(ParameterError, match=r"\.xyz"):
        cg.save_distance(path, SPHERE, _field())


# ----------------------------------------------------------------------------------------------------------------------
# load_distance: every format save_distance writes
# ----------------------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("ext", DISTANCE_EXTENSIONS)
def test_load_distance_round_trip(tmp_path, ext):
    _needs(ext)
    d = _field()
    for name in ("distance", "geo.dist-1"):
        path = cg.save_distance(tmp_path / f"d{ext.upper()}", SPHERE, d, name=name)
        got = cg.load_distance(path, name=name)
        assert got.dtype == np.float64 and got.shape == (SPHERE.n_vertices,)
        assert np.isinf(got[5]) and np.isfinite(np.delete(got, 5)).all()
        if ext == ".glb":  # glTF holds float32
            np.testing.assert_allclose(got, d, rtol=1e-7)
            assert not np.array_equal(got, d)
        else:
            np.testing.assert_array_equal(got, d)


@pytest.mark.parametrize("ext", sorted(set(DISTANCE_EXTENSIONS) - {".npy"}))
def test_load_distance_names_the_fields_a_file_has(tmp_path, ext):
    _needs(ext)
    path = cg.save_distance(tmp_path / f"d{ext}", SPHERE, _field(), name="geo")
    with pytest.raises(MeshFormatError) as info:
        cg.load_distance(path)
    msg = str(info.value)  # the file, the name asked for and the ones it has
    assert msg.startswith(f"{path}: ") and re.search(r"'_?distance'.*\b_?geo\b", msg, flags=re.I), msg
    np.testing.assert_array_equal(cg.load_distance(path, "geo")[:5], _field()[:5].astype(np.float32 if ext == ".glb"
                                                                                         else np.float64))


def test_load_distance_in_the_file_numbering(tmp_path):
    # an OBJ with a vertex in no face: the CLI's outputs have the file's 163 rows, load_distance returns them
    from cvxgeodesic.cli import main

    V = np.vstack([[9.0, 9.0, 9.0], SPHERE.V])
    src = tmp_path / "s.obj"
    src.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in V.tolist())
                   + "".join(f"f {a + 2} {b + 2} {c + 2}\n" for a, b, c in SPHERE.F.tolist()))
    expected = np.r_[np.inf, cg.geodesic_distance(SPHERE, 4, method="dijkstra")]
    for ext in (".ply", ".csv", ".npy"):
        out = tmp_path / f"d{ext}"
        assert main(["distance", str(src), "-s", "5", "--method", "dijkstra", "-q", "-o", str(out)]) == 0
        np.testing.assert_array_equal(cg.load_distance(out), expected)


def test_load_distance_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="none.ply: no such file"):
        cg.load_distance(tmp_path / "none.ply")
    (tmp_path / "e.csv").write_text("")
    with pytest.raises(MeshFormatError, match="e.csv: file is empty"):
        cg.load_distance(tmp_path / "e.csv")
    (tmp_path / "bad.csv").write_text("vertex,distance\n0,1.5\n1,abc\n")
    with pytest.raises(MeshFormatError, match="bad.csv: column 'distance'"):
        cg.load_distance(tmp_path / "bad.csv")
    np.save(tmp_path / "m.npy", np.zeros((2, 3)))
    with pytest.raises(MeshFormatError, match=r"m.npy: expected a 1-D numeric array .*shape \(2, 3\)"):
        cg.load_distance(tmp_path / "m.npy")
    (tmp_path / "x.npy").write_bytes(b"not numpy")
    with pytest.raises(MeshFormatError, match="x.npy: not a NumPy .npy file"):
        cg.load_distance(tmp_path / "x.npy")
    with pytest.raises(ParameterError, match="name must be a string"):
        cg.load_distance(tmp_path / "m.npy", name=3)


# ----------------------------------------------------------------------------------------------------------------------
# A missing file is a FileNotFoundError too
# ----------------------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("ext", sorted({*MESH_EXTENSIONS, *VOLUME_EXTENSIONS}))
def test_missing_mesh_file_is_a_file_not_found_error(tmp_path, ext):
    path = tmp_path / f"none{ext}"
    with pytest.raises(FileNotFoundError) as info:
        cg.load_mesh(path)
    exc = info.value
    assert isinstance(exc, MeshFileNotFoundError) and isinstance(exc, MeshFormatError)
    assert isinstance(exc, OSError) and isinstance(exc, ValueError)  # every existing `except` still catches it
    assert str(exc) == f"{path}: no such file"
    assert exc.errno == errno.ENOENT and exc.filename == str(path)
    back = pickle.loads(pickle.dumps(exc))  # Dask sends a worker's exception to the client
    assert type(back) is MeshFileNotFoundError and str(back) == str(exc) and back.filename == str(path)
    with pytest.raises(FileNotFoundError):
        cg.geodesic_distance(str(path), 0)


# ----------------------------------------------------------------------------------------------------------------------
# open3d's tensor mesh, by duck typing
# ----------------------------------------------------------------------------------------------------------------------


class _Tensor:
    """What open3d.core.Tensor offers here: ``.numpy()`` (on the CPU only) and ``.cpu()``."""

    def __init__(self, a, on_gpu=False):
        self._a, self._gpu = np.asarray(a), on_gpu

    def cpu(self):
        return _Tensor(self._a)

    def numpy(self):
        if self._gpu:
            raise RuntimeError("numpy() is only supported for CPU tensors")
        return self._a.copy()


class _TensorMap:
    """open3d.t.geometry.TensorMap: item access (every version) and attribute access (0.15 on)."""

    def __init__(self, **tensors):
        self._t = tensors
        self.__dict__.update(tensors)

    def __getitem__(self, key):
        return self._t[key]


class _AttributeOnlyMap:
    def __init__(self, **tensors):
        self.__dict__.update(tensors)


class _O3dTensorMesh:
    """A stand-in for ``open3d.t.geometry.TriangleMesh``: ``.vertex["positions"]``, ``.triangle["indices"]``."""

    def __init__(self, V, F, mapping=_TensorMap, on_gpu=False):
        self.vertex = mapping(positions=_Tensor(np.asarray(V, dtype=np.float32), on_gpu))
        self.triangle = mapping(indices=_Tensor(np.asarray(F, dtype=np.int64), on_gpu))


@pytest.mark.parametrize("mapping, on_gpu", [(_TensorMap, False), (_TensorMap, True), (_AttributeOnlyMap, False)])
def test_open3d_tensor_mesh_is_accepted(mapping, on_gpu):
    mesh = cg.mesh.as_trimesh(_O3dTensorMesh(SPHERE.V, SPHERE.F, mapping, on_gpu))
    np.testing.assert_array_equal(mesh.F, SPHERE.F)
    np.testing.assert_array_equal(mesh.V, SPHERE.V.astype(np.float32))  # open3d's default float32 positions
    d = cg.geodesic_distance(_O3dTensorMesh(SPHERE.V, SPHERE.F, mapping, on_gpu), 0, method="dijkstra")
    np.testing.assert_allclose(d, cg.geodesic_distance(SPHERE, 0, method="dijkstra"), rtol=1e-6)


def test_unknown_mesh_type_names_its_module():
    class TriangleMesh:  # another library's class of the same name
        pass

    with pytest.raises(TypeError) as info:
        cg.geodesic_distance(TriangleMesh(), 0)
    msg = str(info.value)
    assert "open3d.t.geometry.TriangleMesh" in msg
    assert not re.search(r"got TriangleMesh\b", msg)
    assert re.search(r"got test_formats\.test_unknown_mesh_type_names_its_module\.<locals>\.TriangleMesh$", msg), msg
    with pytest.raises(TypeError, match=r"got int$"):
        cg.geodesic_distance(3, 0)
