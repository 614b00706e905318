#!/bin/sh
# t_npz.sh — results as NumPy arrays (--format npz, ?format=npz) read by numpy and scipy, as a
# user reads them: the README's two lines run as written, and every array against the result's
# JSON (V, EV, the rows, holes, the operators as scipy matrices with d1·d2 = 0 and d2·d3 = 0,
# membership, the Boolean's result, the rest in "json"), for 2D lines, SVG, polygons and 3D
# solids, and a 100 000-segment result.  See tests/npz_check.py.
set -u
cd "$(dirname "$0")/.." || exit 1
. tests/lib.sh
export CELLAR_BUILD="${CELLAR_BUILD:-build}"
export CELLAR_BIN="${CELLAR_BIN:-$CELLAR_BUILD/cellar}"
case $CELLAR_BIN in /*) ;; *) CELLAR_BIN="$(pwd)/$CELLAR_BIN" ;; esac
[ -x "$CELLAR_BIN" ] || give_up "$CELLAR_BIN is not built"
need_python "numpy, scipy.sparse" "python3-numpy python3-scipy"
run_py $PY tests/npz_check.py "$T"
