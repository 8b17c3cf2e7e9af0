"""Order 2 from a source point moved toward a vertex of its face: is the field as accurate all the way?

For each mesh, a few faces drawn with a fixed seed; in each, the source point ``(w, (1 − w)/2, (1 − w)/2)`` for
``w`` from the centroid to the corner, solved with ``qclp`` at order 2 and compared with exact MMP from the same point
(mean relative error over the vertices, in %). The field should not depend on where in its face the source lies:
until 2026-12-06 it lost accuracy as the point neared a curved vertex (docs/order2.md, "Next to the sources"), and
``--corners 0`` shows that build (``SOURCE_CORNER_NEAR = 0``). A cylinder is developable: the field is exact there.

Run from the repository root, one thread::

    CVXGEODESIC_THREADS=1 PYTHONPATH=src python benchmarks/source_position.py spot fandisk --faces 3
    CVXGEODESIC_THREADS=1 PYTHONPATH=src python benchmarks/source_position.py cylinder icosphere --corners 0
"""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

import numpy as np

import cvxgeodesic as cg
import cvxgeodesic.problems.squared_distance as squared_distance

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"
GENERATED = {"cylinder": lambda: cg.cylinder(24, 12), "icosphere": lambda: cg.icosphere(3)}
WEIGHTS = (1 / 3, 0.8, 0.9, 0.95, 0.98, 1.0)


def load(name: str) -> cg.TriMesh:
    """A generated mesh by name, or a shared mesh by its stem."""
    if name in GENERATED:
        return GENERATED[name]()
    return cg.load_mesh(next(SHARED.glob(f"{name}.*")), kind="surface")


def error(mesh: cg.TriMesh, source) -> float:
    """Mean relative error (%) of order 2 against exact MMP from ``source``."""
    exact = cg.geodesic_distance(mesh, source, method="exact")
    d = cg.geodesic_distance(mesh, source, method="qclp", order=2)
    reached = exact > 0
    return 100 * float(np.mean(np.abs(d[reached] - exact[reached]) / exact[reached]))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("meshes", nargs="+", help=f"shared mesh stems, or {', '.join(GENERATED)}")
    ap.add_argument("--faces", type=int, default=3, help="faces per mesh (seed 2)")
    ap.add_argument("--corners", type=float, default=squared_distance.SOURCE_CORNER_NEAR,
                    help="SOURCE_CORNER_NEAR (0: the build without the corner samples next to the sources)")
    args = ap.parse_args()
    squared_distance.SOURCE_CORNER_NEAR = args.corners
    warnings.simplefilter("ignore")  # degenerate-face notes of the split faces
    print(f"SOURCE_CORNER_NEAR = {args.corners:g}; mean relative error (%) against exact MMP, w: the point's weight on "
          "the face's first corner (1: the vertex itself)\n")
    print("| mesh | face | " + " | ".join(f"w = {w:.2f}" for w in WEIGHTS) + " |")
    print("|---|---|" + "---|" * len(WEIGHTS))
    for name in args.meshes:
        mesh = load(name)
        faces = np.random.default_rng(2).choice(mesh.n_faces, args.faces, replace=False)
        for face in (int(f) for f in faces):
            cells = []
            for w in WEIGHTS:
                source = int(mesh.F[face, 0]) if w == 1.0 else [cg.SurfacePoint(face, [w, (1 - w) / 2, (1 - w) / 2])]
                cells.append(f"{error(mesh, source):.3f}")
            print(f"| {name} | {face} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
