#!/bin/sh
# t_cgal3d.sh — the 3D arrangement against an independent reference: CGAL's corefinement union
# (tests/ref/cgal_bool) of the same solids (bench/gen3d.py writes both inputs with the same
# doubles).  For random rotated cubes and random tetrahedra at several seeds, and a grid of
# overlapping cubes, the bounded cells' volumes must add up to CGAL's union volume with its
# voids filled (a void the solids enclose is a bounded cell too), within what snapping every
# vertex to the grid can move a volume: precision * area of the union's boundary, plus 1e-9
# relative.  The complex's own invariants are checked by test_arr3; here the CLI's JSON is used.
set -u
. "$(dirname "$0")/lib.sh"
B=${CELLAR_BUILD:-build}
CELLAR=${CELLAR_BIN:-$B/cellar}
CGAL=$B/tests/ref/cgal_bool
GEN="python3 $(dirname "$0")/../bench/gen3d.py"

if [ ! -x "$CGAL" ]; then
    fail "cgal_bool is built ($CGAL)"
    finish
fi

# compare NAME GENARGS...: runs both and compares
compare() {
    name=$1
    shift
    rm -rf "$T/off" && mkdir -p "$T/off"
    # shellcheck disable=SC2086
    $GEN "$@" --json "$T/req.json" --off "$T/off" --options '{"fields":["stats","membership","result"]}' 2>/dev/null ||
        { fail "$name: gen3d"; return; }
    if ! "$CELLAR" run "$T/req.json" >"$T/ours.json" 2>"$T/err"; then
        fail "$name: cellar run ($(head -c 200 "$T/err"))"
        return
    fi
    if ! "$CGAL" --op union "$T"/off/*.off >"$T/cgal.json" 2>"$T/err"; then
        fail "$name: cgal_bool ($(head -c 200 "$T/err"))"
        return
    fi
    python3 - "$T/ours.json" "$T/cgal.json" "$name" <<'PY'
import json, sys
ours = json.load(open(sys.argv[1]))
cgal = json.loads(open(sys.argv[2]).read().strip().splitlines()[-1])
st = ours["stats"]
vols = st["volumes"]
s = sum(vols)
ref = cgal["filled_volume"]
tol = st["precision"] * cgal["area"] + 1e-9 * abs(ref)
ok = abs(s - ref) <= tol and all(v > 0 for v in vols)
print("  %s: cells %d, sum %.15g, CGAL %.15g, diff %.3g, tol %.3g" % (
    sys.argv[3], len(vols), s, ref, abs(s - ref), tol))
sys.exit(0 if ok else 1)
PY
    check "$name: cell volumes add up to CGAL's union" test $? -eq 0
}

# compare_op NAME OP GENARGS...: the Boolean result's volume against CGAL's (1e-9 relative, or
# the snapping bound when that is larger), and its boundary closed (every edge's signed count
# over the result's FE rows is 0) and enclosing its volume (cones of its FV/holes cycles).
compare_op() {
    name=$1
    op=$2
    shift 2
    rm -rf "$T/off" && mkdir -p "$T/off"
    # shellcheck disable=SC2086
    $GEN "$@" --off "$T/off" 2>/dev/null || { fail "$name: gen3d"; return; }
    if ! "$CELLAR" solids "$T"/off/*.off --op "$op" >"$T/ours.json" 2>"$T/err"; then
        fail "$name: cellar solids --op $op ($(head -c 200 "$T/err"))"
        return
    fi
    if ! "$CGAL" --op "$op" "$T"/off/*.off >"$T/cgal.json" 2>"$T/err"; then
        fail "$name: cgal_bool --op $op ($(head -c 200 "$T/err"))"
        return
    fi
    python3 - "$T/ours.json" "$T/cgal.json" "$name $op" <<'PY'
import json, sys
from collections import Counter
ours = json.load(open(sys.argv[1]))
cgal = json.loads(open(sys.argv[2]).read().strip().splitlines()[-1])
r, V = ours["result"], ours["V"]
vol, ref = r["volume"], cgal["volume"]
tol = max(1e-9 * abs(ref), ours["stats"]["precision"] * cgal["area"]) + 1e-15
acc = Counter()
for row in r["FE"]:
    for e in row:
        acc[abs(e)] += 1 if e > 0 else -1
closed = all(v == 0 for v in acc.values())
def cone(cyc):
    s, p0 = 0.0, V[cyc[0]]
    for i in range(1, len(cyc) - 1):
        a, b = V[cyc[i]], V[cyc[i + 1]]
        s += (p0[0] * (a[1] * b[2] - a[2] * b[1]) - p0[1] * (a[0] * b[2] - a[2] * b[0])
              + p0[2] * (a[0] * b[1] - a[1] * b[0]))
    return s / 6
enc = sum(cone(c) for c in r["FV"]) + sum(cone(c) for hs in r["holes"].values() for c in hs)
ok = abs(vol - ref) <= tol and closed and abs(enc - vol) <= 1e-9 * (abs(vol) + 1)
print("  %s: %d cells, %d faces, volume %.15g, CGAL %.15g, rel %.2g, closed %s, encloses %.15g"
      % (sys.argv[3], len(r["cells"]), len(r["faces"]), vol, ref,
         abs(vol - ref) / max(abs(ref), 1e-300), closed, enc))
sys.exit(0 if ok else 1)
PY
    check "$name: $op as CGAL's, closed and outward" test $? -eq 0
}

for seed in 1 2 3; do
    for op in union intersection difference; do
        compare_op "cubes 3 seed $seed" "$op" cubes 3 "$seed" --size 0.9
        compare_op "tets 3 seed $seed" "$op" tets 3 "$seed" --size 1.5
    done
done

for seed in 1 2 3 4 5; do
    compare "cubes 6 seed $seed" cubes 6 "$seed"
done
for seed in 11 12; do
    compare "cubes 30 seed $seed" cubes 30 "$seed"
done
for seed in 1 2 3; do
    compare "tets 12 seed $seed" tets 12 "$seed"
done
compare "grid 3" grid 3
finish
