"""Tests for cvxgeodesic.mesh.io: load_mesh, save_distance, load_distance_ply."""

from __future__ import annotations

import csv
import dataclasses
import struct
import warnings
from pathlib import Path

import numpy as np
import pytest

import cvxgeodesic._atomic
from cvxgeodesic.errors import MeshError, MeshFormatError, MeshRepairWarning, ParameterError
from cvxgeodesic.mesh import TriMesh, load_mesh, save_distance
from cvxgeodesic.mesh.formats.registry import FORMATS
from cvxgeodesic.mesh.io import load_distance_ply

# A unit square split into two triangles plus an apex: 5 vertices, 4 triangles.
V5 = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 1.0]], dtype=float)
F4 = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])


def write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def obj_text(V, F, extra="") -> str:
    V, F = np.asarray(V, dtype=float).tolist(), np.asarray(F, dtype=int).reshape(-1, 3).tolist()
    return "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in V) + extra + "".join(
        f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in F
    )


def assert_same_mesh(mesh: TriMesh, V, F):
    """Same triangles up to vertex order (compares sets of corner positions)."""
    assert mesh.n_faces == len(F)
    got = sorted(tuple(map(tuple, mesh.V[f])) for f in mesh.F)
    exp = sorted(tuple(map(tuple, np.asarray(V, float)[f])) for f in F)
    assert got == exp


def ply_binary(V, F, endian="<", extra_vertex_props=False, face_list_type="int") -> bytes:
    fmt = "binary_little_endian" if endian == "<" else "binary_big_endian"
    vprops = "property float x\nproperty float y\nproperty float z\n"
    if extra_vertex_props:
        vprops += "property uchar red\nproperty double quality\n"
    head = (
        f"ply\nformat {fmt} 1.0\ncomment test\nelement vertex {len(V)}\n{vprops}"
        f"element face {len(F)}\nproperty list uchar {face_list_type} vertex_indices\nend_header\n"
    ).encode()
    body = b""
    for v in V:
        body += struct.pack(endian + "3f", *v)
        if extra_vertex_props:
            body += struct.pack(endian + "Bd", 7, 0.5)
    code = {"int": "i", "uint": "I", "ushort": "H"}[face_list_type]
    for f in F:
        body += struct.pack(endian + "B", len(f)) + struct.pack(endian + f"{len(f)}{code}", *f)
    return head + body


def stl_binary(tris) -> bytes:
    out = b"binary stl header".ljust(80, b" ") + struct.pack("<I", len(tris))
    for t in tris:
        out += struct.pack("<3f", 0, 0, 1) + struct.pack("<9f", *np.ravel(t)) + b"\0\0"
    return out


def stl_ascii(tris) -> str:
    s = "solid test\n"
    for t in tris:
        s += "  facet normal 0 0 1\n    outer loop\n"
        s += "".join(f"      vertex {x!r} {y!r} {z!r}\n" for x, y, z in np.asarray(t).tolist())
        s += "    endloop\n  endfacet\n"
    return s + "endsolid test\n"


# ----------------------------------------------------------------------------------------------------------------------
# load_mesh: formats
# ----------------------------------------------------------------------------------------------------------------------


def test_obj_simple(tmp_path):
    m = load_mesh(write(tmp_path / "pyr.obj", obj_text(V5, F4)))
    assert isinstance(m, TriMesh)
    assert m.name == "pyr.obj"
    np.testing.assert_array_equal(m.V, V5)
    np.testing.assert_array_equal(m.F, F4)
    np.testing.assert_array_equal(m.vertex_map, np.arange(5))


def test_obj_uv_seam_is_welded(tmp_path):
    # Two triangles sharing edge (1,2); the exporter duplicated those vertices for a UV seam.
    text = """# seam
mtllib x.mtl
o thing
v 0 0 0
v 1 0 0
v 0 1 0
v 1 0 0
v 0 1 0
v 1 1 0
vt 0 0
vt 1 0
vt 0 1
vt 0.5 0
vt 0 0.5
vt 1 1
vn 0 0 1
g group1
usemtl mat
s 1
f 1/1/1 2/2/1 3/3/1
f 4/4/1 6/6/1 5/5/1
"""
    m = load_mesh(write(tmp_path / "seam.obj", text))
    assert (m.n_vertices, m.n_faces) == (4, 2)
    np.testing.assert_array_equal(m.vertex_map, [0, 1, 2, 5])
    np.testing.assert_array_equal(m.F, [[0, 1, 2], [1, 3, 2]])
    assert len(m.edges) == 5  # the seam edge is shared


