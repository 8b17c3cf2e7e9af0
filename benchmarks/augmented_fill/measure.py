"""nnz(L) and factorization Mflops (PARDISO, METIS) of the QCQP-Hessian Newton system's forms; CHOLMOD's count as a
second opinion; optional timing of one numeric factorization (alternating forms).

Usage (from anywhere):
  PYTHONPATH=src python benchmarks/augmented_fill/measure.py MESH [MESH ...] [--cholmod]
      [--time N] [--threads T] [--json OUT.json]
Forms: see forms.py. Values: H = an SPD matrix on the QCLP pattern (diagonally dominant), λ = 1 / max|Q| · 10;
every augmented form's Schur complement on x is H + λQ (checked by a solve against form 2).
Forms L2/L4: the squared-Laplacian energy S M⁻¹ S (a product of 1-ring factors), vertex system against the
augmented [[H, S], [S, −M/λ]]: the textbook case of the lever, for comparison.
"""
from __future__ import annotations

import argparse
import ctypes
import json
import sys
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, str(Path(__file__).resolve().parent))
from forms import (
    curved_hessian_energy,
    face_eig,
    face_factors,
    form3,
    form4,
    form5a,
    form6,
    global_G_S,
    kkt_pattern,
    load,
)

from cvxgeodesic.linalg import pardiso as P


class Pardiso:
    """PARDISO on the lower triangle (CSC) = upper CSR of a symmetric matrix, mtype 2 (SPD) or -2 (indefinite)."""

    def __init__(self, A: sp.csc_matrix, mtype: int, threads: int, ordering: int = 2, matching: bool = False):
        self.lib = P._load()
        L = sp.tril(A, format="csc")
        L.sort_indices()
        self.n = A.shape[0]
        self.indptr = L.indptr.astype(np.int32)
        self.indices = L.indices.astype(np.int32)
        self.data = L.data.astype(np.float64).copy()
        self.mtype, self.threads = mtype, threads
        self.pt = np.zeros(64, np.int64)
        ip = np.zeros(64, np.int32)
        ip[0] = 1
        ip[1] = ordering          # 2: METIS nested dissection, 0: minimum degree
        ip[7] = 0
        ip[9] = 13 if mtype != 2 else 0   # pivot perturbation 1e-13 (PARDISO's default is 8 for -2; tiny here)
        # no scaling, no weighted matching: a static symmetric ordering of the pattern itself; with matching
        # (PARDISO's default for mtype -2) the analysis pairs rows into 2×2 pivots from the values first
        ip[10] = 1 if matching else 0
        ip[12] = 1 if matching else 0
        ip[17] = -1               # report nnz(L)
        ip[18] = -1               # report Mflops of the factorization
        ip[20] = 1 if mtype != 2 else 0   # Bunch-Kaufman 1x1/2x2 pivoting inside supernodes
        ip[23] = P._FACTOR_ALGORITHM
        ip[24] = P._SOLVE_ALGORITHM
        ip[34] = 1
        self.ip = ip
        t = time.perf_counter()
        self._call(11)
        self.t_analysis = time.perf_counter() - t
        self.nnz_L = int(ip[17])
        self.mflops = int(ip[18])

    def _call(self, phase, b=None, x=None):
        err = ctypes.c_int32(0)
        one = ctypes.c_int32(1)
        prev = self.lib.MKL_Set_Num_Threads_Local(self.threads)
        try:
            self.lib.pardiso(self.pt.ctypes.data, ctypes.byref(one), ctypes.byref(one),
                             ctypes.byref(ctypes.c_int32(self.mtype)), ctypes.byref(ctypes.c_int32(phase)),
                             ctypes.byref(ctypes.c_int32(self.n)), self.data.ctypes.data, self.indptr.ctypes.data,
                             self.indices.ctypes.data, None, ctypes.byref(one), self.ip.ctypes.data,
                             ctypes.byref(ctypes.c_int32(0)), None if b is None else b.ctypes.data,
                             None if x is None else x.ctypes.data, ctypes.byref(err))
        finally:
            self.lib.MKL_Set_Num_Threads_Local(prev)
        if err.value:
            raise P.PardisoError(err.value, phase)

    def factorize(self):
        t = time.perf_counter()
        self._call(22)
        return time.perf_counter() - t

    def solve(self, b):
        b = np.array(b, dtype=np.float64)
        x = np.zeros_like(b)
        self._call(33, b, x)
        return x

    def inertia(self):
        return int(self.ip[21]), int(self.ip[22]), int(self.ip[13])  # positive, negative, perturbed pivots

    def release(self):
        self._call(-1)


