#!/bin/sh
# t_winding2d.sh — the 2D polygons' fill rules "odd", "nonzero" and "positive" (issue 26): two
# squares overlapping in one polygon, holes turning either way, a clockwise square, a pentagram,
# a Boolean of such polygons, and random star rings (some clockwise, some on a lattice, some far
# from the origin).  Every face's winding numbers against the rings' own about a point inside
# it, each polygon's sum of area * winding against its rings' signed area, and the result's
# area against GEOS's polygonize of the ring lines.  See tests/winding2d.py.
# CELLAR_STRESS=N: N seeds per random family.
set -u
cd "$(dirname "$0")/.." || exit 1
. tests/lib.sh
export CELLAR_BUILD="${CELLAR_BUILD:-build}"
export CELLAR_BIN="${CELLAR_BIN:-$CELLAR_BUILD/cellar}"
case $CELLAR_BIN in /*) ;; *) CELLAR_BIN="$(pwd)/$CELLAR_BIN" ;; esac
[ -x "$CELLAR_BIN" ] || give_up "$CELLAR_BIN is not built"
need_python "shapely.geometry, shapely.ops" "python3-shapely"
run_py $PY tests/winding2d.py