def test_obj_slash_forms_and_negative_indices(tmp_path):
    text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2//1 3//1\nv 1 1 0\nf -3/1 -1/2 -2/3\n"
    m = load_mesh(write(tmp_path / "neg.obj", text))
    np.testing.assert_array_equal(m.F, [[0, 1, 2], [1, 3, 2]])


def test_obj_quad_and_polygon_fan_triangulated(tmp_path):
    text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\nf 1 2 3 4\nf 2 5 6 3\n"
    m = load_mesh(write(tmp_path / "quad.obj", text))
    np.testing.assert_array_equal(m.F, [[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]])
    pent = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0.5 2 0\nv 0 1 0\nf 1 2 3 4 5\n"
    m = load_mesh(write(tmp_path / "pent.obj", pent))
    np.testing.assert_array_equal(m.F, [[0, 1, 2], [0, 2, 3], [0, 3, 4]])


def test_obj_crlf_tabs_and_extra_vertex_values(tmp_path):
    text = "v\t0 0 0 1.0\r\nv 1 0 0 0.5 0.5 0.5\r\n  v 0 1 0\r\nf\t1 2 3\r\n"
    m = load_mesh(write(tmp_path / "crlf.OBJ", text))
    np.testing.assert_array_equal(m.V, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    assert m.n_faces == 1


def test_unreferenced_vertices_dropped_with_vertex_map(tmp_path):
    V = np.vstack([[9.0, 9, 9], V5[:2], [8.0, 8, 8], V5[2:]])  # file vertices 0 and 3 unused
    F = np.array([[1, 2, 6], [2, 4, 6], [4, 5, 6], [5, 1, 6]])
    m = load_mesh(write(tmp_path / "unref.obj", obj_text(V, F)))
    assert m.n_vertices == 5
    np.testing.assert_array_equal(m.vertex_map, [1, 2, 4, 5, 6])
    np.testing.assert_array_equal(m.V, V[m.vertex_map])
    np.testing.assert_array_equal(m.F, F4)


def test_degenerate_face_after_welding_dropped_with_warning(tmp_path):
    V = np.vstack([V5, V5[0]])  # vertex 5 duplicates vertex 0
    F = np.vstack([F4, [[0, 5, 1]]])  # becomes (0, 0, 1)
    with pytest.warns(UserWarning, match=r"dropped 1 degenerate face"):
        m = load_mesh(write(tmp_path / "deg.obj", obj_text(V, F)))
    assert (m.n_vertices, m.n_faces) == (5, 4)
    np.testing.assert_array_equal(m.F, F4)


def test_duplicate_faces_dropped_with_warning(tmp_path):
    F = np.vstack([F4, F4[:1], F4[1:2, ::-1]])  # an exact copy and a reversed copy
    with pytest.warns(UserWarning, match=r"dropped 2 duplicate face"):
        m = load_mesh(write(tmp_path / "dup.obj", obj_text(V5, F)))
    np.testing.assert_array_equal(m.F, F4)


def test_clean_file_gives_no_warning(tmp_path):
    path = write(tmp_path / "clean.obj", obj_text(V5, F4))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        load_mesh(path)


def test_off(tmp_path):
    text = "OFF\n# comment\n5 5 0\n" + "".join(f"{x} {y} {z}\n" for x, y, z in V5)
    text += "3 0 1 4\n3 1 2 4\n3 2 3 4\n3 3 0 4\n4 0 3 2 1  255 0 0\n"  # quad base with a color
    m = load_mesh(write(tmp_path / "pyr.off", text))
    assert (m.n_vertices, m.n_faces) == (5, 6)
    np.testing.assert_array_equal(m.F[:4], F4)
    np.testing.assert_array_equal(m.F[4:], [[0, 3, 2], [0, 2, 1]])


@pytest.mark.parametrize("cut, record", [(2, 4), (17, 4), (23, 3)])
def test_ply_binary_mixed_polygon_sizes_truncated(tmp_path, cut, record):
    # the record-by-record reader names the record where the data ends: inside the last quad's indices (cut 2),
    # right after its count byte (cut 17), inside the triangle before it (cut 23; 13 bytes per triangle)
    faces = [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4], [0, 3, 2, 1]]
    path = tmp_path / "mixed.ply"
    path.write_bytes(ply_binary(V5, faces)[:-cut])
    with pytest.raises(MeshFormatError, match=rf"mixed\.ply: binary PLY data ends in record {record} of element "
                                              "'face'"):
        load_mesh(path)


