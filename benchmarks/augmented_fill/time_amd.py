"""Factor times of the vertex system (METIS and AMD) against forms 4 and 5 with AMD, the augmented forms' cheapest
ordering on armadillo. Alternating, N rounds, 2 threads.
Usage: PYTHONPATH=src python benchmarks/augmented_fill/time_amd.py MESH [N]"""
import sys
from pathlib import Path

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, str(Path(__file__).resolve().parent))
from measure import Pardiso, build  # noqa: E402

name = sys.argv[1]
rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 5
forms, info = build(name, np.random.default_rng(0))
pick = {"2 METIS": ("2 Hessian, vertex system", 2), "2 AMD": ("2 Hessian, vertex system", 0),
        "4 AMD": ("4 aug. q-def. per face [H,Bᵀ;B,-Λ⁻¹]", 0), "5 AMD": ("5a per-face copies [H,G_fᵀ;G_f,-S_f⁻¹]", 0)}
h = {}
for k, (label, ordering) in pick.items():
    A, mtype = forms[label]
    A = sp.csc_matrix(A)
    A.sort_indices()
    h[k] = Pardiso(A, mtype, 2, ordering=ordering)
    print(f"{name} {k}: nnz(L) {h[k].nnz_L}, Mflops {h[k].mflops}", flush=True)
t = {k: [] for k in h}
for _ in range(rounds):
    for k in h:
        t[k].append(h[k].factorize())
for k in h:
    print(f"{name} {k}: factor ms " + ", ".join(f"{x * 1e3:.0f}" for x in t[k]))
    h[k].release()
