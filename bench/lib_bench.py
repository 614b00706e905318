"""lib_bench.py — a polygon overlay three ways, from one run: shapely (GEOS), cellar's library
from Python (python/: arrays in, arrays out) and the CLI on the same request as JSON.

Two layers of K x K squares (side 0.9, pitch 1: each layer's squares are disjoint), the second
turned by 30 degrees about the grid's centre and shifted:
  union         all 2 K^2 polygons        unary_union(A + B)
  intersection  (union of A) & (union of B): cellar's op ["&", ["+", A...], ["+", B...]],
                unary_union(A).intersection(unary_union(B))
Columns: shapely's time (its Polygons made beforehand); the library's wall time from Python
with the rings packed beforehand (cellar.polygons_packed: the run and the arrays copied out
into NumPy; no JSON); the same from a list of one array per ring (cellar.polygons: the lists
packed in the call); the C call's own wall time
(Result.seconds); the core alone (the same call with fields ["stats"]: the arrangement, the
membership and the Boolean computed, no array made); the arrangement's stages alone (stats.ms.total: for polygons it leaves out
the Boolean's membership, select and polygons stages and the arrays' making, so it is not the
whole core); the CLI's wall time (`cellar run REQ.json > out`: the process, the JSON read and
written); call/core (what the arrays cost over the core: "the library path has no JSON cost,
its time is the core's within 10 %" reads off as a ratio below 1.10); lib/core (the same from
Python); CLI/lib; and the areas' relative difference to shapely.  Each
time is the best of --repeat runs (default 3).  About 20 s at the default K = 100 (20 000 squares).
Usage: python3 bench/lib_bench.py [BUILD_DIR] [--k K] [--repeat N] [--threads T]
(the library: BUILD_DIR/lib/libcellar.so.0 unless CELLAR_LIBRARY is set; the package:
python/ of this tree unless one is installed and --installed is given)
"""
import argparse, json, math, os, subprocess, sys, tempfile, time

ap = argparse.ArgumentParser()
ap.add_argument("build", nargs="?", default="build")
ap.add_argument("--k", type=int, default=100)
ap.add_argument("--repeat", type=int, default=3)
ap.add_argument("--threads", type=int, default=0,
                help="the library's threads (the CLI uses every CPU)")
ap.add_argument("--installed", action="store_true")
args = ap.parse_args()

top = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
os.environ.setdefault("CELLAR_LIBRARY", os.path.abspath(os.path.join(args.build, "lib",
                                                                     "libcellar.so.0")))
if not args.installed:
    sys.path.insert(0, os.path.join(top, "python"))
import numpy as np  # noqa: E402
import shapely  # noqa: E402
from shapely.ops import unary_union  # noqa: E402 (shapely 1.8 of Debian 12: no union_all)
from shapely.geometry import Polygon  # noqa: E402

import cellar  # noqa: E402

BIN = os.path.join(args.build, "cellar")
K = args.k


def layers():
    sq = np.array([[0, 0], [0.9, 0], [0.9, 0.9], [0, 0.9]])
    a = [sq + (i, j) for i in range(K) for j in range(K)]
    c, s = math.cos(math.pi / 6), math.sin(math.pi / 6)
    rot = np.array([[c, -s], [s, c]])
    ctr = np.array([K / 2, K / 2])
    b = [(p - ctr) @ rot.T + ctr + (0.37, 0.21) for p in a]
    return a, b


A, B = layers()
n = len(A)
CASES = [
    ("union", A + B, "union", lambda ga, gb: unary_union(ga + gb)),
    ("intersection", A + B, ["&", ["+"] + list(range(n)), ["+"] + list(range(n, 2 * n))],
     lambda ga, gb: unary_union(ga).intersection(unary_union(gb))),
]


def best(fn):
    t, out = math.inf, None
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        out = fn()
        t = min(t, time.perf_counter() - t0)
    return t, out


tmp = tempfile.mkdtemp()
print("lib_bench: %d + %d squares (K = %d), the second layer turned 30 degrees; best of %d; "
      "cellar %s (%s), shapely %s (GEOS %s)" % (n, n, K, args.repeat, cellar.version(),
                                                cellar._lib.path, shapely.__version__,
                                                '.'.join(map(str, shapely.geos.geos_version))))
print("%-13s %10s %10s %10s %10s %10s %10s %10s %9s %9s %8s %s" % (
    "op", "shapely s", "lib s", "lists s", "C call s", "core s", "arr. s", "CLI s", "call/core",
    "lib/core", "CLI/lib", "area rel. diff"))
for name, polys, op, ref in CASES:
    ga, gb = [Polygon(p) for p in A], [Polygon(p) for p in B]
    ts, g = best(lambda: ref(ga, gb))
    core = []

    xy = np.ascontiguousarray(np.concatenate(polys))
    ring_off = np.arange(0, 4 * len(polys) + 1, 4)
    poly_off = np.arange(len(polys) + 1)

    def lib():
        r = cellar.polygons_packed(xy, ring_off, poly_off, op, threads=args.threads)
        core.append((r.seconds, r.stats["ms"]["total"] / 1000))
        return r
    tl, r = best(lib)
    tlists, r2 = best(lambda: cellar.polygons([[p] for p in polys], op, threads=args.threads))
    assert r2.area == r.area
    tcore = min(cellar.polygons_packed(xy, ring_off, poly_off, op, threads=args.threads,
                                       fields=["stats"]).seconds for _ in range(args.repeat))
    req = os.path.join(tmp, "req.json")
    with open(req, "w") as f:
        json.dump({"kind": "polygons", "polygons": [[p.tolist()] for p in polys], "op": op,
                   }, f)
    out = os.path.join(tmp, "out.json")

    def cli():
        with open(out, "wb") as f:
            subprocess.run([BIN, "run", req, "--quiet"], stdout=f, check=True)
    tc, _ = best(cli)
    with open(out) as f:
        area_cli = json.load(f)["result"]["area"]
    tcall = min(c for c, _ in core)
    tarr = min(a for _, a in core)
    diff = abs(r.area - g.area) / g.area
    print("%-13s %10.3f %10.3f %10.3f %10.3f %10.3f %10.3f %10.3f %9.2f %9.2f %8.2f %.1e%s" % (
        name, ts, tl, tlists, tcall, tcore, tarr, tc, tcall / tcore, tl / tcore, tc / tl, diff,
        "" if area_cli == r.area else "  (CLI's area differs: %r)" % area_cli))
