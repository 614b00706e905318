#!/bin/sh
# bench/run.sh — the 2D benchmark: cellar beside CGAL and GEOS on the same segments.
#
# Usage: bench/run.sh BUILD_DIR        (make bench builds what it needs and runs it)
# Needs BUILD_DIR/cellar, BUILD_DIR/bench/cgal_arrangement, BUILD_DIR/bench/geos_polygonize and
# /usr/bin/time (GNU).  BENCH_CASES="orthogonal grid1000 ..." restricts the cases.
#
# For each case a request file is made in a temporary directory (the generated ones get
# "options": {"keep_dangling": true, "fields": ["stats"]} so that cellar keeps the edges CGAL
# keeps and prints only its counts, not a huge result), each program runs once under
# /usr/bin/time, and one row of the table is printed: process wall time and peak RSS of each,
# the speed-up over CGAL, the counts, and whether the counts agree.  The outputs are small JSON
# objects, read with grep and sed only (no python or jq needed).
# Exit status: 0, or 1 when a program failed or printed no counts (the others still run).
set -u

B=${1:-build}
CASES=${BENCH_CASES:-"orthogonal random5000 random100000 grid1000"}
OPTS='{"keep_dangling":true,"fields":["stats"]}'
OURS=$B/cellar
CGAL=$B/bench/cgal_arrangement
GEOS=$B/bench/geos_polygonize
TIME=/usr/bin/time

for p in "$OURS" "$CGAL" "$GEOS" "$TIME"; do
    if [ ! -x "$p" ]; then
        echo "bench: $p is missing (make bench builds it)" >&2
        exit 1
    fi
done

tmp=$(mktemp -d "${TMPDIR:-/tmp}/cellar-bench.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
trap 'exit 130' INT TERM

# make_request CASE FILE: writes the request of a case.
make_request() {
    case $1 in
    orthogonal)
        printf '{"kind":"lines","options":%s,"lines":[%s,%s,%s,%s,%s,%s,%s,%s]}\n' "$OPTS" \
            '[[0,0],[6,0]]' '[[0,4],[10,4]]' '[[0,0],[0,4]]' '[[3,0],[3,4]]' \
            '[[6,0],[6,8]]' '[[3,2],[6,2]]' '[[10,0],[10,8]]' '[[0,8],[10,8]]' >"$2"
        return 0 ;;
    random5000) set -- "$2" lines 5000 0.1 1 ;;
    random100000) set -- "$2" lines 100000 0.02 1 ;;
    grid1000) set -- "$2" grid 1000 ;;
    *)
        echo "bench: unknown case '$1'" >&2
        return 1 ;;
    esac
    f=$1
    shift
    if ! "$OURS" gen "$@" >"$f.gen" 2>"$f.err"; then
        echo "bench: $OURS gen $* failed:" >&2
        cat "$f.err" >&2
        return 1
    fi
    # The generated request is one compact object: put our options first.
    sed "1s/^{/{\"options\":$OPTS,/" "$f.gen" >"$f" && rm -f "$f.gen"
}

# timed NAME OUT CMD...: runs CMD with stdout to OUT; sets T_S (wall s) and T_MIB (peak RSS).
timed() {
    name=$1
    out=$2
    shift 2
    "$TIME" -f '%e %M' -o "$out.time" "$@" >"$out" 2>"$out.err"
    rc=$?
    if [ "$rc" -ne 0 ]; then
        echo "bench: $name failed (exit $rc): $*" >&2
        cat "$out.err" >&2
        return 1
    fi
    T_S=$(tail -n 1 "$out.time" | awk '{ print $1 }')
    T_MIB=$(tail -n 1 "$out.time" | awk '{ printf "%.1f", $2 / 1024 }')
}

# num KEY FILE: the first number stored under "KEY" in FILE (empty if none).
num() {
    grep -o "\"$1\": *-\{0,1\}[0-9][0-9.eE+-]*" "$2" | head -n 1 | sed 's/.*: *//'
}

row() {
    printf '%-13s %7s %8s %7s %8s %7s %8s %8s  %-24s %-24s %8s  %s\n' "$@"
}

