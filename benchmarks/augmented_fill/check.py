"""Check that the factors built by forms.py reproduce cvxgeodesic's Hessian energy: Gᵀ S G = Q, and the per-face
eigen-split Σ_f (C_f G_f)ᵀ Λ_f (C_f G_f) = Q.  Usage: PYTHONPATH=src python benchmarks/augmented_fill/check.py MESH"""
import sys
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, str(Path(__file__).resolve().parent))
from forms import curved_hessian_energy, face_eig, face_factors, global_G_S, load

name = sys.argv[1] if len(sys.argv) > 1 else "bunny_7k.off"
mesh = load(name)
t = time.time()
Cs, LKs, verts, unk, ne = face_factors(mesh)
G, S = global_G_S(mesh, Cs, LKs, verts, unk, ne)
Q = curved_hessian_energy(mesh)
print(f"{name}: n {mesh.n_vertices} m {len(mesh.F)} edges {ne}; max|GᵀSG − Q| / max|Q| = "
      f"{abs(G.T @ S @ G - Q).max() / abs(Q).max():.2e}  ({time.time() - t:.1f} s)")
w, Ct, keep = face_eig(LKs)
B = np.einsum("fkj,fjv->fkv", Ct, Cs)
blocks = np.einsum("fkr,fk,fkc->frc", B, np.where(keep, w, 0.0), B)
n = mesh.n_vertices
r = np.repeat(verts, 6, axis=1).ravel()
c = np.tile(verts, (1, 6)).ravel()
ok = (r >= 0) & (c >= 0)
Qe = sp.csc_matrix((blocks.ravel()[ok], (r[ok], c[ok])), shape=(n, n))
print(f"  eigen-split: max|Σ BᵀΛB − Q| / max|Q| = {abs(Qe - Q).max() / abs(Q).max():.2e}")
print("  faces by number of nonzero eigenvalues of S_f (0..6):", np.bincount(keep.sum(1), minlength=7).tolist(),
      "; negative eigenvalues in all:", int((keep & (w < 0)).sum()), "of", int(keep.sum()))
print(f"  G: {G.shape}, {G.nnz / G.shape[0]:.2f} nnz/row; S: {S.nnz / S.shape[0]:.2f} nnz/row; "
      f"Q: {Q.nnz / n:.2f} nnz/row")
