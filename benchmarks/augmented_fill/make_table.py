"""Markdown table from measure.py's JSON files.  Usage: python make_table.py bimba.json horse.json ..."""
import json
import sys

rows = []
for p in sys.argv[1:]:
    rows += json.load(open(p))
times = {(r["mesh"], r["form"]): r["factor_ms"] for r in rows if "factor_ms" in r}
print("| mesh | form | n | nnz(A) | nnz(L) | Mflops | × form 2 | CHOLMOD nnz(L) METIS / ND "
      "| CHOLMOD Σc² Mflops METIS / ND "
      "| factor ms (alternating runs) |")
print("|---|---|---|---|---|---|---|---|---|---|")
ref = {}
for r in rows:
    if r.get("form", "").startswith("2") and "mflops" in r:
        ref[r["mesh"]] = r["mflops"]


def fmt(x):
    return f"{x / 1e6:.2f}M" if x >= 1e6 else f"{x / 1e3:.0f}K"


for r in rows:
    if "mflops" not in r:
        continue
    form = r["form"]
    t = times.get((r["mesh"], form), "")
    if form.startswith(("3", "6")):
        tm = times.get((r["mesh"], form[0] + "m " + (form[2:form.index(" [")] if " [" in form else form[2:])
                        + ", matching"), "")
        extra = f" (static pivots; with matching {fmt(r['nnz_L_matching'])}, {r['mflops_matching']} Mflops)"
        t = f"matching: {', '.join(f'{x:.0f}' for x in tm)}" if tm else ""
    else:
        extra = ""
        t = ", ".join(f"{x:.0f}" for x in t) if t else ""
    ch = ""
    if "cholmod_metis_nnz_L" in r:
        ch = (f"{fmt(r['cholmod_metis_nnz_L'])} / {fmt(r['cholmod_nesdis_nnz_L'])}",
              f"{r['cholmod_metis_Mflops_sum_c2']:.0f} / {r['cholmod_nesdis_Mflops_sum_c2']:.0f}")
    else:
        ch = ("", "")
    ratio = f"{r['mflops'] / ref[r['mesh']]:.2f}" if not form.startswith("L") else ""
    print(f"| {r['mesh']} | {form} | {r['n']:,} | {fmt(r['nnz_A_lower'])} | {fmt(r['nnz_L'])}{extra} | {r['mflops']} "
          f"| {ratio} | {ch[0]} | {ch[1]} | {t} |")
