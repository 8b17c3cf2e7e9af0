#!/bin/bash
# Build the wheel from HEAD, install it in a fresh venv and run the default test suite with every shared library of the
# Makefile's Debian packages hidden, as on a Linux x86-64 machine that never ran `make` (issue 16).
#
#   sudo scripts/check_wheel_without_debian_libs.sh [WORKDIR]   (root for unshare/mount, network for pip; the wheel
#   is built with BUILD_PYTHON, default .venv/bin/python, which needs `build`: `make setup` installs it)
#
# The libraries of the Makefile's DEB_PACKAGES and of the SuiteSparse/BLAS runtime packages they pull in are
# masked, inside a private mount namespace only, by bind-mounting an empty file over each (`dlopen` then fails
# with "file too short"). pip installs the wheel with the pardiso, io, cluster and test extras from PyPI; the
# tests run from a copy of tests/ with no ../shared beside it, as in a user's checkout.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
WORK=${1:-/tmp/cvxgeodesic-no-debian}
PY=${PYTHON:-python3}
if [ "${CVXG_INSIDE:-}" != 1 ]; then
  rm -rf "$WORK" && mkdir -p "$WORK/t"
  deb=$(sed -n 's/^DEB_PACKAGES := //p' "$ROOT/Makefile")
  runtime="libamd2 libcamd2 libbtf1 libcolamd2 libccolamd2 libcholmod3 libcxsparse3 libklu1 libldl2 libmongoose2
           libumfpack5 librbio2 libspqr2 libsliplu1 libsuitesparseconfig5 libopenblas-pthread-dev libopenblas-dev
           libblas3 liblapack3"
  for p in $deb $runtime; do dpkg -L "$p" 2>/dev/null || true; done | grep -E '\.so(\.|$)' | sort -u \
    | while read -r f; do [ -e "$f" ] && readlink -f "$f"; done | sort -u > "$WORK/hidden.txt"
  # from the committed tree only: an in-tree build reuses setuptools' build/lib, whose stale files (modules
  # deleted since the last build) would end up in the wheel
  mkdir -p "$WORK/src" && git -C "$ROOT" archive --format=tar HEAD | tar -x -C "$WORK/src"
  "${BUILD_PYTHON:-$ROOT/.venv/bin/python}" -m build --wheel --outdir "$WORK/dist" "$WORK/src" > "$WORK/build.log" 2>&1
  cp -r "$ROOT/tests" "$WORK/t/"
  exec env CVXG_INSIDE=1 unshare -m --propagation private "$0" "$WORK"
fi
: > "$WORK/empty"
while read -r f; do mount --bind "$WORK/empty" "$f"; done < "$WORK/hidden.txt"
echo "hidden: $(wc -l < "$WORK/hidden.txt") shared libraries of the Debian packages (list: $WORK/hidden.txt)"
if "$PY" -c "import ctypes; ctypes.CDLL('libgomp.so.1')" 2>/dev/null; then echo "libgomp still loads" >&2; exit 1; fi
"$PY" -m venv "$WORK/venv"
V="$WORK/venv/bin"
"$V/python" -m pip install -q --upgrade pip
"$V/python" -m pip install -q "$(ls "$WORK"/dist/*.whl)[pardiso,io,cluster,test]"
cd "$WORK/t"
"$V/python" -c "
import cvxgeodesic as cg
r = cg.GeodesicSolver(cg.icosphere(3), 'qcqp-hessian').solve(0)
print('solver', r.info.solver, '| factorization', r.info.extra.get('backend'), '| iterations', r.info.iterations)
"
CVXGEODESIC_THREADS=1 "$V/python" -m pytest -q -m "not slow" -p no:cacheprovider tests
