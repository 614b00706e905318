#!/bin/sh
# t_winding3d.sh — solids that pass through themselves, by winding number (issue 26): boxes
# merged into one solid (some inside out, some on a lattice so that faces coincide) against
# coordinate compression under the fill rules positive, nonzero and odd; a pentagram prism; a
# surface given twice; inside-out and hollow boxes; a tube swept past its start; overlapping
# meshes merged into one solid against CGAL's union of them (tests/ref/cgal_bool); the cow,
# which passes through itself.  On every case: every cell's volume > 0 and the sum of winding *
# volume is the input's signed volume.  See tests/winding3d.py.
# CELLAR_STRESS=N: N seeds per random family; CELLAR_DUMP=DIR keeps the failing inputs.
set -u
cd "$(dirname "$0")/.." || exit 1
. tests/lib.sh
export CELLAR_BUILD="${CELLAR_BUILD:-build}"
export CELLAR_BIN="${CELLAR_BIN:-$CELLAR_BUILD/cellar}"
[ -x "$CELLAR_BIN" ] || give_up "$CELLAR_BIN is not built"
run_py "${PYTHON:-python3}" tests/winding3d.py
