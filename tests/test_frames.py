"""The closed-form plane fits of mesh/frames.py against numpy's eigh, on ordinary and degenerate neighbourhoods."""

import numpy as np
import pytest

from cvxgeodesic.mesh.frames import plane_fits, scatter_matrices, tangent_frames


def _neighbourhoods(rng, n=500, k=12):
    """Noisy patches of curved surfaces at random positions and orientations, far from the origin as scans are."""
    uv = rng.normal(size=(n, k, 2))
    height = 0.3 * uv[..., 0] ** 2 - 0.2 * uv[..., 1] ** 2 + 1e-3 * rng.normal(size=(n, k))
    local = np.concatenate([uv, height[..., None]], axis=2)
    turn = np.linalg.qr(rng.normal(size=(n, 3, 3)))[0]
    return np.einsum("nij,nkj->nki", turn, local) + 1e3 * rng.normal(size=(n, 1, 3))


def _centred(X):
    return X - X.mean(axis=1, keepdims=True)


def test_scatter_matrices_are_the_products_with_and_without_weights():
    rng = np.random.default_rng(0)
    Q = _centred(_neighbourhoods(rng))
    assert np.allclose(scatter_matrices(Q), Q.transpose(0, 2, 1) @ Q, rtol=1e-13, atol=1e-9)
    w = rng.random(Q.shape[:2])
    assert np.allclose(scatter_matrices(Q, w), np.einsum("nk,nki,nkj->nij", w, Q, Q), rtol=1e-13, atol=1e-9)


def test_plane_fits_agree_with_eigh_on_surface_patches():
    C = scatter_matrices(_centred(_neighbourhoods(np.random.default_rng(1))))
    values, normals = plane_fits(C)
    w, frames = np.linalg.eigh(C)
    assert np.abs(values - w).max() <= 1e-12 * w[:, 2].max()
    assert np.allclose(np.abs(np.einsum("ni,ni->n", normals, frames[:, :, 0])), 1.0, atol=1e-12)
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-14)


@pytest.mark.parametrize("kind", ["plane", "line", "isotropic", "point", "two-equal-large"])
def test_plane_fits_on_degenerate_neighbourhoods(kind):
    """Exact planes have a zero least eigenvalue; a line, an isotropic cloud and a single point have no separated
    least eigenvalue (eigh's answer is taken); a disc has two equal large ones (its normal is still defined)."""
    rng = np.random.default_rng(2)
    if kind == "plane":
        Q = np.c_[rng.normal(size=(20, 2)), np.zeros(20)]
    elif kind == "line":
        Q = np.outer(rng.normal(size=20), [1.0, 2.0, 2.0])
    elif kind == "isotropic":
        Q = np.r_[np.eye(3), -np.eye(3)]
    elif kind == "point":
        Q = np.zeros((5, 3))
    else:
        t = np.linspace(0, 2 * np.pi, 13)[:-1]
        Q = np.c_[np.cos(t), np.sin(t), np.zeros_like(t)]
    C = scatter_matrices(_centred(Q[None]))
    values, normals = plane_fits(C)
    w, frames = np.linalg.eigh(C)
    assert np.all(np.isfinite(values)) and np.all(np.isfinite(normals))
    assert np.abs(values - w).max() <= 1e-12 * max(w.max(), 1.0)
    assert np.isclose(np.linalg.norm(normals), 1.0)
    residual = C[0] @ normals[0] - values[0, 0] * normals[0]  # an eigenvector of the least eigenvalue
    assert np.linalg.norm(residual) <= 1e-12 * max(w.max(), 1.0)
    if kind in ("plane", "two-equal-large"):
        assert np.allclose(np.abs(normals[0]), [0.0, 0.0, 1.0], atol=1e-12)


def test_tangent_frames_are_orthonormal_with_the_normal_first():
    rng = np.random.default_rng(3)
    normals = rng.normal(size=(200, 3))
    normals[:3] = np.eye(3)  # along the axes: the axis least along the normal is another one
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    F = tangent_frames(normals)
    assert np.allclose(F[:, :, 0], normals)
    assert np.allclose(F.transpose(0, 2, 1) @ F, np.eye(3), atol=1e-14)
