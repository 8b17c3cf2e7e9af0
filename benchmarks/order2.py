"""Order 2 (P2 squared distance) against order 1 (P1 qclp), heat, FMM and exact MMP.

Usage: ``PYTHONPATH=src python benchmarks/order2.py [--weights=p2|lumped] OUT.json [mesh ...]``; meshes are names in
../shared/meshes (``thingi10k_small`` expands to its files). Source vertex 0; errors are relative,
per vertex, sources excluded, against pygeodesic's exact MMP. Times are wall-clock on whatever
machine runs it (state its load when you publish them).
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import cvxgeodesic as cg
from cvxgeodesic.baselines import BASELINES

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"


def rel_err(d, de):
    ok = np.isfinite(de) & (de > 1e-12 * np.nanmax(de[np.isfinite(de)]))
    r = np.abs(d[ok] - de[ok]) / de[ok]
    return float(np.mean(r)), float(np.max(r))


def run(name: str) -> dict:
    mesh = cg.load_mesh(SHARED / name)
    out = {"mesh": name, "faces": mesh.n_faces, "vertices": mesh.n_vertices}
    try:
        de, _ = BASELINES["exact"](mesh).solve(np.array([0]))
    except Exception as exc:  # non-manifold input: no exact reference
        out["skipped"] = f"exact: {type(exc).__name__}: {exc}"
        return out
    de = np.asarray(de, float)
    for label, kw in (("p1", {"method": "qclp"}), ("p2", {"method": "qclp", "order": 2}),
                      ("heat", {"method": "heat"}), ("fmm", {"method": "fmm"})):
        try:
            s = cg.GeodesicSolver(mesh, **kw)
            t = time.perf_counter()
            r = s.solve(0)
            out[label] = {"time": time.perf_counter() - t + s.setup_time, "status": r.info.status,
                          "mean": rel_err(r.distance, de)[0], "max": rel_err(r.distance, de)[1],
                          "solver": r.info.solver, "notes": list(r.info.notes)}
        except Exception as exc:
            out[label] = {"error": f"{type(exc).__name__}: {exc}"}
    return out


def main(argv):
    warnings.simplefilter("ignore")
    if argv[0].startswith("--weights="):
        import cvxgeodesic.elements_p2 as p2

        p2.DEFAULT_WEIGHTS = argv.pop(0).split("=", 1)[1]
    dest = Path(argv[0])
    names = []
    for a in argv[1:]:
        if a == "thingi10k_small":
            names += [f"thingi10k_small/{p.name}" for p in sorted((SHARED / a).glob("*.stl"))]
        else:
            names.append(a)
    rows = json.loads(dest.read_text()) if dest.exists() else []
    done = {r["mesh"] for r in rows}
    for nm in names:
        if nm in done:
            continue
        row = run(nm)
        rows.append(row)
        dest.write_text(json.dumps(rows, indent=1))
        print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
