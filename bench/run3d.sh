#!/bin/sh
# bench/run3d.sh — the 3D benchmark: cellar's arrangement of solids beside CGAL's union
# (corefinement) of the same solids.
#
# Usage: bench/run3d.sh BUILD_DIR      (make bench builds what it needs and runs it)
# Needs BUILD_DIR/cellar, BUILD_DIR/tests/ref/cgal_bool, python3 (bench/gen3d.py) and
# /usr/bin/time (GNU).  BENCH3D_CASES="cubes10 grid10 ..." restricts the cases;
# BENCH3D_TIMEOUT (seconds, default 900) stops a program that runs longer.
#
# Each case is generated once by bench/gen3d.py, both as a cellar request (with
# "options": {"fields": ["stats"]}, so cellar prints its counts and the bounded cells' volumes,
# not the complex) and as one OFF file per solid, with the same doubles.  Each program runs once
# under /usr/bin/time; one row per case: wall time and peak RSS of each, the speed-up over CGAL,
# cellar's bounded cells, the triangles and cavities of CGAL's union, the sum of cellar's cell
# volumes and CGAL's union volume with its cavities filled (filled_volume: a void that the solids
# enclose is a bounded cell too: 4 random cubes can enclose one), their relative difference and
# whether they agree:
#   yes   within 1e-9 relative;
#   snap  not within 1e-9, but within precision * area (cellar's grid step times the area of
#         the union's boundary: how far snapping every vertex to the grid may move the volume);
#   NO    neither (or, for grid, a cell count other than the closed form of gen3d.py).
# A program that fails or times out shows "failed" / "timeout" in its columns; the other runs.
# Exit status: 0, or 1 when a program failed or the volumes disagree (the table is printed all
# the same).
set -u

B=${1:-build}
CASES=${BENCH3D_CASES:-"cubes10 cubes100 cubes1000 grid10"}
LIMIT=${BENCH3D_TIMEOUT:-900}
OPTS='{"fields":["stats"]}'
OURS=$B/cellar
CGAL=$B/tests/ref/cgal_bool
GEN=$(dirname "$0")/gen3d.py
TIME=/usr/bin/time

for p in "$OURS" "$CGAL" "$TIME"; do
    if [ ! -x "$p" ]; then
        echo "bench3d: $p is missing (make bench builds it)" >&2
        exit 1
    fi
done

tmp=$(mktemp -d "${TMPDIR:-/tmp}/cellar-bench3d.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
trap 'exit 130' INT TERM

# gen_args CASE: the gen3d.py arguments of a case.
gen_args() {
    case $1 in
    cubes10) echo "cubes 10 1" ;;
    cubes100) echo "cubes 100 1" ;;
    cubes1000) echo "cubes 1000 1" ;;
    grid10) echo "grid 10" ;;
    tets100) echo "tets 100 1" ;;
    *) return 1 ;;
    esac
}

# timed NAME OUT CMD...: runs CMD with stdout to OUT under /usr/bin/time and the time limit;
# sets T_S (wall s) and T_MIB (peak RSS), or T_S=failed / timeout.
timed() {
    name=$1
    out=$2
    shift 2
    "$TIME" -f '%e %M' -o "$out.time" timeout "$LIMIT" "$@" >"$out" 2>"$out.err"
    rc=$?
    T_MIB=-
    if [ "$rc" -eq 124 ]; then
        echo "bench3d: $name timed out after $LIMIT s" >&2
        T_S=timeout
        return 1
    fi
    if [ "$rc" -ne 0 ]; then
        echo "bench3d: $name failed (exit $rc):" >&2
        head -c 600 "$out.err" >&2
        echo >&2
        T_S=failed
        return 1
    fi
    T_S=$(tail -n 1 "$out.time" | awk '{ print $1 }')
    T_MIB=$(tail -n 1 "$out.time" | awk '{ printf "%.1f", $2 / 1024 }')
}

# num KEY FILE: the first number stored under "KEY" in FILE (empty if none).
num() {
    grep -o "\"$1\": *-\{0,1\}[0-9][0-9.eE+-]*" "$2" | head -n 1 | sed 's/.*: *//'
}

# volsum FILE: the sum of the numbers of "volumes":[...] in FILE (empty if none).
volsum() {
    grep -o '"volumes": *\[[^]]*\]' "$1" | head -n 1 | sed 's/.*\[//; s/\]//' | tr ',' '\n' |
        awk 'NF { s += $1; n++ } END { if (n) printf "%.17g", s; else if (NR) print 0 }'
}

row() {
    printf '%-10s %8s %8s %8s %8s %7s %8s %8s %4s  %-20s %-20s %8s  %s\n' "$@"
}

