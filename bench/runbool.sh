#!/bin/sh
# bench/runbool.sh — the 3D Boolean benchmark: cellar's union of solids (arrangement + Boolean)
# beside CGAL's (corefinement) and Manifold's (npm manifold-3d, bench/manifold_bool.mjs).
#
# Usage: bench/runbool.sh BUILD_DIR    (make bench builds what it needs and runs it)
# Needs BUILD_DIR/cellar, BUILD_DIR/tests/ref/cgal_bool, python3 (bench/gen3d.py) and
# /usr/bin/time (GNU); Manifold needs node and bench/node_modules/manifold-3d (make bench runs
# `npm ci --prefix bench` when npm is there) and is skipped ("manifold: not installed") without.
# BENCHBOOL_CASES="cubes100 cubes1000 bunny.rot" picks the cases; BENCHBOOL_TIMEOUT (seconds,
# default 900) stops a program that runs longer.
#
# Cases: cubesN (gen3d.py cubes N 1: N random rotated cubes), grid10 (gen3d.py grid 10: 1000
# axis-aligned cubes overlapping by half, every face on others) and MESH.SCENE for every mesh of
# tests/data/mesh/real but cow (whose surface passes through itself: every program refuses it)
# and SCENE rot, box, shell (gen3d.py mesh: the mesh with its turned and moved copy, with a box
# through it, with its copy scaled by 0.8 inside it).
# Each case is generated once by bench/gen3d.py as one OFF file per solid; each program reads
# the same files and runs once under /usr/bin/time:
#   ours      cellar solids FILES --op union --options '{"fields":["stats","membership","result"]}' (result.volume)
#   CGAL      cgal_bool --op union FILES (Epeck, PMP corefinement, pairwise union tree; volume)
#   manifold  node manifold_bool.mjs --op union FILES (Manifold.union(array), double coordinates)
# One row per case: wall time (s, the whole process: start-up and reading included) and peak RSS
# (MiB) of each, the speed-ups (CGAL s / ours s, manifold s / ours s), then the union volumes
# (cavities subtracted), their relative difference to CGAL's and whether they agree:
#   yes   within 1e-9 relative;
#   snap  not within 1e-9, but within precision * area (cellar's grid step times the area of
#         CGAL's union boundary: how far snapping every vertex to the grid may move the volume);
#   NO    neither.
# A program that fails or times out shows "failed" / "timeout".  Exit status: 0, or 1 when ours
# or CGAL failed or our volume disagrees with CGAL's (Manifold's failures or disagreements are
# reported but do not change it: it is a third-party reference and optional).
set -u

B=${1:-build}
REAL=$(dirname "$0")/../tests/data/mesh/real
real_cases() {
    for m in "$REAL"/*.off; do
        n=$(basename "$m" .off)
        [ "$n" = cow ] && continue
        printf '%s.rot %s.box %s.shell ' "$n" "$n" "$n"
    done
}
CASES=${BENCHBOOL_CASES:-"cubes100 cubes1000 grid10 $(real_cases)"}
LIMIT=${BENCHBOOL_TIMEOUT:-900}
REPEAT=${BENCHBOOL_REPEAT:-3}
OPTS='{"fields":["stats","membership","result"]}'
HERE=$(dirname "$0")
OURS=$B/cellar
CGAL=$B/tests/ref/cgal_bool
MF=$HERE/manifold_bool.mjs
GEN=$HERE/gen3d.py
TIME=/usr/bin/time

BENCH_NAME=benchbool
. "$HERE/lib.sh"
need "$OURS" "$CGAL" "$TIME"

# Manifold: node and the module (manifold_bool.mjs exits 2 when it cannot load manifold-3d,
# 1 for the usage message it prints without files).
have_mf=0
if command -v node >/dev/null 2>&1; then
    node "$MF" >/dev/null 2>&1
    [ $? -eq 1 ] && have_mf=1
fi

tmp=$(mktemp -d "${TMPDIR:-/tmp}/cellar-benchbool.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
trap 'exit 130' INT TERM

gen_args() {
    case $1 in
    cubes10) echo "cubes 10 1" ;;
    cubes100) echo "cubes 100 1" ;;
    cubes1000) echo "cubes 1000 1" ;;
    tets100) echo "tets 100 1" ;;
    grid10) echo "grid 10" ;;
    *.rot | *.box | *.shell)
        [ -f "$REAL/${1%.*}.off" ] || return 1
        echo "mesh $REAL/${1%.*}.off ${1##*.}"
        ;;
    *) return 1 ;;
    esac
}


# ourvol FILE: result.volume of cellar's output (the "volume" key after "result").
ourvol() {
    sed 's/.*"result": *{//' "$1" | grep -o '"volume": *-\{0,1\}[0-9][0-9.eE+-]*' | head -n 1 |
        sed 's/.*: *//'
}

# compare V REF PREC AREA: sets REL (|V - REF| / |REF|) and AGREE (yes / snap / NO / -).
compare() {
    REL=- AGREE=-
    [ -n "$1" ] && [ -n "$2" ] || return 0
    REL=$(awk -v o="$1" -v c="$2" 'BEGIN { d = o - c; if (d < 0) d = -d
        printf "%.1e", c != 0 ? d / (c < 0 ? -c : c) : d }')
    AGREE=$(awk -v o="$1" -v c="$2" -v h="${3:-0}" -v a="${4:-0}" 'BEGIN {
        d = o - c; if (d < 0) d = -d; m = c < 0 ? -c : c
        if (d <= 1e-9 * m) print "yes"; else if (d <= h * a) print "snap"; else print "NO" }')
}

row() {
    printf '%-22s %7s %8s %7s %8s %7s %8s %6s %6s  %-22s %-22s %-22s %7s %4s %7s %4s\n' "$@"
}

