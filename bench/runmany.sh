#!/bin/sh
# bench/runmany.sh — Booleans of many operands (the union of N inputs) beside the peers, in one
# run: cellar's 2D union of N polygons beside GEOS's GEOSUnaryUnion (build/bench/geos_bool2),
# cellar's 3D union of N solids beside Manifold's batch union (node bench/manifold_bool.mjs).
#
# Usage: bench/runmany.sh BUILD_DIR    (make bench builds what it needs and runs it)
# BENCHMANY_CASES picks cases (default: all below); BENCHMANY_TIMEOUT (s, default 600) stops a
# program that runs longer.
#
# Cases, at constant density (the arrangement grows about linearly with N):
#   squaresN     N unit squares turned at random, centres uniform in a square of area N / 2
#                (each point covered about twice): 1000, 10000, 100000;
#   tilingK      the K x K unit squares of a tiling (every edge shared): exact union area K^2,
#                one polygon, no hole; K = 32, 100, 316 (about 10^3, 10^4, 10^5 squares);
#   cubesN       bench/gen3d.py cubes N 1 (N random turned cubes, total volume constant):
#                250, 1000, 4000, 16000;
#   checkerK     the cubes (i, j, k) of a K x K x K grid with i + j + k even (unit cubes meeting
#                only along edges and at vertices): exact union volume, the number of cubes;
#                K = 13, 20, 32 (1099, 4000, 16384 cubes).
# Each program reads the same files and runs once under /usr/bin/time (wall seconds of the
# whole process, start-up and reading included; peak RSS MiB).  ours 2D: cellar run REQUEST
# (fields: stats, membership, result: the result polygons and the membership, not the complex);
# ours 3D: cellar solids FILES --op union (the same fields).  agree: the areas within the
# snapping bound (GEOS's result perimeter x our grid step) and the same polygon and hole
# counts (2D), the volumes within 1e-9 relative or our grid step x the cubes' total area (3D);
# for the tilings and the checkerboards also against the exact value.
set -u

