#!/bin/sh
# t_solids.sh — black-box tests of `cellar solids` and of 3D results in the CLI and the daemon:
# usage errors (exit 2), unreadable and invalid files (exit 1, the message names the file, the
# line or the JSON path), a cube as .obj, as .off and on stdin, the same bytes as `cellar run`
# of the request written by hand, --faces, --precision, --format obj and --explode; then
# cellard: POST a solids request, Accept: model/obj on the result (the same OBJ as the CLI's),
# explode in the query, 422 for OBJ of a 2D result, 406 naming model/obj.
# The checks marked CORE need the 3D core (core/arr3.c) to compute the real complex.
# Usage: CELLAR_BIN=build/cellar tests/t_solids.sh   (tests/run.sh sets CELLAR_BIN)
# Prints one line per check ("ok ..." / "FAIL ...") and a last line "N passed, N failed".
set -u
. "$(dirname "$0")/lib.sh"
BIN=${CELLAR_BIN:-build/cellar}
case $BIN in /*) ;; *) [ -e "$BIN" ] && BIN="$(pwd)/$BIN" ;; esac # before the cd below
cd "$(dirname "$0")/.."
PY=${PYTHON:-python3}
# a value of the result in $T/out: json EXPR (python, the result is r)
json() { $PY -c "import json,sys; r=json.load(open('$T/out')); print($1)"; }
errhas() { grep -q -- "$1" "$T/err"; }
count() { grep -c "$1" "$2" | tr -d ' '; }

[ -x "$BIN" ] || give_up "$BIN is not built"

# a unit cube (OBJ, 1-based) and the same moved by (0.5, 0.5, 0.5) (OFF, 0-based)
cat >"$T/cube.obj" <<'EOF'
# a unit cube, outward
o cube
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
vn 0 0 1
f 1//1 4//1 3//1 2//1
f 5 6 7 8
f 1/1 2/1 6/1 5/1
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
EOF
cat >"$T/cube.off" <<'EOF'
OFF
# the same cube
8 6 12
0 0 0
1 0 0
1 1 0
0 1 0
0 0 1
1 0 1
1 1 1
0 1 1
4 0 3 2 1
4 4 5 6 7
4 0 1 5 4
4 1 2 6 5
4 2 3 7 6
4 3 0 4 7
EOF
cat >"$T/half.OFF" <<'EOF'
OFF
8 6 0
0.5 0.5 0.5
1.5 0.5 0.5
1.5 1.5 0.5
0.5 1.5 0.5
0.5 0.5 1.5
1.5 0.5 1.5
1.5 1.5 1.5
0.5 1.5 1.5
4 0 3 2 1
4 4 5 6 7
4 0 1 5 4
4 1 2 6 5
4 2 3 7 6
4 3 0 4 7
EOF
# the cube without its top: an open surface
grep -v '^f 5 6 7 8$' "$T/cube.obj" >"$T/open.obj"
printf 'v 0 0 0\nv 1 0 0\nf 1 2 x\n' >"$T/bad.obj"
CUBE_V='[[0,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1]]'
HALF_V='[[0.5,0.5,0.5],[1.5,0.5,0.5],[1.5,1.5,0.5],[0.5,1.5,0.5],[0.5,0.5,1.5],[1.5,0.5,1.5],[1.5,1.5,1.5],[0.5,1.5,1.5]]'
CUBE_FV='[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,7]]'
NOSTATS='{"fields":["V","EV","FV","FE","holes","CF","CV","exterior"]}'

# --- help and usage
check "--help names solids" sh -c "'$BIN' --help | grep -q 'cellar solids A.obj B.off'"
check "solids without a file exits 2" status 2 "$BIN" solids
check "... and says what it takes" errhas '^cellar: solids takes one or more files'
check "a file of no mesh format exits 2" status 2 "$BIN" solids "$T/cube.obj" "$T/cube.step"
check "... and names it" errhas 'cube.step": expected a .obj, .off, .stl, .ply or .3mf file'
check "--faces with run exits 2" status 2 "$BIN" run "$T/x.json" --faces
check "... and says it is for solids" errhas '^cellar: --faces is for the solids command'
check "--precision with run exits 2" status 2 "$BIN" run "$T/x.json" --precision 0.1
check "--normalize with solids exits 2" status 2 "$BIN" solids "$T/cube.obj" --normalize
check "--precision 0 exits 2" status 2 "$BIN" solids "$T/cube.obj" --precision 0
check "--format step exits 2" status 2 "$BIN" solids "$T/cube.obj" --format step
check "--explode without --format obj or svg exits 2" status 2 "$BIN" solids "$T/cube.obj" --explode 2
check "... and says so" errhas '^cellar: --explode is for --format svg, obj or glb'
check "--width with --format obj exits 2" status 2 "$BIN" solids "$T/cube.obj" --format obj --width 100
check "--explode 0.5 exits 2" status 2 "$BIN" solids "$T/cube.obj" --format obj --explode 0.5
check "--options not an object exits 2" status 2 "$BIN" solids "$T/cube.obj" --options '[1]'
check "--options not JSON exits 2" status 2 "$BIN" solids "$T/cube.obj" --options '{'

# --- unreadable and invalid input: exit 1, nothing on stdout
check "a missing file exits 1" status 1 "$BIN" solids "$T/cube.obj" "$T/missing.off"
check "... and names it" errhas "^cellar: $T/missing.off: No such file"
check "... prints nothing on stdout" test ! -s "$T/out"
mkdir "$T/dir.obj"
check "a directory exits 1" status 1 "$BIN" solids "$T/dir.obj"
check "a malformed OBJ exits 1" status 1 "$BIN" solids "$T/bad.obj"
check "... naming file and line" errhas "^cellar: $T/bad.obj: line 3: malformed vertex reference 'x'"
cp "$T/bad.obj" "$T/bad.off"
check "OBJ text read as OFF exits 1" status 1 "$BIN" solids "$T/bad.off"
check "... naming file and line" errhas "^cellar: $T/bad.off: line 1: not an OFF file"
check "an open surface exits 1" status 1 "$BIN" solids "$T/cube.obj" "$T/open.obj"
check "... with the JSON path and the file" errhas "^cellar: solids\[1\]\.FV\[[0-9]*\]: open surface .*(solids\[1\] is $T/open.obj)$"
check "an unknown option exits 1" status 1 "$BIN" solids "$T/cube.obj" --options '{"colour":1}'
check "... and names it" errhas '^cellar: options.colour: unknown option'
check "malformed OBJ on stdin exits 1" status 1 sh -c "'$BIN' solids - <'$T/bad.obj'"
check "... naming standard input" errhas '^cellar: standard input: line 3'

# --- a cube (CORE)
check "solids cube.obj exits 0" status 0 "$BIN" solids "$T/cube.obj"
cp "$T/out" "$T/cube.out"
check "one line, nothing on stderr" sh -c "test \"\$(wc -l <'$T/out' | tr -d ' ')\" = 1 && test ! -s '$T/err'"
check "CORE: a cube is 8 V, 12 E, 6 F, 1 cell of volume 1" test "$(json 'r["dim"], r["stats"]["V"], r["stats"]["E"], r["stats"]["F"], r["stats"]["C"], float(round(r["stats"]["volumes"][0], 12))')" = "3 8 12 6 1 1.0"
check "the result is valid against result.schema.json" sh -c "$PY tests/validate.py result '$T/out' >/dev/null"
"$BIN" solids "$T/cube.obj" --options "$NOSTATS" >"$T/obj.json"
"$BIN" solids "$T/cube.off" --options "$NOSTATS" >"$T/off.json"
"$BIN" solids - --options "$NOSTATS" <"$T/cube.obj" >"$T/stdin.json"
check "the cube as .off gives the same bytes as .obj" cmp -s "$T/obj.json" "$T/off.json"
check "the cube on stdin gives the same bytes" cmp -s "$T/obj.json" "$T/stdin.json"
printf '{"kind":"solids","solids":[{"V":%s,"FV":%s}],"options":%s}\n' "$CUBE_V" "$CUBE_FV" "$NOSTATS" >"$T/cube.request.json"
"$BIN" run "$T/cube.request.json" >"$T/run.json"
check "cellar solids gives the bytes of cellar run on the request" cmp -s "$T/obj.json" "$T/run.json"

# --- two cubes, the second moved by (0.5, 0.5, 0.5) (CORE)
check "solids cube.obj half.OFF exits 0" status 0 "$BIN" solids "$T/cube.obj" "$T/half.OFF" --threads 2
check "CORE: two cubes are 22 V, 36 E, 18 F, 3 cells" test "$(json 'r["stats"]["V"], r["stats"]["E"], r["stats"]["F"], r["stats"]["C"]')" = "22 36 18 3"
check "CORE: their volumes add up to 1.875" test "$(json 'round(sum(r["stats"]["volumes"]), 12)')" = "1.875"
printf '{"kind":"solids","solids":[{"V":%s,"FV":%s},{"V":%s,"FV":%s}],"options":%s}\n' "$CUBE_V" "$CUBE_FV" "$HALF_V" "$CUBE_FV" "$NOSTATS" >"$T/two.request.json"
"$BIN" solids "$T/cube.obj" "$T/half.OFF" --options "$NOSTATS" >"$T/two.json"
"$BIN" run "$T/two.request.json" >"$T/two.run.json"
check "two cubes: the bytes of cellar run" cmp -s "$T/two.json" "$T/two.run.json"
# a real mesh and a turned copy with an op: the files go straight to the run; the request that
# --format request prints gives the same bytes through `cellar run`
M=tests/data/mesh/real/bunny.off
if [ -f "$M" ]; then
    "$PY" -c "
import math, sys
t = [l.split('#')[0].split() for l in open('$M')]
t = [x for l in t for x in l]
nv, nf = int(t[1]), int(t[2])
V = [[float(x) for x in t[4 + 3 * i:7 + 3 * i]] for i in range(nv)]
c, s = math.cos(0.7), math.sin(0.7)
out = ['OFF', '%d %d 0' % (nv, nf)]
out += ['%.17g %.17g %.17g' % (c * x - s * y + 0.01, s * x + c * y + 0.02, z + 0.003) for x, y, z in V]
i = 4 + 3 * nv
for f in range(nf):
    n = int(t[i])
    out.append(' '.join(t[i:i + n + 1]))
    i += n + 1
open('$T/bunny_rot.off', 'w').write(chr(10).join(out) + chr(10))
"
    "$BIN" solids "$M" "$T/bunny_rot.off" --op intersection --options "$NOSTATS" >"$T/b.direct.json"
    "$BIN" solids "$M" "$T/bunny_rot.off" --op intersection --options "$NOSTATS" --format request >"$T/b.request.json"
    "$BIN" run "$T/b.request.json" >"$T/b.run.json"
    check "a mesh and its turned copy, intersection: the bytes of cellar run on the request" sh -c "test -s '$T/b.direct.json' && cmp -s '$T/b.direct.json' '$T/b.run.json'"
else
    check "tests/data/mesh/real/bunny.off is there" false
fi
"$BIN" --threads 1 solids "$T/cube.obj" "$T/half.OFF" --options "$NOSTATS" >"$T/two.t1.json"
check "--threads 1 gives the same bytes" cmp -s "$T/two.json" "$T/two.t1.json"
check "--faces exits 0" status 0 "$BIN" solids --faces "$T/cube.obj" "$T/half.OFF"
check "CORE: the soup of both cubes' faces is the same complex" test "$(json 'r["stats"]["V"], r["stats"]["E"], r["stats"]["F"], r["stats"]["C"], r["stats"]["input_solids"]')" = "22 36 18 3 1"
check "--precision becomes options.precision" status 0 "$BIN" solids "$T/cube.obj" --precision 0.001
check "... as stats.precision says" test "$(json 'r["stats"]["precision"]')" = "0.001"
check "--precision and --options together" status 0 "$BIN" solids "$T/cube.obj" --precision=0.25 --options '{"fields":["stats"]}'
check "... both apply" test "$(json 'list(r), r["stats"]["precision"]')" = "['dim', 'stats'] 0.25"

# --- OBJ out (CORE: the cells come from the core)
check "--format obj exits 0" status 0 "$BIN" solids "$T/cube.obj" "$T/half.OFF" --format obj
cp "$T/out" "$T/two.obj"
check "OBJ: a comment first" sh -c "head -n 1 '$T/two.obj' | grep -q -E '^# cellar: 3 cells, [0-9]+ triangles of 18 faces, 22 of 22 vertices$'"
check "CORE: OBJ has 22 vertices and 3 groups" test "$(count '^v ' "$T/two.obj") $(count '^g cell' "$T/two.obj")" = "22 3"
check "OBJ: only v, g, f and comment lines" sh -c "! grep -v -E '^(v -?[0-9.e+-]+ -?[0-9.e+-]+ -?[0-9.e+-]+|g cell[0-9]+|f [0-9]+ [0-9]+ [0-9]+|# .*)$' '$T/two.obj'"
"$BIN" run "$T/two.request.json" --format obj >"$T/two.run.obj"
check "cellar run --format obj gives the same OBJ" cmp -s "$T/two.obj" "$T/two.run.obj"
check "--format obj --explode 3 exits 0" status 0 "$BIN" solids "$T/cube.obj" "$T/half.OFF" --format obj --explode 3
cp "$T/out" "$T/two.x3.obj"
check "CORE: exploded, every cell has its own vertices" test "$(count '^v ' "$T/two.x3.obj")" -gt 22
check "exploded, the same triangles" test "$(count '^f ' "$T/two.x3.obj")" = "$(count '^f ' "$T/two.obj")"
# each cell closed and outward: every directed edge has its reverse in the cell, volume > 0
cat >"$T/mesh.py" <<'EOF'
import sys
v, cells = [], {}
g = None
for line in open(sys.argv[1]):
    w = line.split()
    if not w or w[0] == "#": continue
    if w[0] == "v": v.append(tuple(map(float, w[1:])))
    elif w[0] == "g": g = w[1]; cells[g] = []
    elif w[0] == "f": cells[g].append(tuple(int(x) - 1 for x in w[1:]))
bad = 0
for name, tris in cells.items():
    edges = {}
    vol = 0.0
    for a, b, c in tris:
        for p, q in ((a, b), (b, c), (c, a)):
            k = (v[p], v[q]); edges[k] = edges.get(k, 0) + 1
        (x1, y1, z1), (x2, y2, z2), (x3, y3, z3) = v[a], v[b], v[c]
        vol += x1 * (y2 * z3 - z2 * y3) - y1 * (x2 * z3 - z2 * x3) + z1 * (x2 * y3 - y2 * x3)
    if any(n != 1 or edges.get((q, p)) != 1 for (p, q), n in edges.items()) or vol <= 0:
        bad += 1
        print(name, "open, inconsistent or inward", vol / 6)
print(len(cells), "cells,", bad, "bad")
EOF
check "CORE: every cell of the OBJ is closed and outward" sh -c "$PY '$T/mesh.py' '$T/two.obj' | grep -q '^3 cells, 0 bad$'"
check "CORE: so is every exploded cell" sh -c "$PY '$T/mesh.py' '$T/two.x3.obj' | grep -q '^3 cells, 0 bad$'"
echo '{"kind":"lines","lines":[[[0,0],[1,0]],[[1,0],[1,1]],[[1,1],[0,0]]]}' >"$T/tri.json"
check "--format obj of a 2D result exits 1" status 1 "$BIN" run "$T/tri.json" --format obj
check "... and says why" errhas '^cellar: --format obj: dim: expected 3'
check "--format svg of a 3D result exits 1" status 1 "$BIN" run "$T/cube.request.json" --format svg
check "... and says why" errhas '^cellar: --format svg: dim: expected 2'

# --- the daemon: Accept: model/obj
if ! command -v curl >/dev/null 2>&1 || [ ! -x "$(dirname "$BIN")/cellard" ]; then
    fail "the daemon checks need curl and cellard next to $BIN"
    finish
fi
"$(dirname "$BIN")/cellard" --listen 127.0.0.1:0 --db "$T/c.db" 2>"$T/log" &
pid=$!
trap 'kill $pid 2>/dev/null; wait $pid 2>/dev/null; rm -rf "$T"' EXIT INT TERM
port=""
for i in $(seq 300); do # the daemon logs the port it bound (30 s at most: sanitizer builds)
    port=$(sed -n 's/.*"msg":"listening".*"port":\([0-9]*\).*/\1/p' "$T/log" 2>/dev/null | head -n 1)
    [ -n "$port" ] && break
    sleep 0.1