def test_off_counts_on_header_line_and_coff(tmp_path):
    text = "COFF 3 1 0\n0 0 0 255 0 0 255\n1 0 0 255 0 0 255\n0 1 0 255 0 0 255\n3 0 1 2\n"
    m = load_mesh(write(tmp_path / "c.off", text))
    assert (m.n_vertices, m.n_faces) == (3, 1)


def test_ply_ascii(tmp_path):
    text = (
        "ply\nformat ascii 1.0\ncomment hi\nelement vertex 5\nproperty float x\nproperty float y\n"
        "property float z\nproperty uchar red\nelement face 4\nproperty list uchar int vertex_indices\n"
        "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n"
    )
    text += "".join(f"{x} {y} {z} 12\n" for x, y, z in V5)
    text += "".join(f"3 {a} {b} {c}\n" for a, b, c in F4) + "0 1\n"
    m = load_mesh(write(tmp_path / "a.ply", text))
    np.testing.assert_array_equal(m.V, V5)
    np.testing.assert_array_equal(m.F, F4)


@pytest.mark.parametrize("endian", ["<", ">"])
@pytest.mark.parametrize("face_type", ["int", "uint", "ushort"])
def test_ply_binary(tmp_path, endian, face_type):
    path = tmp_path / "b.PLY"
    path.write_bytes(ply_binary(V5, F4, endian, extra_vertex_props=True, face_list_type=face_type))
    m = load_mesh(path)
    np.testing.assert_array_equal(m.V, V5)
    np.testing.assert_array_equal(m.F, F4)


def test_ply_binary_mixed_polygon_sizes(tmp_path):
    faces = [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4], [0, 3, 2, 1]]
    path = tmp_path / "mixed.ply"
    path.write_bytes(ply_binary(V5, faces))
    m = load_mesh(path)
    assert m.n_faces == 6
    np.testing.assert_array_equal(m.F[4:], [[0, 3, 2], [0, 2, 1]])


def test_stl_binary_soup_is_welded(tmp_path):
    tris = V5[F4]  # 12 corners, 5 distinct positions
    path = tmp_path / "soup.stl"
    path.write_bytes(stl_binary(tris))
    m = load_mesh(path)
    assert (m.n_vertices, m.n_faces) == (5, 4)
    assert_same_mesh(m, V5, F4)
    # vertex_map gives the first corner with that position (corner = 3 * triangle + k)
    np.testing.assert_array_equal(m.vertex_map, [0, 1, 2, 4, 7])
    np.testing.assert_array_equal(m.V, tris.reshape(-1, 3)[m.vertex_map])


def test_stl_binary_whose_header_starts_with_solid(tmp_path):
    data = stl_binary(V5[F4])
    path = tmp_path / "tricky.stl"
    path.write_bytes(b"solid but actually binary".ljust(80) + data[80:])
    assert load_mesh(path).n_faces == 4


def test_stl_ascii_soup_is_welded(tmp_path):
    m = load_mesh(write(tmp_path / "soup.STL", stl_ascii(V5[F4])))
    assert (m.n_vertices, m.n_faces) == (5, 4)
    assert_same_mesh(m, V5, F4)


def test_same_mesh_from_every_format(tmp_path):
    (tmp_path / "m.ply").write_bytes(ply_binary(V5, F4))
    (tmp_path / "m.stl").write_bytes(stl_binary(V5[F4]))
    write(tmp_path / "m.obj", obj_text(V5, F4))
    (tmp_path / "m.off").write_text(
        "OFF\n5 4 0\n" + "".join(f"{x} {y} {z}\n" for x, y, z in V5) + "".join(f"3 {a} {b} {c}\n" for a, b, c in F4)
    )
    for ext in ("obj", "off", "ply", "stl"):
        assert_same_mesh(load_mesh(tmp_path / f"m.{ext}"), V5, F4)


