"""How much of the interior-point Newton matrix changes from one iteration to the next, cone by cone.

Not a test: run it by hand (docs/dev/order2-log.md, "Set-up, kernels and the start")::

    PYTHONPATH=src python benchmarks/newton_change.py bimba.obj            # a mesh of ../shared/meshes
    PYTHONPATH=src python benchmarks/newton_change.py fandisk.obj --order 1

For every cone block of at least 10 000 clique cones (the order-2 sampled cones; at order 1 the tetrahedron
cones), each iteration's ``W_t⁻²`` (the cone's scaling in the Newton matrix ``Σ G_tᵀ W_t⁻² G_t``) is compared
with the previous iteration's after removing the best common scale (the median ratio of their norms: a
preconditioner multiplied by one number absorbs it). The fractions of cones whose relative change exceeds 10 %,
50 % and 200 % bound what reusing the previous factorization can do: a low-rank update has the rank of the
changed cones.
"""

from __future__ import annotations

import argparse
import os

import numpy as np

import cvxgeodesic as cg
import cvxgeodesic.solvers.ipm.blocks as blocks

MESHES = os.path.join(os.path.dirname(__file__), "..", "..", "shared", "meshes")


def scaling_matrices(w: np.ndarray, inv_eta2: np.ndarray) -> np.ndarray:
    """(k, d, d): ``W_t⁻² = (2 v vᵀ − J)/η²`` with ``v = J w̄`` for scaling points ``w`` (d, k)."""
    d = w.shape[0]
    v = w.copy()
    v[1:] *= -1.0
    M = 2.0 * np.einsum("ik,jk->kij", v, v)
    M[:, np.arange(d), np.arange(d)] -= np.array([1.0] + [-1.0] * (d - 1))
    return M * inv_eta2[:, None, None]


def record_changes(min_cones: int = 10_000) -> list[tuple[int, float, float, float, float]]:
    """Patch :class:`CliqueSOCBlock` to record, per assembly, ``(cones, common scale, >10 %, >50 %, >200 %)``."""
    previous: dict[int, np.ndarray] = {}
    rows: list[tuple[int, float, float, float, float]] = []
    assemble = blocks.CliqueSOCBlock.assemble_add

    def recording(self, sc, data):
        if self.count >= min_cones:
            cur = scaling_matrices(sc.w, sc.inv_eta2)
            old = previous.get(id(self))
            if old is not None:
                n_old = np.linalg.norm(old, axis=(1, 2))
                scale = float(np.median(np.linalg.norm(cur, axis=(1, 2)) / n_old))
                rel = np.linalg.norm(cur - scale * old, axis=(1, 2)) / (scale * n_old)
                rows.append((self.count, scale, *(float((rel > t).mean()) for t in (0.1, 0.5, 2.0))))
            previous[id(self)] = cur
        return assemble(self, sc, data)

    blocks.CliqueSOCBlock.assemble_add = recording
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mesh", help="a file name in ../shared/meshes or a path")
    parser.add_argument("--order", type=int, default=2)
    parser.add_argument("--method", default="qclp")
    args = parser.parse_args()
    path = args.mesh if os.path.exists(args.mesh) else os.path.join(MESHES, args.mesh)
    rows = record_changes()
    res = cg.GeodesicSolver(cg.load_mesh(path), args.method, order=args.order, solver="ipm").solve(0)
    print(f"{args.mesh} {args.method} order {args.order}: {res.info.iterations} iterations, {res.info.status}")
    print("assembly  cones  common scale  changed >10 %  >50 %  >200 %   (each against the one before)")
    for i, (k, scale, a, b, c) in enumerate(rows, start=2):
        print(f"{i:8d}  {k:6d}  {scale:12.3g}  {a:13.3f}  {b:5.3f}  {c:6.3f}")


if __name__ == "__main__":
    main()