echo "3D benchmark ($(date -u +%Y-%m-%dT%H:%MZ), $(nproc 2>/dev/null || echo '?') CPUs)"
echo "  ours = $OURS run (fields: stats); CGAL = $CGAL --op union"
echo "  (Epeck, PMP corefinement, pairwise union tree).  Inputs: bench/gen3d.py (cubesN: cubes N 1,"
echo "  N random rotated cubes; grid10: 10x10x10 unit cubes overlapping by half, union 5.5^3,"
echo "  1331 cells)."
echo "  s = wall seconds of the whole process (reading included); MiB = peak RSS;"
echo "  x CGAL = CGAL s / ours s; cells = our bounded cells; tris, cav = triangles, cavities of"
echo "  CGAL's union; volumes: the sum of our cells' and CGAL's union's with its cavities filled"
echo "  (a void enclosed by the solids is a bounded cell too); rel = |difference| / CGAL's;"
echo "  agree: yes within 1e-9 relative, snap within precision * union area, else NO."
row case "ours s" "ours MiB" "CGAL s" "CGAL MiB" "x CGAL" cells tris cav "ours volume" \
    "CGAL volume" rel agree
inner=""
status=0
for c in $CASES; do
    if ! args=$(gen_args "$c"); then
        echo "bench3d: unknown case '$c'" >&2
        status=1
        continue
    fi
    req=$tmp/$c.json
    # shellcheck disable=SC2086 # args is a word list
    if ! python3 "$GEN" $args --json "$req" --off "$tmp/$c.off" --options "$OPTS" --info \
        2>"$tmp/$c.info"; then
        echo "bench3d: gen3d.py $args failed:" >&2
        cat "$tmp/$c.info" >&2
        row "$c" - - - - - - - - "(no input)" - - NO
        status=1
        continue
    fi
    expect_cells=$(num cells "$tmp/$c.info")
    fail=0
    if timed "cellar ($c)" "$tmp/$c.ours" "$OURS" run "$req"; then
        os=$T_S om=$T_MIB
    else
        os=$T_S om=- fail=1
    fi
    # shellcheck disable=SC2046 # one argument per OFF file
    if timed "cgal_bool ($c)" "$tmp/$c.cgal" "$CGAL" --op union $(ls "$tmp/$c.off"/*.off); then
        cs=$T_S cm=$T_MIB
    else
        cs=$T_S cm=- fail=1
    fi
    oC='' ov='' oprec='' oms='' cv='' ca='' cf='' ch='' cms=''
    if [ "$fail" -eq 0 ] || [ "$om" != - ]; then
        oC=$(num C "$tmp/$c.ours") ov=$(volsum "$tmp/$c.ours")
        oprec=$(num precision "$tmp/$c.ours") oms=$(num total "$tmp/$c.ours")
        if [ -z "$oC" ] || [ -z "$ov" ]; then
            echo "bench3d: cellar ($c) printed no stats C, volumes:" >&2
            head -c 400 "$tmp/$c.ours" >&2
            echo >&2
            fail=1
        fi
    fi
    if [ "$cm" != - ]; then
        cv=$(num filled_volume "$tmp/$c.cgal") ca=$(num area "$tmp/$c.cgal")
        cf=$(num faces "$tmp/$c.cgal") ch=$(num cavities "$tmp/$c.cgal")
        cms=$(num ms "$tmp/$c.cgal")
    fi
    speed=$(awk -v c="$cs" -v o="$os" 'BEGIN {
        if (c !~ /^[0-9.]+$/ || o !~ /^[0-9.]+$/ || c + 0 < 0.01 || o + 0 < 0.01) print "-"
        else printf "%.1f", c / o }')
    rel=- agree=-
    if [ -n "$ov" ] && [ -n "$cv" ]; then
        rel=$(awk -v o="$ov" -v c="$cv" 'BEGIN { d = o - c; if (d < 0) d = -d
            printf "%.1e", c != 0 ? d / (c < 0 ? -c : c) : d }')
        agree=$(awk -v o="$ov" -v c="$cv" -v h="${oprec:-0}" -v a="${ca:-0}" 'BEGIN {
            d = o - c; if (d < 0) d = -d; m = c < 0 ? -c : c
            if (d <= 1e-9 * m) print "yes"; else if (d <= h * a) print "snap"; else print "NO" }')
        if [ -n "$expect_cells" ] && [ "$oC" != "$expect_cells" ]; then
            echo "bench3d: $c: $oC bounded cells, expected $expect_cells" >&2
            agree=NO
        fi
        [ "$agree" != NO ] || fail=1
    fi
    [ "$fail" -eq 0 ] || status=1
    row "$c" "$os" "$om" "$cs" "$cm" "$speed" "${oC:--}" "${cf:--}" "${ch:--}" "${ov:--}" \
        "${cv:--}" "$rel" "$agree"
    inner="$inner$(awk -v c="$c" -v o="$oms" -v k="$cms" -v p="$oprec" '
        function f(x) { return x == "" ? "-" : sprintf("%.2f", x) }
        BEGIN { printf "%-10s %14s %14s %14s", c, f(o), f(k), p == "" ? "-" : p }')
"
done
echo
echo "In-program times, ms (ours: stats.ms.total; CGAL: the unions), and our grid step:"
printf '%-10s %14s %14s %14s\n' case ours CGAL precision
printf '%s' "$inner"
exit $status