echo "2D arrangement benchmark ($(date -u +%Y-%m-%dT%H:%MZ), $(nproc 2>/dev/null || echo '?') CPUs)"
echo "  ours = $OURS run (keep_dangling, stats only); CGAL = Arrangement_2 (Epeck,"
echo "  segment traits, aggregated insert); GEOS = GEOSNode + GEOSPolygonize."
echo "  s = wall seconds of the whole process (reading the request included); MiB = peak RSS;"
echo "  x CGAL = CGAL s / ours s (- below the 0.01 s resolution);"
echo "  V/E/F = vertices/edges/bounded faces, dangling edges kept; GEOS F = polygons;"
echo "  agree = same F for all three and same V, E as CGAL."
row case "ours s" "ours MiB" "CGAL s" "CGAL MiB" "GEOS s" "GEOS MiB" "x CGAL" \
    "ours V/E/F" "CGAL V/E/F" "GEOS F" agree
inner=""
status=0
for c in $CASES; do
    req=$tmp/$c.json
    if ! make_request "$c" "$req"; then
        row "$c" FAIL - FAIL - FAIL - - "(no request)" - - no
        status=1
        continue
    fi
    fail=0
    if timed "cellar ($c)" "$tmp/$c.ours" "$OURS" run "$req"; then
        os=$T_S om=$T_MIB
    else
        os=FAIL om=- fail=1
    fi
    if timed "CGAL ($c)" "$tmp/$c.cgal" "$CGAL" "$req"; then
        cs=$T_S cm=$T_MIB
    else
        cs=FAIL cm=- fail=1
    fi
    if timed "GEOS ($c)" "$tmp/$c.geos" "$GEOS" "$req"; then
        gs=$T_S gm=$T_MIB
    else
        gs=FAIL gm=- fail=1
    fi
    oV='' oE='' oF='' oms='' cV='' cE='' cF='' cms='' gF='' gms=''
    if [ "$os" != FAIL ]; then
        oV=$(num V "$tmp/$c.ours") oE=$(num E "$tmp/$c.ours") oF=$(num F "$tmp/$c.ours")
        oms=$(num total "$tmp/$c.ours")
        if [ -z "$oV" ] || [ -z "$oE" ] || [ -z "$oF" ]; then
            echo "bench: cellar ($c) printed no stats V, E, F:" >&2
            head -c 400 "$tmp/$c.ours" >&2
            echo >&2
            fail=1
        fi
    fi
    if [ "$cs" != FAIL ]; then
        cV=$(num V "$tmp/$c.cgal") cE=$(num E "$tmp/$c.cgal") cF=$(num F "$tmp/$c.cgal")
        cms=$(num ms "$tmp/$c.cgal")
    fi
    if [ "$gs" != FAIL ]; then
        gF=$(num F "$tmp/$c.geos") gms=$(num ms "$tmp/$c.geos")
    fi
    speed=$(awk -v c="$cs" -v o="$os" 'BEGIN {
        if (c == "FAIL" || o == "FAIL" || c + 0 < 0.01 || o + 0 < 0.01) print "-"
        else printf "%.1f", c / o }')
    agree=no
    if [ "$fail" -eq 0 ] && [ -n "$oF" ] && [ "$oF" = "$cF" ] && [ "$oF" = "$gF" ] &&
        [ "$oV" = "$cV" ] && [ "$oE" = "$cE" ]; then
        agree=yes
    fi
    [ "$fail" -eq 0 ] || status=1
    row "$c" "$os" "$om" "$cs" "$cm" "$gs" "$gm" "$speed" \
        "${oV:-?}/${oE:-?}/${oF:-?}" "${cV:-?}/${cE:-?}/${cF:-?}" "${gF:-?}" "$agree"
    inner="$inner$(awk -v c="$c" -v o="$oms" -v k="$cms" -v g="$gms" '
        function f(x) { return x == "" ? "-" : sprintf("%.2f", x) }
        BEGIN { printf "%-13s %14s %14s %14s", c, f(o), f(k), f(g) }')
"
done
echo
echo "In-program times, ms (ours: stats.ms.total; CGAL: insertion; GEOS: node + polygonize):"
printf '%-13s %14s %14s %14s\n' case ours CGAL GEOS
printf '%s' "$inner"
exit $status
