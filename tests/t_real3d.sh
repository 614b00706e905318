#!/bin/sh
# t_real3d.sh — the 3D Booleans on real meshes (tests/data/mesh/real) and on hard families
# (slivers, near-coplanar faces), against CGAL's exact corefinement and closed forms, within the
# snapping bound; the failing cases of tests/data/solids-cases.  See tests/real3d.py.
# CELLAR_STRESS=N: every mesh, N seeds per family (make stress).
set -u
cd "$(dirname "$0")/.."
B=$(dirname "${CELLAR_BIN:-build/cellar}")
if [ ! -x "$B/cellar" ] || [ ! -x "$B/tests/ref/cgal_bool" ]; then
    echo "FAIL $B/cellar or $B/tests/ref/cgal_bool is not built"
    echo "0 passed, 1 failed"
    exit 1
fi
exec "${PYTHON:-python3}" tests/real3d.py "$B" "$@"