# ----------------------------------------------------------------------------------------------------------------------
# load_mesh: errors
# ----------------------------------------------------------------------------------------------------------------------


def test_missing_file(tmp_path):
    with pytest.raises(MeshFormatError, match="no such file") as exc:
        load_mesh(tmp_path / "nope.obj")
    assert "nope.obj" in str(exc.value)


def test_directory(tmp_path):
    d = tmp_path / "dir.obj"
    d.mkdir()
    with pytest.raises(MeshFormatError, match="directory"):
        load_mesh(d)


def test_unsupported_extension_lists_supported(tmp_path):
    p = write(tmp_path / "mesh.blend", "x")
    with pytest.raises(MeshFormatError, match=r"\.obj, \.off, \.ply, \.stl, \.glb, \.gltf, \.3mf, \.vtk, \.vtu") as exc:
        load_mesh(p)
    assert "mesh.blend" in str(exc.value)
    with pytest.raises(MeshFormatError, match="unsupported"):
        load_mesh(tmp_path / "noext")


@pytest.mark.parametrize("ext", ["obj", "off", "ply", "stl"])
def test_empty_file(tmp_path, ext):
    p = write(tmp_path / f"e.{ext}", "")
    with pytest.raises(MeshFormatError, match="empty") as exc:
        load_mesh(p)
    assert f"e.{ext}" in str(exc.value)


def test_errors_are_value_errors(tmp_path):
    with pytest.raises(ValueError):
        load_mesh(tmp_path / "nope.obj")
    assert issubclass(MeshFormatError, MeshError)


@pytest.mark.parametrize(
    ("name", "text", "pattern"),
    [
        ("bad_v.obj", "v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n", r"line 2.*'zero'"),
        ("short_v.obj", "v 0 0 0\n# c\nv 1 0\nv 0 1 0\nf 1 2 3\n", r"line 3.*needs 3 numbers"),
        ("bad_f.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 x\n", r"line 5.*'x'"),
        ("float_f.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3.5\n", r"line 4"),
        ("zero_f.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", r"line 4.*start at 1"),
        ("two_f.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2\n", r"face 1 \(line 5\).*at least 3"),
        ("nothing.obj", "# only a comment\nvt 0 0\n", r"no 'v' or 'f'"),
        ("bad_v.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 one 0\n3 0 1 2\n", r"line 5.*'one'"),
        ("bad_head.off", "PFF\n3 1 0\n", r"line 1.*OFF"),
        ("bad_counts.off", "OFF\n3 x 0\n", r"line 2.*counts"),
        ("short.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n", r"ends after 2 of 3 vertices"),
        ("bad_f.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", r"line 6.*announces 4"),
        ("bad.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
         "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
         "0 0 0\n1 0 0\n0 1 zz\n3 0 1 2\n", r"line 12.*'zz'"),
        ("badface.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
         "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
         "0 0 0\n1 0 0\n0 1 0\n3 0 1\n", r"line 13.*malformed 'face' record"),
        ("nohead.ply", "ply\nformat ascii 1.0\nelement vertex 3\n", r"end_header"),
        ("notply.ply", "hello\n", r"not a PLY"),
        ("bad.stl", "solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0\n"
         "   vertex 0 1 0\n  endloop\n endfacet\nendsolid\n", r"line 5.*needs 3 numbers"),
        ("two.stl", "solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n"
         "  endloop\n endfacet\nendsolid\n", r"line 6.*facet has 2 vertices"),
        ("junk.stl", "solid x\n facet normal 0 0 1\n banana\n", r"line 3.*banana"),
    ],
)
def test_malformed_files_name_the_line(tmp_path, name, text, pattern):
    p = write(tmp_path / name, text)
    with pytest.raises(MeshFormatError, match=pattern) as exc:
        load_mesh(p)
    assert name in str(exc.value)


