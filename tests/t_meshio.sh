#!/bin/sh
# t_meshio.sh — meshes out and in through the command-line tool, each written file opened by an
# independent reader: --format stl by Python's struct and 3mf by zipfile + xml.etree
# (tests/mesh_check.py), glb by three.js's GLTFLoader (tests/glb_check.mjs: one mesh per cell,
# the Boolean's result its own node, the vertex and triangle counts); then read back by
# `cellar solids` (STL, OFF, 3MF written, a PLY) to the same volume and cells; a bad file named
# in the error.  Counts of triangles and volumes come from the result JSON (mesh_check.py count).
set -u
cd "$(dirname "$0")/.." || exit 1
. tests/lib.sh
export CELLAR_BUILD="${CELLAR_BUILD:-build}"
C="${CELLAR_BIN:-$CELLAR_BUILD/cellar}"
[ -x "$C" ] || give_up "$C is not built"
need_python "zipfile, xml.etree.ElementTree, struct, json" "python3"
command -v node >/dev/null 2>&1 || give_up "node is missing (make deps)"
[ -f web/node_modules/three/examples/jsm/loaders/GLTFLoader.js ] ||
    give_up "web/node_modules/three is missing (npm ci in web/, make builds it)"
A=examples/box.obj
B=examples/pyramid.obj

sub() { # sub NAME CMD...: runs a checker, tallies its lines (a crash is a failure)
    name=$1
    shift
    "$@" >"$T/sub.out" 2>"$T/sub.err"
    rc=$?
    tally_file "$T/sub.out"
    grep -q -E '^[0-9]+ passed, [0-9]+ failed' "$T/sub.out" ||
        { tail -n 5 "$T/sub.err"; fail "$name: exited $rc without a summary"; }
}

"$C" solids $A $B --quiet >"$T/cells.json" || give_up "cellar solids failed"
"$C" solids $A $B --op union --quiet >"$T/union.json" || give_up "cellar solids --op failed"
set -- $($PY tests/mesh_check.py count "$T/union.json" result)
UT=$1 UV=$3
set -- $($PY tests/mesh_check.py count "$T/cells.json" cells)
CT=$1 CN=$2 CV=$3

# STL: a Boolean's result solid; of the arrangement every cell's triangles
"$C" solids $A $B --op union --quiet --format stl >"$T/union.stl"
sub stl-union $PY tests/mesh_check.py stl "$T/union.stl" "$UT" "$UV"
"$C" solids $A $B --quiet --format stl >"$T/cells.stl"
sub stl-cells $PY tests/mesh_check.py stl "$T/cells.stl" "$CT" "$CV"

# 3MF: one object per cell; of a Boolean the result
"$C" solids $A $B --quiet --format 3mf >"$T/cells.3mf"
sub 3mf-cells $PY tests/mesh_check.py 3mf "$T/cells.3mf" "$CN" "$CV"
"$C" solids $A $B --op union --quiet --format 3mf >"$T/union.3mf"
sub 3mf-union $PY tests/mesh_check.py 3mf "$T/union.3mf" 1 "$UV"

# glb: a node per cell, and the result's
"$C" solids $A $B --op union --quiet --format glb >"$T/union.glb"
sub glb-union node tests/glb_check.mjs "$T/union.json" "$T/union.glb"
"$C" solids $A $B --quiet --format glb --explode 1.5 >"$T/cells.glb"
sub glb-cells node tests/glb_check.mjs "$T/cells.json" "$T/cells.glb" exploded

# read back: the union's STL, OFF and 3MF are the union solid again; the cells' 3MF the cells
volume_of() { $PY -c "import json,sys; r=json.load(open(sys.argv[1])); print(r['result']['volume'])" "$1"; }
cells_of() { $PY -c "import json,sys; print(len(json.load(open(sys.argv[1]))['CF']))" "$1"; }
same() { $PY -c "import sys; a,b=float(sys.argv[1]),float(sys.argv[2]); sys.exit(abs(a-b)>1e-6*max(1,abs(b)))" "$1" "$2"; }
"$C" solids $A $B --op union --quiet --format off >"$T/union.off"
for f in union.stl union.off union.3mf; do
    if "$C" solids "$T/$f" --op union --quiet >"$T/back.json" 2>"$T/err" &&
        v=$(volume_of "$T/back.json") && same "$v" "$UV"; then
        pass "read back $f: volume $v"
    else
        fail "read back $f: $(cat "$T/err") volume ${v:-?}, want $UV"
    fi
done
if "$C" solids "$T/cells.3mf" --quiet >"$T/back.json" 2>"$T/err" &&
    n=$(cells_of "$T/back.json") && [ "$n" = "$CN" ]; then
    pass "read back cells.3mf: $n cells"
else
    fail "read back cells.3mf: $(cat "$T/err") ${n:-?} cells, want $CN"
fi