B=${1:-build}
HERE=$(dirname "$0")
OURS=$B/cellar
GEOS=$B/bench/geos_bool2
MF=$HERE/manifold_bool.mjs
TIME=/usr/bin/time
LIMIT=${BENCHMANY_TIMEOUT:-600}
CASES=${BENCHMANY_CASES:-"squares1000 squares10000 squares100000 tiling32 tiling100 tiling316
cubes250 cubes1000 cubes4000 cubes16000 checker13 checker20 checker32"}
BENCH_NAME=runmany
. "$HERE/lib.sh"
need "$OURS" "$GEOS" "$TIME"
have_mf=0
command -v node >/dev/null 2>&1 && [ -d "$HERE/node_modules/manifold-3d" ] && have_mf=1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
trap 'exit 130' INT TERM

REPEAT=1 # runs of minutes: once

# The inputs: a polygons request (2D) or a directory of OFF files (3D), and the exact answer.
gen() {
    python3 - "$1" "$2" <<'EOF'
import json, math, os, random, sys
case, d = sys.argv[1], sys.argv[2]
def off(path, V, F):
    with open(path, 'w') as fh:
        fh.write('OFF\n%d %d 0\n' % (len(V), len(F)))
        for v in V: fh.write('%r %r %r\n' % tuple(v))
        for f in F: fh.write('%d %s\n' % (len(f), ' '.join(map(str, f))))
def cube(x, y, z):
    V = [[x + a, y + b, z + c] for c in (0, 1) for b in (0, 1) for a in (0, 1)]
    F = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    return V, F
exact = None
if case.startswith('squares'):
    n = int(case[7:]); rng = random.Random(1); side = math.sqrt(n / 2.0); polys = []
    for _ in range(n):
        cx, cy, t = rng.uniform(0, side), rng.uniform(0, side), rng.uniform(0, math.pi / 2)
        c, s = math.cos(t) / 2, math.sin(t) / 2
        polys.append([[[cx + dx * c - dy * s, cy + dx * s + dy * c]
                       for dx, dy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]])
elif case.startswith('tiling'):
    k = int(case[6:])
    polys = [[[[i, j], [i + 1, j], [i + 1, j + 1], [i, j + 1]]] for i in range(k) for j in range(k)]
    exact = (float(k * k), 1, 0)
if case.startswith(('squares', 'tiling')):
    json.dump({'kind': 'polygons', 'polygons': polys, 'op': 'union',
               'options': {'fields': ['stats', 'membership', 'result']}}, open(os.path.join(d, 'req.json'), 'w'))
    print(json.dumps({'n': len(polys), 'exact': exact}))
    sys.exit(0)
os.makedirs(os.path.join(d, 'off'))
if case.startswith('checker'):
    k = int(case[7:]); n = 0
    for i in range(k):
        for j in range(k):
            for l in range(k):
                if (i + j + l) % 2 == 0:
                    off(os.path.join(d, 'off', 's%06d.off' % n), *cube(i, j, l)); n += 1
    print(json.dumps({'n': n, 'exact': [float(n)]}))
else:  # cubesN: bench/gen3d.py writes the files
    print(json.dumps({'n': int(case[5:]), 'exact': None}))
EOF
}

row() {
    printf '%-14s %7s %7s %8s %7s %8s %6s  %-22s %-22s %-9s %s\n' "$@"
}
echo "Booleans of many operands: the union ($(date -u +%Y-%m-%dT%H:%MZ), $(nproc) CPUs)"
echo "  2D peer: GEOS $(pkg-config --modversion geos 2>/dev/null || echo '?') GEOSUnaryUnion" \
    "($GEOS); 3D peer: Manifold batch union (node $MF)"
[ $have_mf -eq 1 ] || echo "  manifold: not installed (node + npm ci --prefix bench); its columns show -"
row case N "ours s" "ours MiB" "peer s" "peer MiB" "xPeer" "ours area/volume" "peer area/volume" \
    agree exact
status=0
for c in $CASES; do
    d=$tmp/$c
    mkdir -p "$d"
    info=$(gen "$c" "$d") || {
        echo "runmany: cannot make $c" >&2
        status=1
        continue
    }
    n=$(echo "$info" | python3 -c 'import json,sys; print(json.load(sys.stdin)["n"])' 2>/dev/null)
    case $c in
    cubes*)
        python3 "$HERE/gen3d.py" cubes "${c#cubes}" 1 --off "$d/off" || continue
        n=${c#cubes}
        ;;
    esac
    if [ -f "$d/req.json" ]; then
        timed "cellar ($c)" "$d/ours" "$OURS" run "$d/req.json"
        os=$T_S om=$T_MIB
        timed "geos_bool2 ($c)" "$d/peer" "$GEOS" "$d/req.json"
        ps=$T_S pm=$T_MIB
    else
        timed "cellar ($c)" "$d/ours" "$OURS" solids "$d"/off/*.off --op union --options '{"fields":["stats","membership","result"]}'
        os=$T_S om=$T_MIB
        ps=- pm=-
        if [ $have_mf -eq 1 ]; then
            timed "manifold ($c)" "$d/peer" node "$MF" --op union "$d"/off/*.off
            ps=$T_S pm=$T_MIB
        fi
    fi
    verdict=$(python3 - "$d" "$info" <<'EOF'
import json, sys
d, info = sys.argv[1], json.loads(sys.argv[2])
def load(p, last):
    try:
        txt = open(p).read().strip()
        return json.loads(txt.splitlines()[-1] if last else txt)
    except Exception:
        return None
o, p = load(d + '/ours', False), load(d + '/peer', True)
ours = peer = agree = ex = '-'
if o and 'result' in o:
    r = o['result']; step = o['stats']['precision']
    if 'area' in r:
        holes = sum(len(v) for v in r['holes'].values())
        ours = '%.10g %d/%d' % (r['area'], len(r['FV']), holes)
        if p:
            peer = '%.10g %d/%d' % (p['area'], p['polygons'], p['holes'])
            tol = p.get('perimeter', 0) * step + 1e-9 * abs(p['area'])
            agree = 'yes' if abs(r['area'] - p['area']) <= tol and len(r['FV']) == p['polygons'] and holes == p['holes'] else 'NO'
        if info.get('exact'):
            a, np_, nh = info['exact']
            ex = 'yes' if abs(r['area'] - a) <= 1e-9 * a and len(r['FV']) == np_ and holes == nh else 'NO'
    else:
        v = r['volume']; ours = '%.12g' % v
        if p and 'volume' in p:
            peer = '%.12g' % p['volume']
            agree = 'yes' if abs(v - p['volume']) <= 1e-9 * abs(p['volume']) + step * 6 * info['n'] else 'NO'
        if info.get('exact'):
            ex = 'yes' if abs(v - info['exact'][0]) <= 1e-9 * info['exact'][0] else 'NO'
print(ours.replace(' ', '_'), peer.replace(' ', '_'), agree, ex)
EOF
)
    [ -n "$verdict" ] || verdict="- - - -"
    set -- $verdict
    xp=$(speed "$ps" "$os")
    row "$c" "$n" "$os" "$om" "$ps" "$pm" "$xp" "$1" "$2" "$3" "$4"
    case "$os $3 $4" in *failed* | *timeout* | *NO*) status=1 ;; esac
done
echo "  N = operands; s = wall seconds, MiB = peak RSS; xPeer = peer s / ours s (> 1: ours faster);"
echo "  2D area as 'area polygons/holes'; agree: with the peer within the snapping bound (2D) or"
echo "  1e-9 relative plus grid step x total cube area (3D); exact: against the closed form."
exit $status