@pytest.mark.parametrize(
    ("name", "text", "pattern"),
    [
        ("oor.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 7\n", r"face 1 \(line 5\).*index 7.*3 vertices"),
        ("neg.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", r"face 0 \(line 4\).*index -4"),
        ("oor.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 3\n", r"face 1 \(line 7\).*index 3"),
    ],
)
def test_face_index_out_of_range(tmp_path, name, text, pattern):
    with pytest.raises(MeshFormatError, match=pattern):
        load_mesh(write(tmp_path / name, text))


def test_face_index_out_of_range_binary_ply(tmp_path):
    p = tmp_path / "oor.ply"
    p.write_bytes(ply_binary(V5, [[0, 1, 2], [0, 1, 9]]))
    with pytest.raises(MeshFormatError, match=r"face 1 .*index 9.*5 vertices"):
        load_mesh(p)


@pytest.mark.parametrize("value", ["nan", "inf", "-inf", "1e999"])
def test_non_finite_coordinate(tmp_path, value):
    text = f"v 0 0 0\nv 1 0 0\nv 0 {value} 0\nf 1 2 3\n"
    with pytest.raises(MeshFormatError, match=r"vertex 2 \(line 3\).*non-finite"):
        load_mesh(write(tmp_path / "nf.obj", text))


def test_non_finite_coordinate_binary_stl(tmp_path):
    tris = V5[F4].copy()
    tris[1, 2, 0] = np.nan
    p = tmp_path / "nan.stl"
    p.write_bytes(stl_binary(tris))
    with pytest.raises(MeshFormatError, match="non-finite"):
        load_mesh(p)


@pytest.mark.parametrize(
    ("name", "text"),
    [
        ("nof.obj", "v 0 0 0\nv 1 0 0\n"),
        ("nof.off", "OFF\n2 0 0\n0 0 0\n1 0 0\n"),
        ("nof.stl", "solid x\nendsolid x\n"),
    ],
)
def test_no_faces(tmp_path, name, text):
    with pytest.raises(MeshFormatError, match="no faces"):
        load_mesh(write(tmp_path / name, text))


def test_only_degenerate_faces(tmp_path):
    text = "v 0 0 0\nv 0 0 0\nv 1 0 0\nf 1 2 3\n"
    with pytest.warns(UserWarning), pytest.raises(MeshFormatError, match="no faces left"):
        load_mesh(write(tmp_path / "allbad.obj", text))


def test_truncated_binary_stl_and_ply(tmp_path):
    p = tmp_path / "t.stl"
    p.write_bytes(stl_binary(V5[F4])[:-30])
    with pytest.raises(MeshFormatError, match="truncated"):
        load_mesh(p)
    p = tmp_path / "t.ply"
    p.write_bytes(ply_binary(V5, F4)[:-5])
    with pytest.raises(MeshFormatError, match=r"t\.ply"):
        load_mesh(p)


def test_binary_garbage_in_text_format(tmp_path):
    p = tmp_path / "garbage.obj"
    p.write_bytes(b"v 0 0 0\nv \xff\xfe\x00 1 0\nf 1 2 3\n")
    with pytest.raises(MeshFormatError, match="line 2"):
        load_mesh(p)


