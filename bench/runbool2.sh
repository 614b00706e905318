#!/bin/sh
# bench/runbool2.sh — the 2D Boolean benchmark: cellar's "polygons" requests (one arrangement
# of all ring edges, faces selected by the operation) beside GEOS's overlay (OverlayNG) on the
# same requests.
#
# Usage: bench/runbool2.sh BUILD_DIR    (make bench builds what it needs and runs it)
# Needs BUILD_DIR/cellar, BUILD_DIR/bench/geos_bool2 (bench/geos_bool2.c), python3 (no
# modules beyond the standard library: it writes the requests and reads our answers) and
# /usr/bin/time (GNU).  BENCHBOOL2_CASES="squares1000 star10000.xor ..." picks the cases;
# BENCH_BIG=1 adds squares100000 and raises the time limit; BENCHBOOL2_TIMEOUT (seconds,
# default 90, 900 with BENCH_BIG=1) stops a program that runs longer, and a program that timed
# out on one operation of an input is not run on its other operations ("skipped": the same
# stars, the same noding); BENCHBOOL2_REPEAT (default 3) is how many times a run under 2 s is
# made, the fastest kept.  By default the whole table takes about 3 to 5 minutes on 2 CPUs,
# most of it the 100000-vertex stars (GEOS takes about 270 s on each of them, so it shows
# "timeout" unless BENCH_BIG=1).
#
# Cases (the requests are written by the python script below into a temporary directory;
# every one gets "options": {"fields": ["stats", "membership", "result"]}, so that our answer is
# the stats, the membership table and the result, not the whole arrangement):
#   squaresN              union of N unit squares, randomly turned, centres uniform in a square
#                         of area N/2 (each point covered about twice); N = 1000, 10000, and
#                         100000 with BENCH_BIG=1;
#   starN.OP              OP = intersection, difference, xor of two star polygons of N vertices
#                         each (radii alternately in [0.8, 1] and [0.3, 0.5], the second turned
#                         by half a step): every spike of one crosses spikes of the other;
#                         N = 10000, 100000;
#   parcelsK.union        the K x K unit squares of a lattice and the same squares turned by 1
#                         degree about the centre and moved by (0.3, 0.2): 2 K^2 polygons, union
#                         of all;
#   parcelsK.intersection the same two layers, intersected: ["&", ["+", layer 1], ["+", layer
#                         2]] (op "intersection" would intersect every parcel with every other);
#                         K = 100;
#   layersKxM.OP          two GIS layers at UTM coordinates (500 000 m, 4 400 000 m): K x K
#                         parcels of 20 m laid as bricks (T-junctions), and M buffers of 64
#                         vertices (circles, segments' buffers) overlapping; OP of the layers'
#                         unions ["&" / "-" / "+", ["+", layer 1], ["+", layer 2]], fields
#                         ["result", "stats"]: the answer itself is written (K = 60, M = 550);
#   real/NAME             tests/data/bool2-cases/NAME.json, every request of kind "polygons"
#                         there (reduced from real GIS overlays), when the folder exists.
# Each program runs under /usr/bin/time on the same request file:
#   ours  BUILD_DIR/cellar run FILE: area = result.area, P = result polygons (len of
#         result.FV), H = their holes (all lists of result.holes), ms = stats.ms.total;
#   GEOS  BUILD_DIR/bench/geos_bool2 FILE: the same operation with GEOS's C API (union: unary
#         union of all; intersection, xor: chained; difference: the first minus the unary union
#         of the others; expressions likewise); prints ms (the operation only), area,
#         perimeter, P and H.
# One row per case: wall time (s, the whole process: start-up, reading and writing included)
# and peak RSS (MiB) of each, xG = GEOS s / ours s, both areas, d = |ours - GEOS|, tol = GEOS's
# result perimeter times our grid step (stats.precision: how far snapping the vertices to the
# grid may move the area), P/H of each, and agree: yes when d <= tol and P, H are the same, else
# what differs.  A program that fails or times out shows "failed" / "timeout" / "skipped".
# Exit status: 0, or 1 when ours failed, timed out or was skipped, GEOS failed (GEOS's timeouts
# are reported only), or an answer disagrees.
set -u

B=${1:-build}
HERE=$(dirname "$0")
REAL=$HERE/../tests/data/bool2-cases
BIG=${BENCH_BIG:-0}
# BENCH_BIG=1 adds the larger sizes and the 100 000-vertex stars (GEOS needs minutes on those);
# bench/runmany.sh has the unions of 10^3 to 10^5 operands.
if [ "$BIG" = 1 ]; then
    LIMIT=${BENCHBOOL2_TIMEOUT:-900}
    SQUARES="squares1000 squares3000 squares10000 squares100000"
    PARCELS="parcels50.union parcels50.intersection parcels100.union parcels100.intersection"
