#!/bin/sh
# bench/run.sh — the 2D benchmark: cellar beside CGAL and GEOS on the same segments.
#
# Usage: bench/run.sh BUILD_DIR        (make bench builds what it needs and runs it)
# Needs BUILD_DIR/cellar, BUILD_DIR/bench/cgal_arrangement, BUILD_DIR/bench/geos_polygonize and
# /usr/bin/time (GNU).  BENCH_CASES="orthogonal grid1000 ..." restricts the cases; BENCH_BIG=0
# leaves out random1600000 (CGAL needs about two minutes and 9 GB on it).
#
# The cases: the orthogonal example; random segments (the seeds' randomLines: `cellar gen lines
# N S 1`) with N = 5000 and N = 25 000, 100 000, 400 000, 1 600 000 at S = 0.02 sqrt(100 000 /
# N), so that the crossings grow as N (about 14 per 4 segments); the 1000 x 1000 grid.  Each
# runs in two forms:
#   stats  "options": {"keep_dangling": true, "fields": ["stats"]}: the edges CGAL keeps, only
#          the counts written (compared with CGAL's and GEOS's);
#   full   the request as `cellar gen` writes it (default options: the whole result, 40 MB at
#          100 000 segments), written to a file, as a user runs it.
# Each program runs under /usr/bin/time, best of 3 under 2 s (bench/lib.sh), and one row of the
# table is printed: process wall time and peak RSS of each, the speed-up over CGAL of both our
# forms, the counts, and whether the counts agree.  The outputs are small JSON objects, read
# with grep and sed only (no python or jq needed).
# Exit status: 0, or 1 when a program failed or printed no counts (the others still run).
set -u

B=${1:-build}
BIG=""
[ "${BENCH_BIG:-1}" = 0 ] || BIG=random1600000
CASES=${BENCH_CASES:-"orthogonal random5000 random25000 random100000 random400000 $BIG grid1000"}
OPTS='{"keep_dangling":true,"fields":["stats"]}'
OURS=$B/cellar
CGAL=$B/bench/cgal_arrangement
GEOS=$B/bench/geos_polygonize
TIME=/usr/bin/time
REPEAT=${BENCH_REPEAT:-3}
LIMIT=${BENCH_TIMEOUT:-600}
BENCH_NAME=bench
. "$(dirname "$0")/lib.sh"
need "$OURS" "$CGAL" "$GEOS" "$TIME"

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
    random25000) set -- "$2" lines 25000 0.04 1 ;;
    random100000) set -- "$2" lines 100000 0.02 1 ;;
    random400000) set -- "$2" lines 400000 0.01 1 ;;
    random1600000) set -- "$2" lines 1600000 0.005 1 ;;
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
    # The generated request is one compact object: put our options first (the full form is
    # the request as generated).
    sed "1s/^{/{\"options\":$OPTS,/" "$f.gen" >"$f" && mv "$f.gen" "$f.full"
}

row() {
    printf '%-13s %7s %8s %7s %7s %8s %7s %8s %7s %8s %6s %6s  %-24s %-24s %8s  %s\n' "$@"
}

echo "2D arrangement benchmark ($(date -u +%Y-%m-%dT%H:%MZ), $(nproc 2>/dev/null || echo '?') CPUs)"
echo "  ours = $OURS run: stats (keep_dangling, stats only) and full (the default options,"
echo "  the whole result written to a file: its MB); CGAL = Arrangement_2 (Epeck, segment"
echo "  traits, aggregated insert); GEOS = GEOSNode + GEOSPolygonize."
echo "  s = wall seconds of the whole process (reading the request included), best of $REPEAT under"
echo "  2 s; MiB = peak RSS; xC = CGAL s / ours s, of stats and of full;"
echo "  V/E/F = vertices/edges/bounded faces, dangling edges kept; GEOS F = polygons;"
echo "  agree = same F for all three and same V, E as CGAL."
row case "stats s" "MiB" "full s" "full MB" "MiB" "CGAL s" "CGAL MiB" "GEOS s" "GEOS MiB" \
    "xC st" "xC fu" "ours V/E/F" "CGAL V/E/F" "GEOS F" agree
inner=""
status=0
for c in $CASES; do
    req=$tmp/$c.json
    if ! make_request "$c" "$req"; then
        row "$c" FAIL - - - - FAIL - FAIL - - - "(no request)" - - no
        status=1
        continue
    fi
    fail=0
    if timed "cellar ($c)" "$tmp/$c.ours" "$OURS" run "$req"; then
        os=$T_S om=$T_MIB
    else
        os=FAIL om=- fail=1
    fi
    fs=- fm=- fmb=-
    if [ -f "$req.full" ]; then
        if timed "cellar ($c, full)" "$tmp/$c.full" "$OURS" run "$req.full"; then
            fs=$T_S fm=$T_MIB
            fmb=$(wc -c <"$tmp/$c.full" | awk '{ printf "%.0f", $1 / 1e6 }')
        else
            fs=FAIL fail=1
        fi
        rm -f "$tmp/$c.full"
    fi
    if timed "CGAL ($c)" "$tmp/$c.cgal" "$CGAL" "$req"; then
        cs=$T_S cm=$T_MIB
    else
        cs=FAIL cm=- fail=1
    fi
    if [ "$c" = random1600000 ]; then
        gs=skipped gm=- # GEOS needs many minutes here (19 s at 100 000, growing faster than N)
    elif timed "GEOS ($c)" "$tmp/$c.geos" "$GEOS" "$req"; then
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
    if [ "$gs" != FAIL ] && [ "$gs" != skipped ]; then
        gF=$(num F "$tmp/$c.geos") gms=$(num ms "$tmp/$c.geos")
    fi
    speed=$(speed "$cs" "$os")
    fspeed=$(speed "$cs" "$fs")
    agree=no
    if [ "$fail" -eq 0 ] && [ -n "$oF" ] && [ "$oF" = "$cF" ] &&
        { [ "$oF" = "$gF" ] || [ "$gs" = skipped ]; } && [ "$oV" = "$cV" ] && [ "$oE" = "$cE" ]; then
        agree=yes
    fi
    [ "$fail" -eq 0 ] || status=1
    row "$c" "$os" "$om" "$fs" "$fmb" "$fm" "$cs" "$cm" "$gs" "$gm" "$speed" "$fspeed" \
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
