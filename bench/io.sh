#!/bin/sh
# bench/io.sh — JSON read and write throughput (issue 27): requests of each kind made here, read
# and their results written by BUILD_DIR/bench/io (bench/io.c says what each figure is), beside
# jansson on the same bytes.  Targets: results written at >= 300 MB/s, requests read at >= 150.
#
# Usage: bench/io.sh BUILD_DIR        (make bench builds what it needs and runs it)
# The requests:
#   lines100k     cellar gen lines 100000 0.02 1: the full result (V, EV, FV, FE, holes, ...)
#   grid1000      cellar gen grid 1000: 998 001 faces
#   layers60x550  the GIS layers of bench/runbool2.sh (60 x 60 parcels laid as bricks at UTM
#                 coordinates, 550 circles of 64 vertices), their intersection, every field;
#                 -geojson: the same as a GeoJSON FeatureCollection (properties, closed rings)
#   spheres160k   two spheres of 160 000 triangles each, overlapping (their arrangement)
# Exit status: 0, or 1 when a request failed.
set -u
B=${1:-build}
HERE=$(dirname "$0")
BENCH_NAME=benchio
. "$HERE/lib.sh"
need "$B/cellar" "$B/bench/io"
tmp=$(mktemp -d "${TMPDIR:-/tmp}/cellar-benchio.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
trap 'exit 130' INT TERM

"$B/cellar" gen lines 100000 0.02 1 >"$tmp/lines100k.json" || exit 1
"$B/cellar" gen grid 1000 >"$tmp/grid1000.json" || exit 1
python3 - "$tmp" <<'PY' || exit 1
import math, random, sys
tmp = sys.argv[1]
def num(x):
    return repr(float(x))
# GIS layers (as bench/runbool2.sh's layersKxM): bricks of 20 m x 10 m and buffers
x0, y0, K, M = 500000.0, 4400000.0, 60, 550
polys = []
for j in range(K):
    off = 10.0 if j % 2 else 0.0
    for i in range(K):
        x, y = x0 + 20 * i + off, y0 + 10 * j
        polys.append([[[x, y], [x + 20, y], [x + 20, y + 10], [x, y + 10]]])
rnd = random.Random(3)
for k in range(M):
    cx, cy, r = x0 + rnd.uniform(0, 20 * K), y0 + rnd.uniform(0, 10 * K), rnd.uniform(3, 25)
    polys.append([[[cx + r * math.cos(2 * math.pi * t / 64), cy + r * math.sin(2 * math.pi * t / 64)]
                   for t in range(64)]])
ring = lambda p: "[" + ",".join("[%s,%s]" % (num(a), num(b)) for a, b in p) + "]"
text = ",".join("[" + ",".join(ring(r) for r in p) + "]" for p in polys)
l1 = ",".join(str(i) for i in range(K * K))
l2 = ",".join(str(i) for i in range(K * K, K * K + M))
open(tmp + "/layers60x550.json", "w").write(
    '{"kind":"polygons","polygons":[%s],"op":["&",["+",%s],["+",%s]]}' % (text, l1, l2))
# the same layers as a GeoJSON FeatureCollection, as GIS tools write them (rings closed)
feats = ",".join(
    '{"type":"Feature","properties":{"id":%d,"layer":"%s"},"geometry":{"type":"Polygon",'
    '"coordinates":[%s]}}' % (i, "parcels" if i < K * K else "buffers",
                              ",".join(ring(r + [r[0]]) for r in p)) for i, p in enumerate(polys))
open(tmp + "/layers60x550-geojson.json", "w").write(
    '{"kind":"polygons","polygons":{"type":"FeatureCollection","features":[%s]},'
    '"op":["&",["+",%s],["+",%s]]}' % (feats, l1, l2))
# two UV spheres of 400 x 200 quads (160 000 triangles each), the second moved
def sphere(cx, cy, cz, n=400, m=200):
    V = [[cx, cy, cz + 1.0], [cx, cy, cz - 1.0]]
    for j in range(1, m):
        t = math.pi * j / m
        for i in range(n):
            p = 2 * math.pi * i / n
            V.append([cx + math.sin(t) * math.cos(p), cy + math.sin(t) * math.sin(p), cz + math.cos(t)])
    at = lambda j, i: 2 + (j - 1) * n + i % n
    F = []
    for i in range(n):
        F.append([0, at(1, i), at(1, i + 1)])
        F.append([1, at(m - 1, i + 1), at(m - 1, i)])
    for j in range(1, m - 1):
        for i in range(n):
            a, b, c, d = at(j, i), at(j, i + 1), at(j + 1, i + 1), at(j + 1, i)
            F.append([a, d, c])
            F.append([a, c, b])
    return ('{"V":[' + ",".join("[%s,%s,%s]" % tuple(num(c) for c in v) for v in V) + '],"FV":[' +
            ",".join("[%d,%d,%d]" % tuple(f) for f in F) + "]}")
open(tmp + "/spheres160k.json", "w").write(
    '{"kind":"solids","solids":[%s,%s]}' % (sphere(0, 0, 0), sphere(0.31, 0.17, 0.05)))
PY
echo "JSON throughput ($(date -u +%Y-%m-%dT%H:%MZ), $(nproc 2>/dev/null || echo '?') CPUs), MB/s, best of 3:"
echo "  read = the request parsed and checked by a run; intake = the daemon's check and canonical"
echo "  form; write = the result written (streamed to /dev/null); jansson r/w = json_loadb of the"
echo "  request, json_dumps of the result's tree.  Targets: read >= 150, write >= 300."
"$B/bench/io" "$tmp/lines100k.json" "$tmp/grid1000.json" "$tmp/layers60x550.json" \
    "$tmp/layers60x550-geojson.json" "$tmp/spheres160k.json"
