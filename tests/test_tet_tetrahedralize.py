"""tetrahedralize (issue 26) through an optional mesher; skipped where none is installed."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

from conftest import shared_mesh_path
from cvxgeodesic.errors import MeshError, ParameterError
from cvxgeodesic.mesh.generate import grid_plane, icosphere
from cvxgeodesic.mesh.tetrahedralize import MESHERS, tetrahedralize

INSTALLED = [m for m, (mod, _) in MESHERS.items() if importlib.util.find_spec(mod) is not None]


def test_without_a_mesher_the_error_says_what_to_install(monkeypatch):
    import cvxgeodesic.mesh.tetrahedralize as tz

    monkeypatch.setattr(tz, "_available", lambda name: None)
    with pytest.raises(ParameterError, match="pip install tetgen .*pip install wildmeshing"):
        tetrahedralize(icosphere(1))
    with pytest.raises(ParameterError, match="mesher 'wildmeshing' is not installed: pip install wildmeshing"):
        tetrahedralize(icosphere(1), mesher="wildmeshing")
    with pytest.raises(ParameterError, match="unknown mesher"):
        tetrahedralize(icosphere(1), mesher="gmsh")


@pytest.mark.skipif("tetgen" not in INSTALLED, reason="tetgen is not installed")
def test_tetgen_fills_a_sphere_and_keeps_its_surface():
    s = icosphere(2)
    m = tetrahedralize(s, mesher="tetgen")
    assert m.is_manifold and (m.signed_volumes > 0).all() and m.degenerate_tets().size == 0
    # the input surface is the boundary: its volume, area and every input vertex
    V, F = s.V, s.F
    vol = np.einsum("ij,ij->", V[F[:, 0]], np.cross(V[F[:, 1]], V[F[:, 2]])) / 6
    np.testing.assert_allclose(m.total_volume, vol, rtol=1e-12)
    np.testing.assert_allclose(m.boundary_area, s.face_areas.sum(), rtol=1e-12)
    assert any("tetrahedralized by tetgen" in n for n in m.notes)
    finer = tetrahedralize(s, mesher="tetgen", max_volume=vol / 2000)
    # TetGen refines to the bound, then its mesh improvement moves vertices: measured 1.1 × the bound at most
    assert finer.n_tets > 2000 and finer.volumes.max() <= 1.25 * vol / 2000
    with pytest.raises(MeshError, match="needs a closed manifold surface, this one has 16 boundary edges"):
        tetrahedralize(grid_plane(4), mesher="tetgen")


@pytest.mark.skipif("wildmeshing" not in INSTALLED, reason="wildmeshing is not installed")
@pytest.mark.slow
def test_wildmeshing_fills_a_sphere(tmp_path, monkeypatch, capfd):
    monkeypatch.chdir(tmp_path)
    s = icosphere(2)
    m = tetrahedralize(s, mesher="wildmeshing", edge_length=0.3)
    assert list(tmp_path.iterdir()) == [] and capfd.readouterr() == ("", "")  # fTetWild's file and output
    assert m.is_manifold and (m.signed_volumes > 0).all()
    np.testing.assert_allclose(m.total_volume, 4 / 3 * np.pi, rtol=0.05)


@pytest.mark.skipif(not INSTALLED, reason="no mesher installed")
def test_a_shared_closed_surface_becomes_a_volume():
    from cvxgeodesic.mesh.io import load_mesh

    s = load_mesh(shared_mesh_path("spot.obj"))
    m = tetrahedralize(s, mesher=INSTALLED[0])
    assert m.is_manifold and m.n_components == 1 and m.folded_faces.size == 0
    V, F = s.V, s.F
    vol = np.einsum("ij,ij->", V[F[:, 0]], np.cross(V[F[:, 1]], V[F[:, 2]])) / 6
    np.testing.assert_allclose(m.total_volume, abs(vol), rtol=1e-9 if INSTALLED[0] == "tetgen" else 0.05)
