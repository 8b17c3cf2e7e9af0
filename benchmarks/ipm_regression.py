"""Iteration counts and fields of the structured IPM on a fixed set of problems (a refactoring guard).

Every formulation in :data:`cvxgeodesic.problems.formulations.FORMULATIONS` on icosphere(3), spot and bimba, source
vertex 0, ``solver="ipm"``, ``m = 1``. Not a test (bimba takes a while); run it by hand::

    python benchmarks/ipm_regression.py --out benchmarks/ipm_regression.json --fields /tmp/fields_before.npz
    python benchmarks/ipm_regression.py --compare benchmarks/ipm_regression.json --fields /tmp/fields_before.npz

``--compare`` exits with status 1 when a status or an iteration count differs from the recorded one, or a
field differs from the recorded fields by more than ``--field-tol`` × the bounding-box diagonal.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from cvxgeodesic import GeodesicSolver
from cvxgeodesic.mesh import icosphere, load_mesh
from cvxgeodesic.problems.formulations import FORMULATIONS

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"
MESHES = {"icosphere3": lambda: icosphere(3), "spot": lambda: load_mesh(SHARED / "spot.obj"),
          "bimba": lambda: load_mesh(SHARED / "bimba.obj")}


def run(names: list[str]) -> tuple[dict, dict]:
    """``{mesh/method: {"status", "iterations"}}`` and ``{mesh/method: field}`` (plus the bbox diagonals)."""
    table, fields = {}, {}
    for name in names:
        mesh = MESHES[name]()
        diag = float(np.linalg.norm(mesh.V.max(axis=0) - mesh.V.min(axis=0)))
        fields[f"{name}/diag"] = np.array(diag)
        for method in FORMULATIONS:
            res = GeodesicSolver(mesh, method, m=1.0, solver="ipm").solve([0])
            key = f"{name}/{method}"
            table[key] = {"status": res.info.status, "iterations": int(res.info.iterations)}
            fields[key] = np.asarray(res.distance, dtype=np.float64)
            print(f"{key:28s} {res.info.status:15s} {res.info.iterations:3d}", flush=True)
    return table, fields


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", nargs="+", default=list(MESHES), choices=list(MESHES))
    ap.add_argument("--out", type=Path, help="write the statuses and iteration counts (JSON)")
    ap.add_argument("--fields", type=Path, help="with --out: write the fields (npz); with --compare: read them")
    ap.add_argument("--compare", type=Path, help="recorded JSON to compare against")
    ap.add_argument("--field-tol", type=float, default=1e-10)
    args = ap.parse_args()
    table, fields = run(args.meshes)
    if args.out:
        args.out.write_text(json.dumps(table, indent=1) + "\n")
        if args.fields:
            np.savez(args.fields, **{k.replace("/", "__"): v for k, v in fields.items()})
        return 0
    if not args.compare:
        return 0
    ref = json.loads(args.compare.read_text())
    old = np.load(args.fields) if args.fields else None
    bad = 0
    for key, row in table.items():
        msg = ""
        if ref.get(key) != row:
            msg = f"recorded {ref.get(key)}, now {row}"
        if old is not None:
            diag = float(old[key.split("/")[0] + "__diag"])
            a, b = old[key.replace("/", "__")], fields[key]
            finite = np.isfinite(a) & np.isfinite(b)
            err = float(np.abs(a[finite] - b[finite]).max()) / diag
            same_inf = bool(np.array_equal(np.isfinite(a), np.isfinite(b)))
            msg += f" max|Δd|/diag {err:.2e}" + ("" if same_inf else " (inf pattern differs)")
            if err > args.field_tol or not same_inf:
                bad += 1
        if ref.get(key) != row:
            bad += 1
        print(f"{key:28s} {msg}")
    print("OK" if not bad else f"{bad} differences")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
