#!/bin/sh
# t_geojson.sh — cellar's GeoJSON maps checked by a real validator (shapely, on GEOS): the
# README's and the overlay cases' Boolean requests, random Boolean requests made to be hard,
# line drawings with dangling edges and blocks at cut vertices, and SVG drawings; every map
# valid, rings closed and oriented, a Boolean's result region with its area, the selected
# faces' union equal to it (tests/geojson_check.py says what exactly).
# Usage: CELLAR_BIN=build/cellar tests/t_geojson.sh   (tests/run.sh sets CELLAR_BIN)
set -u
. "$(dirname "$0")/lib.sh"
BIN=${CELLAR_BIN:-build/cellar}
case $BIN in /*) ;; *) [ -e "$BIN" ] && BIN="$(pwd)/$BIN" ;; esac
cd "$(dirname "$0")/.."
need_python "shapely.geometry, shapely.ops, shapely.validation" "python3-shapely"
[ -x "$BIN" ] || give_up "$BIN is not built"
# line drawings: dangling trees inside a face and hanging from its side, blocks at cut vertices
cat >"$T/cut-vertices.json" <<'JSON'
{"kind": "lines", "lines": [[[0, 0], [8, 0]], [[8, 0], [8, 8]], [[8, 8], [0, 8]], [[0, 8], [0, 0]],
 [[4, 0], [6, 4]], [[6, 4], [2, 4]], [[2, 4], [4, 0]], [[1, 5], [2, 7]], [[2, 7], [3, 5]],
 [[3, 5], [1, 5]], [[3, 5], [4, 7]], [[4, 7], [5, 5]], [[5, 5], [3, 5]], [[6, 6], [7, 6]],
 [[7, 6], [7, 7]], [[7, 6], [7.5, 5.5]], [[0, 2], [1, 2]], [[1, 2], [1, 3]]],
 "options": {"keep_dangling": true}}
JSON
for f in floorplan.svg; do
    "$BIN" svg "examples/$f" --format request >"$T/svg-$f.json" 2>"$T/err" ||
        fail "cellar svg examples/$f --format request: $(head -c 200 "$T/err")"
done
for f in Lar.svg architectural-test.svg; do
    "$BIN" svg "tests/data/svg/$f" --format request >"$T/svg-$f.json" 2>"$T/err" ||
        fail "cellar svg tests/data/svg/$f --format request: $(head -c 200 "$T/err")"
done
$PY tests/geojson_check.py "$BIN" "$T" examples/polygons.json examples/orthogonal.json \
    tests/data/bool2-cases/wrong-side-thin-spike.json tests/data/bool2-cases/no-interior-point.json \
    tests/data/bool2-cases/xor-walk.json tests/data/bool2-cases/touching-holes-union.json \
    "$T/cut-vertices.json" "$T"/svg-*.json >"$T/out" 2>&1
rc=$?
tally_file "$T/out"
[ "$rc" -eq 0 ] || [ "$F" -gt 0 ] || fail "geojson_check.py exited $rc"
finish
