#!/bin/bash
# Every mesh of docs/dev/performance-log.md's fill section: PARDISO + CHOLMOD counts, 5 alternating factor timings, 2 threads.
# Run from the repository root: benchmarks/augmented_fill/run_all.sh OUTDIR (results and logs go to OUTDIR).
set -e
here=$(cd "$(dirname "$0")" && pwd)
out=${1:?usage: run_all.sh OUTDIR}
mkdir -p "$out"
for m in bimba.obj horse.ply armadillo.obj; do
  b=${m%%.*}
  echo "== $m $(date -u +%FT%TZ) $(uptime)" >> "$out/run_all.log"
  PYTHONPATH="$here/../../src" /usr/bin/time -f "peak RSS %M kB, wall %e s" python "$here/measure.py" "$m" \
      --cholmod --time 5 --json "$out/$b.json" > "$out/$b.log" 2>&1
  tail -1 "$out/$b.log" >> "$out/run_all.log"
  echo "   after: $(uptime)" >> "$out/run_all.log"
done
