#!/bin/sh
# t_contacts3d.sh — the 3D Booleans on solids that touch: boxes, tetrahedra, prisms and turned
# cubes at a vertex, along an edge or in a face, from outside and from inside a container, on
# and off the grid's dyadic values; against closed forms and CGAL Nef (tests/ref/cgal_nef), within
# the snapping bound.  See tests/contacts3d.py.
# CELLAR_STRESS=N: N seeds per family (make stress); CELLAR_DUMP=DIR keeps the failing inputs.
set -u
cd "$(dirname "$0")/.."
B=$(dirname "${CELLAR_BIN:-build/cellar}")
if [ ! -x "$B/cellar" ] || [ ! -x "$B/tests/ref/cgal_nef" ]; then
    echo "FAIL $B/cellar or $B/tests/ref/cgal_nef is not built"
    echo "0 passed, 1 failed"
    exit 1
fi
exec "${PYTHON:-python3}" tests/contacts3d.py "$B" "$@"
