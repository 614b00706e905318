#!/bin/sh
# t_gis.sh — GIS layers: `cellar polygons` over GeoJSON files, and over a Shapefile with a
# GeoPackage into a GeoPackage (GDAL's ogr2ogr), equal to shapely's overlay with the
# attributes carried (tests/gis_check.py says what exactly); and the errors a GIS user meets:
# plain GeoJSON given to `cellar run`, a FeatureCollection where a polygon is expected, a layer
# name that is not one, a missing --op or --output, layers in different reference systems, a
# file GDAL cannot read.
# Usage: CELLAR_BIN=build/cellar tests/t_gis.sh   (tests/run.sh sets CELLAR_BIN)
set -u
. "$(dirname "$0")/lib.sh"
BIN=${CELLAR_BIN:-build/cellar}
case $BIN in /*) ;; *) [ -e "$BIN" ] && BIN="$(pwd)/$BIN" ;; esac
cd "$(dirname "$0")/.."
need_python "shapely.geometry, shapely.ops, shapely.wkb, sqlite3" "python3-shapely"
[ -x "$BIN" ] || give_up "$BIN is not built"
command -v ogr2ogr >/dev/null || give_up "ogr2ogr is needed: apt-get install gdal-bin (make deps)"

cat >"$T/a.geojson" <<'JSON'
{"type": "FeatureCollection", "features": [
 {"type": "Feature", "properties": {"id": 1}, "geometry": {"type": "Polygon",
  "coordinates": [[[0, 0], [2, 0], [2, 2], [0, 2], [0, 0]]]}}]}
JSON
cat >"$T/b.geojson" <<'JSON'
{"type": "FeatureCollection", "features": [
 {"type": "Feature", "properties": {"id": 2}, "geometry": {"type": "Polygon",
  "coordinates": [[[1, 1], [3, 1], [3, 3], [1, 3], [1, 1]]]}}]}
JSON

# plain GeoJSON is not a request: the message says which command takes it
status 1 "$BIN" run "$T/a.geojson"
check "cellar run on a FeatureCollection names cellar polygons and layers" \
    grep -q 'this is GeoJSON (a FeatureCollection), not a request.*cellar polygons.*layers' "$T/err"

# a FeatureCollection where one polygon is expected: the error names "layers"
printf '{"kind": "polygons", "polygons": [%s, %s], "op": "intersection"}' \
    "$(cat "$T/a.geojson")" "$(cat "$T/b.geojson")" >"$T/two-fc.json"
status 1 "$BIN" run "$T/two-fc.json"
check "a FeatureCollection in polygons: the error names layers" \
    grep -q 'polygons\[0\].type: a FeatureCollection is a layer.*"layers"' "$T/err"

# both collections merged into one with a named intersection: the empty answer warns
/usr/bin/python3 -c '
import json, sys
a, b = (json.load(open(f)) for f in sys.argv[1:3])
print(json.dumps({"kind": "polygons", "op": "intersection", "polygons": {
    "type": "FeatureCollection", "features": a["features"] + b["features"] + a["features"]}}))
' "$T/a.geojson" "$T/b.geojson" >"$T/merged.json"
sed 's/\[\[0, 0\], \[2, 0\], \[2, 2\], \[0, 2\], \[0, 0\]\]/[[9, 9], [10, 9], [10, 10], [9, 9]]/' \
    "$T/merged.json" >"$T/merged-apart.json"
status 0 "$BIN" run "$T/merged-apart.json"
check "an empty intersection of all of many polygons: stats.warnings points to layers" \
    grep -q '"warnings":\["op: the intersection of all 3 polygons is empty; to intersect collections, give them as \\"layers\\"' "$T/out"
status 0 "$BIN" run "$T/merged.json"
check "... and a non-empty one has no warnings" sh -c "! grep -q warnings '$T/out'"

# layers and the op over their names, through cellar run
printf '{"kind": "polygons", "layers": {"a": %s, "b": %s}, "op": ["&", "a", "b"]}' \
    "$(cat "$T/a.geojson")" "$(cat "$T/b.geojson")" >"$T/layers.json"
status 0 "$BIN" run "$T/layers.json"
check "layers a & b: area 1, the layers and the pieces in the result" /usr/bin/python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert d["result"]["area"] == 1, d["result"]["area"]
assert [(l["name"], l["first"], l["count"], l["properties"]) for l in d["layers"]] == \
    [("a", 0, 1, [{"id": 1}]), ("b", 1, 1, [{"id": 2}])], d["layers"]
pc = d["result"]["pieces"]
assert pc["piece"] == [0] and pc["inputs"] == {"indptr": [0, 2], "indices": [0, 1]}, pc
' "$T/out"
sed 's/\["&", "a", "b"\]/["\&", "a", "c"]/' "$T/layers.json" >"$T/bad-name.json"
status 1 "$BIN" run "$T/bad-name.json"
check "an op naming no layer: the error lists the layers" \
    grep -q 'op\[2\]: "c" is not a layer (the layers: "a", "b")' "$T/err"

# the command's own errors
status 2 "$BIN" polygons "$T/a.geojson" "$T/b.geojson"
check "polygons without --op: a usage error naming the ops" grep -q -- '--op is required' "$T/err"
status 2 "$BIN" polygons "$T/a.geojson" "$T/b.geojson" --op union --format gpkg
check "--format gpkg without --output: a usage error" grep -q -- '--output' "$T/err"
status 2 "$BIN" run "$T/layers.json" --format gpkg
check "--format gpkg is for polygons only" grep -q 'gpkg is for the polygons command' "$T/err"
printf 'not a shapefile' >"$T/broken.shp"
status 1 "$BIN" polygons "$T/a.geojson" "$T/broken.shp" --op union
check "a file GDAL cannot read: an error naming it" grep -q 'reading .*broken.shp' "$T/err"
ogr2ogr -q -f GeoJSON -s_srs EPSG:4326 -t_srs EPSG:3857 "$T/b3857.geojson" "$T/b.geojson"
status 1 "$BIN" polygons "$T/a.geojson" "$T/b3857.geojson" --op union
check "layers in different reference systems: refused" grep -q 'reference system differs' "$T/err"
# a reference system is carried to GeoJSON, and every other format is what it says
ogr2ogr -q -f GeoJSON -s_srs EPSG:4326 -t_srs EPSG:3857 "$T/a3857.geojson" "$T/a.geojson"
status 0 "$BIN" polygons "$T/a3857.geojson" "$T/b3857.geojson" --op union --format geojson
check "layers in EPSG:3857 to GeoJSON: the FeatureCollection names the system" /usr/bin/python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert d["type"] == "FeatureCollection" and "3857" in json.dumps(d["crs"]), d.get("crs")
' "$T/out"
status 0 "$BIN" polygons "$T/a3857.geojson" "$T/b3857.geojson" --op union --format json
check "... and to --format json: the LAR JSON result" /usr/bin/python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert d["dim"] == 2 and d["result"]["area"] > 0, list(d)
' "$T/out"
status 0 "$BIN" polygons "$T/a.geojson" "$T/b.geojson" --op xor --format request
check "--format request: the layers request, named by the files" /usr/bin/python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert d["kind"] == "polygons" and list(d["layers"]) == ["a", "b"] and d["op"] == "xor", d
' "$T/out"

# the overlays against shapely
$PY tests/gis_check.py "$T" >"$T/py.out" 2>"$T/py.err"
rc=$?
tally_file "$T/py.out"
grep -q -E '^[0-9]+ passed, [0-9]+ failed' "$T/py.out" ||
    fail "gis_check.py exited $rc without a summary: $(tail -n 3 "$T/py.err")"
finish