done
if [ -z "$port" ]; then
    fail "cellard did not start: $(head -c 300 "$T/log")"
    finish
fi
U="http://127.0.0.1:$port"
# post FILE: the response headers in $T/h, the body in $T/b, the status printed
post() { curl -s -o "$T/b" -D "$T/h" -w '%{http_code}' -H 'Content-Type: application/json' -H 'Prefer: wait=20' --data-binary "@$1" "$U/v1/jobs"; }
# get PATH ACCEPT: the same for a GET
get() { curl -s -o "$T/b" -D "$T/h" -w '%{http_code}' -H "Accept: $2" "$U$1"; }
hdr() { sed -n "s/^$1: *//Ip" "$T/h" | tr -d '\r' | head -n 1; }

printf '{"kind":"solids","solids":[{"V":%s,"FV":%s},{"V":%s,"FV":%s}]}\n' "$CUBE_V" "$CUBE_FV" "$HALF_V" "$CUBE_FV" >"$T/two.post.json"
check "POST a solids request: 200 (CORE)" test "$(post "$T/two.post.json")" = 200
hash=$(hdr ETag | tr -d '"')
job=$(hdr X-Cellar-Job)
check "... a 3D result" grep -q '^{"dim":3,' "$T/b"
check "GET the result as model/obj: 200" test "$(get "/v1/results/$hash" model/obj)" = 200
check "... Content-Type model/obj" test "$(hdr Content-Type)" = "model/obj"
check "... its own ETag (the result's hash, the format, a digest of the options)" sh -c "echo '$(hdr ETag)' | grep -Eq '^\"$hash-obj-[0-9a-f]{16}\"\$'"
etag1=$(hdr ETag)
check "... Vary: Accept (and Accept-Encoding)" sh -c "echo '$(hdr Vary)' | grep -Eq '^Accept(, Accept-Encoding)?\$'"
check "... the same OBJ as cellar run --format obj" cmp -s "$T/b" "$T/two.run.obj"
check "the job's result as model/obj too" test "$(get "/v1/jobs/$job/result" model/obj)" = 200
check "... the same OBJ" cmp -s "$T/b" "$T/two.run.obj"
check "explode=3 in the query: 200" test "$(get "/v1/results/$hash?explode=3" model/obj)" = 200
check "... the OBJ of cellar --explode 3" cmp -s "$T/b" "$T/two.x3.obj"
check "... and its ETag says so (another tag)" sh -c "echo '$(hdr ETag)' | grep -Eq '^\"$hash-obj-[0-9a-f]{16}\"\$' && test '$(hdr ETag)' != '$etag1'"
check "explode=0 in the query: 422" test "$(get "/v1/results/$hash?explode=0" model/obj)" = 422
check "model/* gives OBJ" sh -c "test \"\$(curl -s -o /dev/null -w '%{content_type}' -H 'Accept: model/*' '$U/v1/results/$hash')\" = model/obj"
check "a 3D result as a picture: 422 naming dim" sh -c "test \"\$(curl -s -o '$T/p' -w '%{http_code}' -H 'Accept: image/svg+xml' '$U/v1/results/$hash')\" = 422 && grep -q '\"path\":\"dim\"' '$T/p'"
check "an Accept we have not: 406" test "$(get "/v1/results/$hash" text/html)" = 406
check "... naming model/obj among the types" grep -q 'model/obj' "$T/b"
check "POST a lines request: 200" test "$(post "$T/tri.json")" = 200
h2=$(hdr ETag | tr -d '"')
check "a 2D result as model/obj: 422" test "$(get "/v1/results/$h2" model/obj)" = 422
check "... the problem names dim" grep -q '"path":"dim"' "$T/b"
printf '{"kind":"solids","solids":[{"V":%s,"FV":%s}]}\n' "$CUBE_V" '[[0,3,2,1],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,7]]' >"$T/open.post.json"
check "POST an open solid: 422 at submit" test "$(post "$T/open.post.json")" = 422
check "... the problem's path names the face" grep -q '"path":"solids\[0\]\.FV\[[0-9]*\]"' "$T/b"
finish