def pattern_factor(A, ordering):
    """CHOLMOD's simplicial factor of an SPD matrix with A's pattern (diagonally dominant: only the pattern
    matters); ``.L()`` and ``.P()`` give the factor and the fill-reducing permutation."""
    from sksparse.cholmod import analyze
    pat = sp.csc_matrix((np.ones(A.nnz), A.indices, A.indptr), shape=A.shape)
    deg = np.asarray(pat.sum(axis=0)).ravel()
    spd = (-pat + sp.diags(2 * deg + 1.0)).tocsc()
    f = analyze(spd, mode="simplicial", ordering_method=ordering)
    f.cholesky_inplace(spd)
    return f


def cholmod_counts(A, ordering):
    """nnz(L) and Σ_j c_j² (the LLᵀ flop count, c_j the nonzeros of column j with the diagonal) from CHOLMOD's
    symbolic factorization of the pattern (an SPD matrix with A's pattern: only the pattern matters)."""
    Lm = pattern_factor(A, ordering).L()
    c = np.diff(Lm.indptr).astype(np.float64)
    return int(Lm.nnz), float((c * c).sum())


def spd_H(pattern, rng):
    """SPD values on the QCLP pattern: off-diagonal −U(0.5, 1.5), diagonal = row sum + 0.01 (strictly dominant)."""
    Hl = sp.tril(pattern, k=-1, format="coo")
    v = -rng.uniform(0.5, 1.5, Hl.nnz)
    off = sp.csc_matrix((v, (Hl.row, Hl.col)), shape=pattern.shape)
    off = off + off.T
    d = -np.asarray(off.sum(axis=1)).ravel() + 0.01
    return (off + sp.diags(d)).tocsc()


def build(name, rng):
    mesh = load(name)
    n, F, edges = mesh.n_vertices, mesh.F, mesh.edges
    Cs, LKs, verts, unk, ne = face_factors(mesh)
    G, S = global_G_S(mesh, Cs, LKs, verts, unk, ne)
    Q = curved_hessian_energy(mesh)
    lam = 10.0 / abs(Q).max()
    H1 = kkt_pattern(n, F, edges)
    H = spd_H(H1, rng)
    H2 = kkt_pattern(n, F, edges, Q)
    A2 = (H + lam * Q).tocsc()
    # the pattern of form 2 is kkt_pattern with Q (explicit zeros where Q cancels are kept by kkt_pattern)
    A2 = (A2 + 0.0 * H2).tocsc()
    A3 = form3(H, G, lam * S)
    w, Ct, keep = face_eig(LKs)
    A4, B, wk = form4(H, Cs, verts, lam * w, Ct, keep, n)
    A5 = form5a(H, Cs, verts, n, LKs, lam)
    from cvxgeodesic.operators.laplacian import cotan_stiffness, mass_matrix
    Sc = cotan_stiffness(mesh)
    M = mass_matrix(mesh).diagonal()
    QL = Sc @ sp.diags(1.0 / M) @ Sc
    lamL = 10.0 / abs(QL).max()
    AL2 = (H + lamL * QL).tocsc()
    AL4 = sp.bmat([[H, Sc], [Sc, sp.diags(-M / lamL)]], format="csc")
    forms = {"1 QCLP (floor)": (H, 2), "2 Hessian, vertex system": (A2, 2),
             "3 aug. edges [H,0,-Gᵀ;0,S,I;-G,I,0]": (A3, -2), "4 aug. q-def. per face [H,Bᵀ;B,-Λ⁻¹]": (A4, -2),
             "5a per-face copies [H,G_fᵀ;G_f,-S_f⁻¹]": (A5, -2),
             "6 aug. perp edge unknowns only": (form6(H, G, lam * S), -2),
             "L2 Laplacian energy SM⁻¹S, vertex system": (AL2, 2), "L4 Laplacian aug. [H,S;S,-M/λ]": (AL4, -2)}
    info = {"n": n, "m": len(F), "edges": ne, "neg_lambda": int((wk < 0).sum()), "n_u": int(wk.size)}
    return forms, info