echo "3D Boolean benchmark: union ($(date -u +%Y-%m-%dT%H:%MZ), $(nproc 2>/dev/null || echo '?') CPUs)"
echo "  ours = $OURS solids --op union (fields: stats);"
echo "  CGAL = $CGAL --op union (Epeck, corefinement, pairwise union tree);"
echo "  mf = node bench/manifold_bool.mjs (manifold-3d"
mfver=$(sed -n 's/^ *"version": *"\([^"]*\)".*/\1/p' "$HERE/node_modules/manifold-3d/package.json" \
    2>/dev/null | head -n 1)
[ $have_mf -eq 1 ] || mfver="not installed"
echo "  ${mfver:-?}, WASM, Manifold.union of all, double coordinates)."
echo "  Inputs: bench/gen3d.py cubes N 1 (N random rotated cubes), grid 10 and, for MESH.SCENE,"
echo "  gen3d.py mesh tests/data/mesh/real/MESH.off SCENE; one OFF file per solid."
echo "  s = wall seconds of the whole process (start-up, reading included); MiB = peak RSS;"
echo "  xC = CGAL s / ours s, xM = mf s / ours s; volumes of the union (cavities subtracted);"
echo "  rel = |v - CGAL's| / CGAL's; agree: yes within 1e-9 relative, snap within precision *"
echo "  CGAL's union area, else NO."
[ $have_mf -eq 1 ] || echo "  manifold: not installed (node + npm ci --prefix bench); its columns show -"
row case "ours s" "ours MiB" "CGAL s" "CGAL MiB" "mf s" "mf MiB" xC xM "ours volume" \
    "CGAL volume" "mf volume" "rel" agr "mf rel" agr
inner=""
status=0
for c in $CASES; do
    if ! args=$(gen_args "$c"); then
        echo "benchbool: unknown case '$c'" >&2
        status=1
        continue
    fi
    # shellcheck disable=SC2086 # args is a word list
    if ! python3 "$GEN" $args --off "$tmp/$c.off" --json /dev/null 2>"$tmp/$c.info"; then
        echo "benchbool: gen3d.py $args failed:" >&2
        cat "$tmp/$c.info" >&2
        status=1
        continue
    fi
    files=$(ls "$tmp/$c.off"/*.off)
    # shellcheck disable=SC2086 # one argument per OFF file
    if timed "cellar ($c)" "$tmp/$c.ours" "$OURS" solids $files --op union --options "$OPTS"; then
        os=$T_S om=$T_MIB
    else
        os=$T_S om=- status=1
    fi
    # shellcheck disable=SC2086
    if timed "cgal_bool ($c)" "$tmp/$c.cgal" "$CGAL" --op union $files; then
        cs=$T_S cm=$T_MIB
    else
        cs=$T_S cm=- status=1
    fi
    ms=- mm=-
    if [ $have_mf -eq 1 ]; then
        # shellcheck disable=SC2086
        if timed "manifold ($c)" "$tmp/$c.mf" node "$MF" --op union $files; then
            ms=$T_S mm=$T_MIB
        else
            ms=$T_S mm=-
        fi
    fi
    ov='' oprec='' oms='' cv='' ca='' cms='' mv='' mms=''
    if [ "$om" != - ]; then
        ov=$(ourvol "$tmp/$c.ours") oprec=$(num precision "$tmp/$c.ours")
        oms=$(num total "$tmp/$c.ours")
        if [ -z "$ov" ]; then
            echo "benchbool: cellar ($c) printed no result.volume:" >&2
            head -c 400 "$tmp/$c.ours" >&2
            echo >&2
            ov=failed status=1
        fi
    fi
    if [ "$cm" != - ]; then
        cv=$(num volume "$tmp/$c.cgal") ca=$(num area "$tmp/$c.cgal") cms=$(num ms "$tmp/$c.cgal")
    fi
    if [ "$mm" != - ]; then
        mv=$(num volume "$tmp/$c.mf") mms=$(num ms "$tmp/$c.mf")
    fi
    [ "$ov" = failed ] && ov=''
    compare "$ov" "$cv" "$oprec" "$ca"
    orel=$REL oagree=$AGREE
    [ "$oagree" != NO ] || status=1
    compare "$mv" "$cv" "$oprec" "$ca"
    mrel=$REL magree=$AGREE
    [ $have_mf -eq 1 ] || ms=- mm=- mrel=- magree=-
    row "$c" "$os" "$om" "$cs" "$cm" "$ms" "$mm" "$(speed "$cs" "$os")" "$(speed "$ms" "$os")" \
        "${ov:--}" "${cv:--}" "${mv:--}" "$orel" "$oagree" "$mrel" "$magree"
    inner="$inner$(awk -v c="$c" -v o="$oms" -v k="$cms" -v m="$mms" -v p="$oprec" '
        function f(x) { return x == "" ? "-" : sprintf("%.1f", x) }
        function r(a, b) { return a == "" || b == "" || a + 0 <= 0 ? "-" : sprintf("%.2f", b / a) }
        BEGIN { printf "%-22s %12s %12s %12s %8s %14s", c, f(o), f(k), f(m), r(o, k),
                p == "" ? "-" : p }')
"
done
echo
echo "In-program times, ms (ours: stats.ms.total, the core from the solids read and checked to"
echo "the complex: snapping, planes, cuts, faces, cells, Boolean; CGAL: the unions only, after"
echo "its reading, checks and triangulation; manifold: Manifold.union and its evaluation), xC ="
echo "CGAL ms / ours ms, and our grid step:"
printf '%-22s %12s %12s %12s %8s %14s\n' case ours CGAL manifold xC precision
printf '%s' "$inner"
exit $status