# a PLY (ascii, and binary little-endian made by Python's struct) of the box, a 3MF, an STL
cat >"$T/box.ply" <<'PLY'
ply
format ascii 1.0
element vertex 8
property float x
property float y
property float z
element face 6
property list uchar int vertex_indices
end_header
0 0 0
2 0 0
2 2 0
0 2 0
0 0 2
2 0 2
2 2 2
0 2 2
4 0 3 2 1
4 4 5 6 7
4 0 1 5 4
4 1 2 6 5
4 2 3 7 6
4 3 0 4 7
PLY
$PY - "$T/box.ply" "$T/boxb.ply" <<'PYEOF'
import struct, sys
lines = open(sys.argv[1]).read().split("\n")
body = lines[9:]
head = "\n".join(lines[:9]).replace("ascii", "binary_little_endian") + "\n"
out = head.encode()
for l in body[:8]:
    out += struct.pack("<3f", *map(float, l.split()))
for l in body[8:14]:
    v = list(map(int, l.split()))
    out += struct.pack("<B4i", *v)
open(sys.argv[2], "wb").write(out)
PYEOF
for f in box.ply boxb.ply; do
    if "$C" solids "$T/$f" $B --op union --quiet >"$T/back.json" 2>"$T/err" &&
        v=$(volume_of "$T/back.json") && same "$v" "$UV"; then
        pass "$f with the pyramid: union volume $v"
    else
        fail "$f with the pyramid: $(cat "$T/err") volume ${v:-?}, want $UV"
    fi
done
# the CLI reads every format at once, in order
if "$C" solids "$T/box.ply" "$T/union.stl" "$T/cells.3mf" $A "$T/union.off" --quiet \
    --format request >"$T/req.json" 2>"$T/err" &&
    n=$($PY -c "import json,sys; print(len(json.load(open(sys.argv[1]))['solids']))" "$T/req.json") &&
    [ "$n" = $((1 + 1 + CN + 1 + 1)) ]; then
    pass "ply stl 3mf obj off in one request: $n solids"
else
    fail "ply stl 3mf obj off in one request: $(cat "$T/err") ${n:-?} solids"
fi

# a result's 3MF is the same bytes in every time zone (the daemon's strong ETag promises it)
TZ=UTC "$C" solids "$A" "$B" --op union --format 3mf --quiet >"$T/utc.3mf" 2>/dev/null
TZ=Pacific/Kiritimati "$C" solids "$A" "$B" --op union --format 3mf --quiet >"$T/kir.3mf" 2>/dev/null
check "3mf: the same bytes in UTC and UTC+14" sh -c "[ -s '$T/utc.3mf' ] && cmp -s '$T/utc.3mf' '$T/kir.3mf'"

# zip bombs: a 3MF whose model inflates to 300 MiB (306 KB of zip) is refused by the size its
# directory declares, before inflating (under 100 MB of memory); one whose directory lies (says
# 1 000 bytes) is refused when inflating passes the limit of 256 MiB (under 300 MB)
$PY - "$T" <<'PY'
import struct, sys, zipfile
d = sys.argv[1]
with zipfile.ZipFile(d + "/bomb.3mf", "w", zipfile.ZIP_DEFLATED) as z:
    with z.open("3D/3dmodel.model", "w", force_zip64=True) as f:
        f.write(b'<?xml version="1.0"?><model xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02"><!--')
        for _ in range(300):
            f.write(b" " * (1 << 20))
        f.write(b"--></model>")
# the same, its sizes in the directory and the local header changed to 1 000 bytes
with zipfile.ZipFile(d + "/liar.3mf", "w", zipfile.ZIP_DEFLATED) as z:
    z.writestr("3D/3dmodel.model", b'<?xml version="1.0"?><model><!--' + b" " * (300 << 20) + b"--></model>")
b = bytearray(open(d + "/liar.3mf", "rb").read())
struct.pack_into("<I", b, 22, 1000)  # the local header's uncompressed size
cd = b.rfind(b"PK\x01\x02")
struct.pack_into("<I", b, cd + 24, 1000)  # the directory's
open(d + "/liar.3mf", "wb").write(bytes(b))
PY
for f in bomb:102400 liar:307200; do
    most=${f#*:}
    f=${f%:*}
    # under the sanitizers memory is theirs too (shadow, quarantine of every realloc's old
    # block): the refusal is checked, the bound is not
    [ "${CELLAR_SANITIZED:-0}" = 1 ] && most=99999999
    /usr/bin/time -f %M -o "$T/$f.mem" "$C" solids "$T/$f.3mf" --quiet >/dev/null 2>"$T/$f.err"
    rc=$?
    kb=$(tail -n 1 "$T/$f.mem")
    if [ "$rc" -eq 1 ] && grep -q "$f.3mf: 3D/3dmodel.model: inflates to more than 268435456 bytes" "$T/$f.err" &&
        [ "$kb" -lt "$most" ]; then
        pass "$f.3mf refused in $kb KB: $(head -c 160 "$T/$f.err")"
    else
        fail "$f.3mf: exit $rc, $kb KB: $(head -c 300 "$T/$f.err")"
    fi
done

# a bad file: the message names it and where
printf 'solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0\n' >"$T/bad.stl"
if status 1 "$C" solids "$T/bad.stl" --quiet && grep -q "bad.stl: line 5: expected a finite number" "$T/err"; then
    pass "bad.stl named: $(cat "$T/err")"
else
    fail "bad.stl: $(cat "$T/err")"
fi
if status 2 "$C" solids "$T/x.step" --quiet && grep -q ".stl, .ply or .3mf" "$T/err"; then
    pass "x.step refused as a usage error"
else
    fail "x.step: $(cat "$T/err")"
fi
finish