else
    LIMIT=${BENCHBOOL2_TIMEOUT:-90}
    SQUARES="squares1000 squares3000"
    PARCELS="parcels50.union parcels50.intersection"
fi
REPEAT=${BENCHBOOL2_REPEAT:-3}
OURS=$B/cellar
GEOS=$B/bench/geos_bool2
TIME=/usr/bin/time

# The polygons requests of tests/data/bool2-cases (other kinds and expected.json are skipped).
real_cases() {
    [ -d "$REAL" ] || return 0
    for f in "$REAL"/*.json; do
        [ -f "$f" ] || continue
        grep -q '"kind": *"polygons"' "$f" || continue
        printf 'real/%s ' "$(basename "$f" .json)"
    done
}
STARS="star10000.intersection star10000.difference star10000.xor"
[ "$BIG" = 1 ] && STARS="$STARS star100000.intersection star100000.difference star100000.xor"
LAYERS="layers60x550.intersection layers60x550.difference layers60x550.union"
CASES=${BENCHBOOL2_CASES:-"$SQUARES $STARS $PARCELS $LAYERS $(real_cases)"}

BENCH_NAME=benchbool2
. "$HERE/lib.sh"
need "$OURS" "$GEOS" "$TIME"
if ! command -v python3 >/dev/null 2>&1; then
    echo "benchbool2: python3 is missing" >&2
    exit 1
fi

tmp=$(mktemp -d "${TMPDIR:-/tmp}/cellar-benchbool2.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
trap 'exit 130' INT TERM

# The helper: "make CASE OUT REALDIR" writes a request; "ours FILE" prints "ms precision area P
# H" of our answer (read without loading the membership table: the stats from the front, the
# result from the back).
PY=$tmp/bool2.py
cat >"$PY" <<'EOF'
import json, math, mmap, os, random, re, sys

def squares(n, seed=1):
    rnd = random.Random(seed)
    side = math.sqrt(n / 2.0)
    out = []
    for _ in range(n):
        cx, cy = rnd.uniform(0, side), rnd.uniform(0, side)
        a = rnd.uniform(0, math.pi / 2)
        c, s = 0.5 * math.cos(a), 0.5 * math.sin(a)
        out.append([[[cx + c - s, cy + s + c], [cx - c - s, cy - s + c],
                     [cx - c + s, cy - s - c], [cx + c + s, cy + s - c]]])
    return out

def star(n, seed, turn):
    rnd = random.Random(seed)
    ring = []
    for i in range(n):
        t = 2 * math.pi * (i + turn) / n
        r = rnd.uniform(0.8, 1.0) if i % 2 == 0 else rnd.uniform(0.3, 0.5)
        ring.append([r * math.cos(t), r * math.sin(t)])
    return [ring]

def parcels(k):
    a = [[[[i, j], [i + 1, j], [i + 1, j + 1], [i, j + 1]]] for i in range(k) for j in range(k)]
    t = math.radians(1)
    c, s, m = math.cos(t), math.sin(t), k / 2.0
    def move(p):
        x, y = p[0] - m, p[1] - m
        return [m + c * x - s * y + 0.3, m + s * x + c * y + 0.2]
    return a, [[[move(p) for p in poly[0]]] for poly in a]

def layers(k, m, seed=1):
    """Two GIS layers at UTM-size coordinates: a cadastre of k x k parcels of 20 m laid as
    bricks (each row shifted by half a parcel: T-junctions everywhere), and m buffers of 64
    vertices (circles of radius 8 to 30 m, and segments' buffers: two half circles joined),
    overlapping each other and the parcels."""
    rnd = random.Random(seed)
    x0, y0, w = 500000.0, 4400000.0, 20.0
    a = []
    for j in range(k):
        sh = w / 2 if j % 2 else 0.0
        for i in range(k):
            x, y = x0 + i * w + sh, y0 + j * w
            a.append([[[x, y], [x + w, y], [x + w, y + w], [x, y + w]]])
    b = []
    for q in range(m):
        cx, cy = x0 + rnd.uniform(0, k * w), y0 + rnd.uniform(0, k * w)
        r = rnd.uniform(8, 30)
        if q % 2 == 0:
            ring = [[cx + r * math.cos(2 * math.pi * t / 64), cy + r * math.sin(2 * math.pi * t / 64)]
                    for t in range(64)]
        else:
            ang, ln = rnd.uniform(0, math.pi), rnd.uniform(20, 80)
            dx, dy = math.cos(ang) * ln / 2, math.sin(ang) * ln / 2
            ring = []
            for end, (ex, ey) in enumerate(((cx + dx, cy + dy), (cx - dx, cy - dy))):
                for t in range(32):
                    th = ang - math.pi / 2 + math.pi * (t / 31.0) + end * math.pi
                    ring.append([ex + r * math.cos(th), ey + r * math.sin(th)])
        b.append([ring])
    return a, b

def make(case, out, real):
    fields = ['stats', 'membership', 'result']
    m = re.fullmatch(r'squares(\d+)', case)
    lay = re.fullmatch(r'layers(\d+)x(\d+)\.(union|intersection|difference)', case)
    if m:
        req = {'kind': 'polygons', 'polygons': squares(int(m.group(1))), 'op': 'union'}
    elif re.fullmatch(r'star\d+\.(intersection|difference|xor)', case):
        n, op = case[4:].split('.')
        req = {'kind': 'polygons', 'polygons': [star(int(n), 1, 0), star(int(n), 2, 0.5)],
               'op': op}
    elif re.fullmatch(r'parcels\d+\.(union|intersection)', case):
        k, op = case[7:].split('.')
        a, b = parcels(int(k))
        if op == 'intersection':
            op = ['&', ['+'] + list(range(len(a))), ['+'] + list(range(len(a), 2 * len(a)))]
        req = {'kind': 'polygons', 'polygons': a + b, 'op': op}
    elif lay:
        a, b = layers(int(lay.group(1)), int(lay.group(2)))
        la, lb = ['+'] + list(range(len(a))), ['+'] + list(range(len(a), len(a) + len(b)))
        op = {'union': ['+', la, lb], 'intersection': ['&', la, lb],
              'difference': ['-', la, lb]}[lay.group(3)]
        req = {'kind': 'polygons', 'polygons': a + b, 'op': op}
        fields = ['result', 'stats'] # the answer itself, written whole
    elif case.startswith('real/'):
        with open(os.path.join(real, case[5:] + '.json')) as f:
            req = json.load(f)
        if req.get('kind') != 'polygons':
            sys.exit('%s: not a polygons request' % case)
    else:
        sys.exit('unknown case %s' % case)
    req.setdefault('options', {})['fields'] = fields
    with open(out, 'w') as f:
        json.dump(req, f, separators=(',', ':'))

def ours(path):
    with open(path, 'rb') as f:
        m = mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ)
    dec = json.JSONDecoder()
    i, j = m.find(b'"stats":'), m.rfind(b'"result":')
    if i < 0 or j < 0:
        sys.exit('%s: no stats or no result' % path)
    st = dec.raw_decode(m[i + 8:i + 8 + 65536].decode())[0]
    r = dec.raw_decode(m[j + 9:].decode())[0]
    print(repr(st['ms']['total']), repr(st['precision']), repr(r['area']), len(r['FV']),
          sum(len(h) for h in r['holes'].values()))

if sys.argv[1] == 'make':
    make(sys.argv[2], sys.argv[3], sys.argv[4])
else:
    ours(sys.argv[2])
EOF


# skip PROG CASE: true when PROG timed out on another operation of the same input (CASE up to
# its first dot, e.g. star100000): the noding, which is most of the work, would be the same.
slow=""
skip() {
    case " $slow " in
    *" $1:${2%%.*} "*)
        echo "benchbool2: $1 skipped on $2 (it timed out on ${2%%.*} already)" >&2
        return 0 ;;
    esac
    return 1
}

row() {
    printf '%-26s %7s %8s %7s %8s %6s  %-18s %-18s %7s %7s  %-11s %-11s %s\n' "$@"
}

echo "2D Boolean benchmark: polygons ($(date -u +%Y-%m-%dT%H:%MZ), $(nproc 2>/dev/null || echo '?') CPUs)"
echo "  ours = $OURS run (fields: stats, membership and result: the membership table and the result;"
echo "  layers: fields result and stats, the answer alone);"
echo "  GEOS = $GEOS (GEOS $(geos-config --version 2>/dev/null || echo '?'), OverlayNG:"
echo "  union = GEOSUnaryUnion of all, intersection / xor chained, difference = first minus the"
echo "  unary union of the rest)."
echo "  Inputs: squaresN (N turned unit squares, union, density 2), starN.OP (two N-vertex stars),"
echo "  parcelsK.OP (K x K lattice squares and the same turned 1 degree: union of all, or the"
echo "  intersection of the two layers), real/NAME (tests/data/bool2-cases/NAME.json)."
echo "  s = wall seconds of the whole process (start-up, reading, writing included); MiB = peak"
echo "  RSS; xG = GEOS s / ours s; d = |ours area - GEOS area|; tol = GEOS result perimeter *"
echo "  our grid step; P/H = result polygons / holes; agree: yes when d <= tol and P/H equal."
echo "  Time limit $LIMIT s a run (BENCHBOOL2_TIMEOUT; skipped: timed out on another op of the"
echo "  same input); runs under 2 s: best of $REPEAT."
row case "ours s" "ours MiB" "GEOS s" "GEOS MiB" xG "ours area" "GEOS area" d tol "ours P/H" \
    "GEOS P/H" agree
inner=""
status=0
for c in $CASES; do
    req=$tmp/$(echo "$c" | tr / _).json
    if ! python3 "$PY" make "$c" "$req" "$REAL" 2>"$req.err"; then
        echo "benchbool2: no request for case '$c':" >&2
        cat "$req.err" >&2
        status=1
        continue
    fi
    base=$tmp/$(echo "$c" | tr / _)
    if skip ours "$c"; then
        os=skipped om=- status=1
    elif timed "cellar ($c)" "$base.ours" "$OURS" run "$req"; then
        os=$T_S om=$T_MIB
    else
        os=$T_S om=- status=1
        [ "$os" = timeout ] && slow="$slow ours:${c%%.*}"
    fi
    if skip GEOS "$c"; then
        gs=skipped gm=-
    elif timed "geos_bool2 ($c)" "$base.geos" "$GEOS" "$req"; then
        gs=$T_S gm=$T_MIB
    else
        gs=$T_S gm=-
        [ "$gs" = timeout ] && slow="$slow GEOS:${c%%.*}"
        [ "$gs" = timeout ] || status=1
    fi
    oms='' oprec='' oa='' oP='' oH=''
    if [ "$om" != - ]; then
        # shellcheck disable=SC2046 # five numbers, one word each
        if set -- $(python3 "$PY" ours "$base.ours" 2>"$base.sum.err") && [ $# -eq 5 ]; then
            oms=$1 oprec=$2 oa=$3 oP=$4 oH=$5
        else
            echo "benchbool2: cellar ($c) printed no stats or result:" >&2
            cat "$base.sum.err" >&2
            head -c 400 "$base.ours" >&2
            echo >&2
            os=failed om=- status=1
        fi
    fi
    gms='' ga='' gper='' gP='' gH=''
    if [ "$gm" != - ]; then
        gms=$(num ms "$base.geos") ga=$(num area "$base.geos") gper=$(num perimeter "$base.geos")
        gP=$(num polygons "$base.geos") gH=$(num holes "$base.geos")
    fi
    d=- tol=- agree=-
    if [ -n "$oa" ] && [ -n "$ga" ]; then
        d=$(awk -v a="$oa" -v b="$ga" 'BEGIN { x = a - b; printf "%.1e", x < 0 ? -x : x }')
        tol=$(awk -v p="$gper" -v h="$oprec" 'BEGIN { printf "%.1e", p * h }')
        agree=$(awk -v a="$oa" -v b="$ga" -v p="$gper" -v h="$oprec" -v op="$oP" -v oh="$oH" \
            -v gp="$gP" -v gh="$gH" 'BEGIN {
            x = a - b; if (x < 0) x = -x
            w = ""
            if (x > p * h) w = "area"
            if (op != gp || oh != gh) w = w (w == "" ? "" : ",") "P/H"
            print w == "" ? "yes" : "NO:" w }')
        [ "$agree" = yes ] || status=1
    fi
    row "$c" "$os" "$om" "$gs" "$gm" "$(speed "$gs" "$os")" \
        "$([ -n "$oa" ] && awk -v a="$oa" 'BEGIN { printf "%.12g", a }' || echo "$os")" \
        "$([ -n "$ga" ] && awk -v a="$ga" 'BEGIN { printf "%.12g", a }' || echo "$gs")" \
        "$d" "$tol" "${oP:--}/${oH:--}" "${gP:--}/${gH:--}" "$agree"
    inner="$inner$(awk -v c="$c" -v o="$oms" -v g="$gms" -v p="$oprec" '
        function f(x) { return x == "" ? "-" : sprintf("%.2f", x) }
        function r(a, b) { return a == "" || b == "" || a + 0 <= 0 ? "-" : sprintf("%.2f", b / a) }
        BEGIN { printf "%-26s %12s %12s %8s %14s", c, f(o), f(g), r(o, g),
                p == "" ? "-" : sprintf("%.6g", p) }')
"
done
echo
echo "In-program times, ms (ours: stats.ms.total, the arrangement of all ring edges from the"
echo "rings read to its faces: snapping, crossings, faces, holes; the membership, the selection"
echo "and the result rings after it are not in it; GEOS: the operation only, after reading and"
echo "building the input geometries), xG = GEOS ms / ours ms, and our grid step:"
printf '%-26s %12s %12s %8s %14s\n' case ours GEOS xG precision
printf '%s' "$inner"
exit $status
