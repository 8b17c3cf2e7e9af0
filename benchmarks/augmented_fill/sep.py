"""Top separators of the nested-dissection orderings: the trailing dense block of the Cholesky factor (columns j
with nnz(L[:, j]) = N − j, the root supernode), its size and how many of its nodes are vertices (x) and how many
auxiliary unknowns; with CHOLMOD's METIS and nested-dissection orderings on the pattern of each form.

Usage: PYTHONPATH=src python benchmarks/augmented_fill/sep.py MESH [MESH ...]
"""
import sys
from pathlib import Path

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, str(Path(__file__).resolve().parent))
from measure import build, pattern_factor  # noqa: E402


def root_block(A, ordering, n_x):
    f = pattern_factor(A, ordering)
    L = f.L()
    N = A.shape[0]
    c = np.diff(L.indptr)
    dense = c == N - np.arange(N)
    k = 0
    while k < N and dense[N - 1 - k]:
        k += 1
    perm = f.P()
    top = perm[N - k:]
    return k, int((top < n_x).sum()), int(L.nnz)


if __name__ == "__main__":
    rng = np.random.default_rng(0)
    for name in sys.argv[1:]:
        forms, info = build(name, rng)
        n = info["n"]
        for label, (A, _) in forms.items():
            if label.startswith(("5", "6")):
                continue
            A = sp.csc_matrix(A)
            for o in ("metis", "nesdis"):
                k, kx, nnzL = root_block(A, o, n)
                print(f"{name}\t{label}\t{o}\troot block {k} nodes ({kx} vertices, {k - kx} auxiliary)\tnnz(L) {nnzL}",
                      flush=True)