TIMED = ("1 QCLP (floor)", "2 Hessian, vertex system", "3m aug. edges, matching",
         "4 aug. q-def. per face [H,Bᵀ;B,-Λ⁻¹]", "5a per-face copies [H,G_fᵀ;G_f,-S_f⁻¹]",
         "L2 Laplacian energy SM⁻¹S, vertex system",
         "L4 Laplacian aug. [H,S;S,-M/λ]")


def check_solve(pd, A, b, ref, n):
    """Factorize, solve [b; 0], compare the x part with the reference (the vertex system's solution)."""
    pd.factorize()
    rhs = np.zeros(A.shape[0])
    rhs[:n] = b
    x = pd.solve(rhs)
    return {"rel_err_x": float(f"{np.linalg.norm(x[:n] - ref) / np.linalg.norm(ref):.2e}"),
            "residual": float(f"{np.linalg.norm(A @ x - rhs) / np.linalg.norm(rhs):.2e}"),
            "inertia(+,-,perturbed)": list(pd.inertia())}


def measure_mesh(name, args, rng, out):
    forms, info = build(name, rng)
    print(f"\n{name}: {info}", flush=True)
    n = info["n"]
    b = rng.standard_normal(n)
    handles, refs = {}, {}
    for label, (A, mtype) in forms.items():
        A = sp.csc_matrix(A)
        A.sort_indices()
        pd = Pardiso(A, mtype, args.threads)
        row = {"mesh": name, "form": label, "n": A.shape[0], "nnz_A_lower": int(sp.tril(A).nnz), "nnz_L": pd.nnz_L,
               "mflops": pd.mflops, "t_analysis_s": round(pd.t_analysis, 3)}
        variants = [(label, pd)]
        if label.startswith("2"):
            pdi = Pardiso(A, -2, args.threads)  # the same pattern analysed as indefinite: the same fill?
            row["nnz_L_as_mtype-2"], row["mflops_as_mtype-2"] = pdi.nnz_L, pdi.mflops
            pdi.release()
        if label.startswith(("3", "6")):
            pdm = Pardiso(A, mtype, args.threads, matching=True)  # a saddle point: needs 2×2 pivots
            row["nnz_L_matching"], row["mflops_matching"] = pdm.nnz_L, pdm.mflops
            short = label[2:label.index(" [")] if " [" in label else label[2:]
            variants.append((f"{label[0]}m {short}, matching", pdm))
        pd0 = Pardiso(A, mtype, args.threads, ordering=0)
        row["nnz_L_amd"], row["mflops_amd"] = pd0.nnz_L, pd0.mflops
        pd0.release()
        if args.cholmod:
            for o in ("metis", "nesdis", "amd"):
                row[f"cholmod_{o}_nnz_L"], fl = cholmod_counts(A, o)
                row[f"cholmod_{o}_Mflops_sum_c2"] = round(fl / 1e6, 1)
        for vlabel, h in variants:
            if vlabel.startswith(("2", "L2")):
                h.factorize()
                refs[vlabel[0]] = h.solve(b)
            elif not vlabel.startswith("1"):
                ref = refs["L" if vlabel.startswith("L") else "2"]
                row["check" if vlabel == label else "check_matching"] = check_solve(h, A, b, ref, n)
            if vlabel in TIMED:
                handles[vlabel] = h
            else:
                h.release()
        print("  " + json.dumps(row, ensure_ascii=False), flush=True)
        out.append(row)
    if n > 30000:  # form 3 with matching: 4-6 s a factorization on bimba already; not timed on larger meshes
        handles.pop("3m aug. edges, matching").release()
    if args.time:
        times = {k: [] for k in handles}
        for _ in range(args.time):
            for k in handles:
                times[k].append(handles[k].factorize())
        for k in handles:
            print(f"  factor time {k}: " + ", ".join(f"{t * 1e3:.0f}" for t in times[k]) + " ms")
            out.append({"mesh": name, "form": k, "factor_ms": [round(t * 1e3, 1) for t in times[k]],
                        "threads": args.threads})
    for h in handles.values():
        h.release()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--cholmod", action="store_true")
    ap.add_argument("--time", type=int, default=0, help="numeric factorizations per timed form (alternating)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--json")
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    out = []
    for name in args.meshes:
        measure_mesh(name, args, rng, out)
        if args.json:
            json.dump(out, open(args.json, "w"), indent=1, ensure_ascii=False)


if __name__ == "__main__":
    main()