@pytest.mark.parametrize("ext", ["obj", "off", "ply", "stl", "ply-ascii", "stl-ascii"])
def test_corrupted_files_raise_only_mesh_format_error(tmp_path, ext):
    """Truncations and byte flips either load or raise MeshFormatError, never anything else."""
    if ext == "obj":
        data = obj_text(V5, F4).encode()
    elif ext == "off":
        data = ("OFF\n5 4 0\n" + "".join(f"{x} {y} {z}\n" for x, y, z in V5)
                + "".join(f"3 {a} {b} {c}\n" for a, b, c in F4)).encode()
    elif ext == "ply":
        data = ply_binary(V5, [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4], [0, 3, 2, 1]], extra_vertex_props=True)
    elif ext == "ply-ascii":
        data = (
            "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
            + "".join(f"{x} {y} {z}\n" for x, y, z in V5) + "".join(f"3 {a} {b} {c}\n" for a, b, c in F4)
        ).encode()
    elif ext == "stl":
        data = stl_binary(V5[F4])
    else:
        data = stl_ascii(V5[F4]).encode()
    suffix = "." + ext.split("-")[0]
    rng = np.random.default_rng(0)
    variants = [data[:k] for k in range(0, len(data), max(1, len(data) // 60))]
    for _ in range(60):
        b = bytearray(data)
        for i in rng.integers(0, len(b), size=3):
            b[i] = int(rng.integers(0, 256))
        variants.append(bytes(b))
    p = tmp_path / f"c{suffix}"
    for v in variants:
        p.write_bytes(v)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                load_mesh(p)
        except MeshFormatError as exc:
            assert p.name in str(exc)


# ----------------------------------------------------------------------------------------------------------------------
# save_distance / load_distance_ply
# ----------------------------------------------------------------------------------------------------------------------


@pytest.fixture
def mesh_and_dist(tmp_path):
    V = np.vstack([[7.0, 7, 7], V5])  # file vertex 0 is unreferenced -> vertex_map = 1..5
    m = load_mesh(write(tmp_path / "src.obj", obj_text(V, F4 + 1)))
    d = np.array([0.0, 1.0 / 3.0, np.inf, 2.5, 1e-300])
    return m, d


def test_save_ply_round_trip(tmp_path, mesh_and_dist):
    m, d = mesh_and_dist
    out = save_distance(tmp_path / "d.ply", m, d, name="geo")
    assert out == tmp_path / "d.ply"
    header = out.read_bytes().split(b"end_header\n")[0].decode()
    assert "format binary_little_endian 1.0" in header
    assert "property double x" in header and "property double geo" in header
    assert "property list uchar int vertex_indices" in header
    m2, fields = load_distance_ply(out)
    assert list(fields) == ["geo"]
    np.testing.assert_array_equal(fields["geo"], d)  # float64 exact, inf kept
    np.testing.assert_array_equal(m2.F, m.F)
    np.testing.assert_array_equal(m2.V, m.V)  # float64 coordinates: exact
    # the file is also a valid mesh for load_mesh
    assert load_mesh(out).n_faces == m.n_faces


def test_save_npy_round_trip(tmp_path, mesh_and_dist):
    m, d = mesh_and_dist
    save_distance(tmp_path / "d.npy", m, d)
    got = np.load(tmp_path / "d.npy")
    assert got.dtype == np.float64
    np.testing.assert_array_equal(got, d)


def test_save_csv_round_trip(tmp_path, mesh_and_dist):
    m, d = mesh_and_dist
    save_distance(tmp_path / "d.CSV", m, list(d), name="dist")
    rows = list(csv.reader((tmp_path / "d.CSV").open()))
    assert rows[0] == ["vertex", "file_vertex", "x", "y", "z", "dist"]
    assert len(rows) == m.n_vertices + 1
    assert rows[3][5] == "inf"
    body = np.array(rows[1:], dtype=float)
    np.testing.assert_array_equal(body[:, 0], np.arange(m.n_vertices))
    np.testing.assert_array_equal(body[:, 1], m.vertex_map)
    np.testing.assert_array_equal(body[:, 2:5], m.V)
    np.testing.assert_array_equal(body[:, 5], d)


def test_save_overwrites_existing(tmp_path, mesh_and_dist):
    m, d = mesh_and_dist
    p = tmp_path / "d.npy"
    save_distance(p, m, d)
    save_distance(p, m, 2 * d)
    np.testing.assert_array_equal(np.load(p), 2 * d)
    assert sorted(x.name for x in tmp_path.iterdir()) == ["d.npy", "src.obj"]


def test_save_accepts_vf_tuple(tmp_path):
    save_distance(tmp_path / "t.npy", (V5, F4), np.arange(5.0))
    np.testing.assert_array_equal(np.load(tmp_path / "t.npy"), np.arange(5.0))


@pytest.mark.parametrize("ext", ["ply", "npy", "csv"])
def test_save_is_atomic(tmp_path, monkeypatch, mesh_and_dist, ext):
    m, d = mesh_and_dist
    target = tmp_path / f"d.{ext}"
    original = FORMATS[f".{ext}"]

    def failing(fh, *args):
        original.write_field(fh, *args)  # write everything, then fail before the file is moved into place
        fh.write(b"partial")
        raise RuntimeError("disk on fire")

    monkeypatch.setitem(FORMATS, f".{ext}", dataclasses.replace(original, write_field=failing))
    before = set(tmp_path.iterdir())
    with pytest.raises(RuntimeError, match="disk on fire"):
        save_distance(target, m, d)
    assert set(tmp_path.iterdir()) == before  # neither target nor temporary file

    # an existing target survives a failed overwrite unchanged
    monkeypatch.setitem(FORMATS, f".{ext}", original)
    save_distance(target, m, d)
    content = target.read_bytes()
    monkeypatch.setitem(FORMATS, f".{ext}", dataclasses.replace(original, write_field=failing))
    with pytest.raises(RuntimeError):
        save_distance(target, m, 2 * d)
    assert target.read_bytes() == content
    assert set(tmp_path.iterdir()) == before | {target}


def test_save_atomic_when_replace_fails(tmp_path, monkeypatch, mesh_and_dist):
    m, d = mesh_and_dist

    def boom(src, dst):
        raise OSError("replace failed")

    monkeypatch.setattr(cvxgeodesic._atomic.os, "replace", boom)
    before = set(tmp_path.iterdir())
    with pytest.raises(OSError, match="replace failed"):
        save_distance(tmp_path / "d.ply", m, d)
    assert set(tmp_path.iterdir()) == before


def test_save_validation(tmp_path, mesh_and_dist):
    m, d = mesh_and_dist
    with pytest.raises(ParameterError, match=r"\(5,\).*\(4,\)"):
        save_distance(tmp_path / "d.npy", m, d[:4])
    with pytest.raises(ParameterError, match=r"\(5,\).*\(5, 1\)"):
        save_distance(tmp_path / "d.npy", m, d[:, None])
    with pytest.raises(ParameterError, match=r"\.txt.*\.ply, \.npy, \.csv"):
        save_distance(tmp_path / "d.txt", m, d)
    with pytest.raises(ParameterError, match="does not exist"):
        save_distance(tmp_path / "missing" / "d.npy", m, d)
    for bad in ["", "two words", "x", "a,b"]:
        with pytest.raises(ParameterError, match="invalid field name"):
            save_distance(tmp_path / "d.ply", m, d, name=bad)
    with pytest.raises(ValueError):  # ParameterError is a ValueError
        save_distance(tmp_path / "d.txt", m, d)
    assert sorted(x.name for x in tmp_path.iterdir()) == ["src.obj"]


def test_load_distance_ply_errors(tmp_path):
    with pytest.raises(MeshFormatError, match="no such file"):
        load_distance_ply(tmp_path / "none.ply")
    p = write(tmp_path / "bad.ply", "ply\nformat ascii 1.0\nend_header\n")
    with pytest.raises(MeshFormatError, match="no 'vertex' element"):
        load_distance_ply(p)


# ----------------------------------------------------------------------------------------------------------------------
# Shared real meshes (only in the development checkout)
# ----------------------------------------------------------------------------------------------------------------------

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"

def _manifest_rows():
    manifest = SHARED / "MANIFEST.tsv"
    if not manifest.is_file():
        return [pytest.param(None, id="shared-meshes-absent")]
    with manifest.open(newline="") as fh:
        rows = [r for r in csv.DictReader(fh, delimiter="\t") if not r["file"].startswith("thingi10k_small/")]
    return [pytest.param(r, id=r["file"]) for r in rows]


@pytest.mark.shared
@pytest.mark.parametrize("row", _manifest_rows())
def test_shared_mesh_counts_match_manifest(row):
    if row is None or not SHARED.is_dir():
        pytest.skip(f"shared meshes not available at {SHARED}")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # none of these files has degenerate or duplicate faces
        # beetle.off has two pairs of distinct vertices at exactly the same position (file vertices 14/386 and
        # 40/387); welding merges them (19885 mesh vertices) and says so; the manifest counts the file's 19887
        warnings.filterwarnings("ignore", message=r".*vertices in the file", category=MeshRepairWarning)
        m = load_mesh(SHARED / row["file"])
    # an STL's file vertices are its triangle corners: the manifest counts the welded ones
    n = m.n_vertices if row["file"].lower().endswith(".stl") else m.n_file_vertices
    assert (n, m.n_faces) == (int(row["vertices"]), int(row["faces"]))
    assert m.name == Path(row["file"]).name
    assert np.all(np.diff(m.vertex_map) > 0)
