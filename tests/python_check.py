"""python_check.py — the Python package `cellar` (python/) as a user runs it (tests/t_python.sh
installs it into a venv and runs this there).

- Library against CLI: for each request (random segments, the README's lines example,
  polygons with holes and touching edges, fill rules, fields subsets, operators, 3D cubes with
  an op, a solid turned inside out, quads given as polygon lists) the package's call on the
  same input gives exactly the arrays of `cellar run --format npz` by name and value (the same
  set of names; "result.area"/"result.volume", in the npz's json, compared there), the same
  dim and stats but the times; and run_json() gives the CLI's JSON but the times.
- Overlays against shapely: random convex polygons, polygons with holes, touching squares, in
  pairs and sets of four: areas of union, intersection, difference, xor within 1e-9 relative,
  result.geometry valid and of the same area.
- 3D volumes: two overlapping boxes (closed form), random boxes (inclusion-exclusion), an
  intersection.
- Errors: NaN coordinates (status 422, the message names the element), a bad op, a bad field,
  a bad face index, a bad segments shape; cellar.Error is a ValueError.
- Progress: fractions never go back and end at 1, stages named; a progress callback that
  raises cancels the run and its exception comes out; SIGINT sent to this process during a
  long run raises KeyboardInterrupt well before the run would end, and the next call works.
- The README's "From Python" examples run as written.
Usage: python tests/python_check.py TMPDIR   (CELLAR_BIN names the CLI; run from the top)
"""
import json, math, os, re, signal, subprocess, sys, threading, time

import numpy as np

from tally import ok, fail, summary

import cellar

BIN = os.environ.get("CELLAR_BIN", "build/cellar")
tmp = sys.argv[1]
rng = np.random.default_rng(29)


def check(name, cond, why=""):
    if cond:
        ok(name)
    else:
        fail(name, why)
    return cond


print("  cellar %s, library %s (%s)" % (cellar.__version__, cellar.version(), cellar._lib.path))


# ---- the library against the CLI ---------------------------------------------------------------

def cli(req, fmt):
    path = os.path.join(tmp, "req.json")
    with open(path, "w") as f:
        json.dump(req, f)
    args = [BIN, "run", path, "--quiet"] + (["--format", fmt] if fmt else [])
    return subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, check=True).stdout


def lib_call(req):
    """The package's call for a JSON request."""
    o = dict(req.get("options", {}))
    kw = {k: o[k] for k in ("precision", "fields", "operators", "fill", "keep_dangling") if k in o}
    if req["kind"] == "lines":
        return cellar.arrangement2d(np.array(req["lines"], float), **kw)
    kw.pop("keep_dangling", None)
    if req["kind"] == "polygons":
        return cellar.polygons([[np.array(r, float) for r in p] for p in req["polygons"]],
                               req["op"], **kw)
    return cellar.solids([(np.array(s["V"], float), s["FV"]) for s in req["solids"]],
                         req.get("op"), **kw)


def no_ms(x):
    if isinstance(x, dict):
        return {k: no_ms(v) for k, v in x.items() if k != "ms"}
    if isinstance(x, list):
        return [no_ms(v) for v in x]
    return x


def same_values(a, b):
    a, b = np.asarray(a), np.asarray(b)
    if a.size == 0 and b.size == 0:
        return True
    if a.shape != b.shape:
        return False
    if a.dtype.kind in "iu" and b.dtype.kind in "iu":
        return np.array_equal(a.astype(np.int64), b.astype(np.int64))
    return np.array_equal(a.astype(np.float64), b.astype(np.float64))


def compare(name, req):
    import io
    try:
        r = lib_call(req)
    except Exception as e:  # noqa: BLE001
        fail(name + ": the library's call", repr(e))
        return
    z = np.load(io.BytesIO(cli(req, "npz")), allow_pickle=False)
    rest = json.loads(z["json"].tobytes()) if "json" in z.files else {}
    scalars = {"result.area": ("result", "area"), "result.volume": ("result", "volume")}
    lib_names = set(r) - set(scalars)
    cli_names = set(z.files) - {"json"}
    check(name + ": the same arrays as the CLI's npz (%d)" % len(cli_names),
          lib_names == cli_names, "library only %s, CLI only %s"
          % (sorted(lib_names - cli_names), sorted(cli_names - lib_names)))
    bad = [k for k in sorted(lib_names & cli_names) if not same_values(r[k], z[k])]
    check(name + ": every array equal to the CLI's", not bad,
          "; ".join("%s: library %s %s, CLI %s %s" % (k, r[k].dtype, r[k].tolist()[:8], z[k].dtype,
                                                       z[k].tolist()[:8]) for k in bad[:3]))
    for k, (a, b) in scalars.items():
        if k in r or b in rest.get(a, {}):
            want = rest.get(a, {}).get(b)
            got = float(r[k][0]) if k in r else None
            check(name + ": %s %s equals the CLI's %s" % (k, got, want), got == want)
    check(name + ": dim", r.dim == rest.get("dim"), "%s vs %s" % (r.dim, rest.get("dim")))
    check(name + ": stats but the times equal the CLI's",
          no_ms(r.stats) == no_ms(rest.get("stats", {})),
          "%s\n  vs %s" % (no_ms(r.stats), no_ms(rest.get("stats", {}))))
    want = json.loads(cli(req, None))
    got = cellar.run_json(req)
    check(name + ": run_json equals cellar run (but the times)", no_ms(got) == no_ms(want))
    return r


def seg_request(n, scale, options):
    p = rng.random((n, 2))
    d = (rng.random((n, 2)) - 0.5) * scale
    s = np.stack([p, p + d], axis=1)
    return {"kind": "lines", "lines": s.tolist(), "options": options}


readme = open("README.md").read()
m = re.search(r"### Line segments.*?```json\n(.*?)```", readme, re.S)
README_LINES = json.loads(m.group(1))

SQ_HOLE = [[[[0, 0], [2, 0], [2, 2], [0, 2]]],
           [[[1, 1], [3, 1], [3, 3], [1, 3]], [[1.5, 1.5], [2.5, 1.5], [2.5, 2.5]]]]
TOUCH = [[[[0, 0], [1, 0], [1, 1], [0, 1]]], [[[1, 0], [2, 0], [2, 1], [1, 1]]],
         [[[0, 1], [2, 1], [2, 2], [0, 2]], [[0.5, 1.25], [1.5, 1.25], [1.5, 1.75], [0.5, 1.75]]],
         [[[0.5, 1.25], [1.5, 1.25], [1.5, 1.75], [0.5, 1.75]]]]
TWO_IN_ONE = [[[[0, 0], [2, 0], [2, 2], [0, 2]], [[1, 1], [3, 1], [3, 3], [1, 3]]],
              [[[0, 0], [3, 0], [3, 0.5]]]]
QUADS = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
TRIS = [[a, b, c] for q in QUADS for (a, b, c) in ((q[0], q[1], q[2]), (q[0], q[2], q[3]))]


def cube(o, s=1.0, faces=TRIS):
    V = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float) * s + o
    return {"V": V.tolist(), "FV": faces}


INSIDE_OUT = cube(0.5, faces=[f[::-1] for f in TRIS])

CASES = {
    "300 random segments, operators": seg_request(300, 0.3, {"operators": True}),
    "2000 random segments, dangling kept": seg_request(2000, 0.05, {"keep_dangling": True}),
    "random segments, fields V,EV,stats": seg_request(200, 0.3, {"fields": ["V", "EV", "stats"]}),
    "README's lines example": README_LINES,
    "polygons with a hole, op -": {"kind": "polygons", "polygons": SQ_HOLE, "op": ["-", 0, 1]},
    "polygons with a hole, nonzero, operators": {
        "kind": "polygons", "polygons": SQ_HOLE, "op": "xor",
        "options": {"operators": True, "fill": "nonzero"}},
    "touching squares and a hole filled, union": {"kind": "polygons", "polygons": TOUCH,
                                                  "op": "union"},
    "touching squares, expression": {"kind": "polygons", "polygons": TOUCH,
                                     "op": ["-", ["+", 0, 1, 2], 3]},
    "two rings in one polygon, fill odd": {"kind": "polygons", "polygons": TWO_IN_ONE,
                                           "op": "union", "options": {"fill": "odd"}},
    "two rings in one polygon, fill nonzero": {"kind": "polygons", "polygons": TWO_IN_ONE,
                                               "op": "union", "options": {"fill": "nonzero"}},
    "two rings in one polygon, fill positive": {"kind": "polygons", "polygons": TWO_IN_ONE,
                                                "op": "intersection",
                                                "options": {"fill": "positive"}},
    "polygons, fields result": {"kind": "polygons", "polygons": SQ_HOLE, "op": "union",
                                "options": {"fields": ["result"]}},
    "polygons, fields V,FV,membership,result": {
        "kind": "polygons", "polygons": TOUCH, "op": "intersection",
        "options": {"fields": ["V", "FV", "membership", "result"]}},
    "polygons, fields stats": {"kind": "polygons", "polygons": SQ_HOLE, "op": "union",
                               "options": {"fields": ["stats"]}},
    "two cubes, union": {"kind": "solids", "solids": [cube(0), cube(0.5)], "op": "union"},
    "two cubes, no op, operators": {"kind": "solids", "solids": [cube(0), cube(0.5)],
                                    "options": {"operators": True}},
    "three cubes, expression, quads": {
        "kind": "solids", "solids": [cube(0, 2, QUADS), cube(1, 1, QUADS), cube(-0.5, 1, QUADS)],
        "op": ["-", 0, ["+", 1, 2]]},
    "a cube turned inside out, intersection": {"kind": "solids",
                                               "solids": [cube(0), INSIDE_OUT],
                                               "op": "intersection"},
    "cubes, fields result": {"kind": "solids", "solids": [cube(0), cube(0.5)], "op": "difference",
                             "options": {"fields": ["result"]}},
    "cubes, fields V,CV,stats, fill nonzero": {
        "kind": "solids", "solids": [cube(0), cube(0.5)], "op": "xor",
        "options": {"fields": ["V", "CV", "stats"], "fill": "nonzero"}},
}

for name, req in CASES.items():
    r = compare(name, req)
    if name.startswith("a cube turned inside out") and r is not None:
        check(name + ": a warning says so and the volume is the overlap's",
              r.stats.get("warnings") and abs(r.volume - 0.125) < 1e-12,
              "%s %s" % (r.stats.get("warnings"), r.volume))

# the conveniences, on results compared above
r = cellar.arrangement2d(np.array(CASES["300 random segments, operators"]["lines"]),
                         operators=True)
d1, d2 = r.operators["d1"], r.operators["d2"]
check("operators are csr_matrix with d1 @ d2 = 0",
      type(d1).__name__ == "csr_matrix" and (d1 @ d2).count_nonzero() == 0
      and d1.shape == (len(r["V"]), len(r["EV"])))
check("FV rows rebuilt from indptr/indices", len(r.FV) == r.stats["F"]
      and all(np.array_equal(a, r["FV.indices"][r["FV.indptr"][i]:r["FV.indptr"][i + 1]])
              for i, a in enumerate(r.FV)))
r4 = cellar.arrangement2d(np.array(CASES["300 random segments, operators"]["lines"]).reshape(-1, 4))
check("segments as (n, 4) give the (n, 2, 2) arrangement",
      np.array_equal(r4["V"], r["V"]) and np.array_equal(r4["EV"], r["EV"]))
r = lib_call(CASES["polygons with a hole, nonzero, operators"])
check("membership is a csr_matrix faces x inputs",
      r.membership.shape == (r.stats["F"], 2) and r.membership.nnz > 0)

# ---- overlays against shapely -------------------------------------------------------------------
try:
    import shapely
    from shapely.geometry import Polygon, MultiPolygon, box
    from shapely.ops import unary_union
    from shapely.validation import explain_validity
    HAVE_SHAPELY = True
except ImportError:
    HAVE_SHAPELY = False
    fail("shapely is needed for the overlay checks (apt-get install python3-shapely)")


def convex(cx, cy, r, k=9):
    a = np.sort(rng.random(k) * 2 * math.pi)
    rr = r * (0.5 + rng.random(k))
    return Polygon(np.c_[cx + rr * np.cos(a), cy + rr * np.sin(a)]).convex_hull


def holed(cx, cy, r):
    out = box(cx - r, cy - r, cx + r, cy + r)
    return out.difference(box(cx - r / 3, cy - r / 2, cx + r / 4, cy + r / 3))


def reference(gs, op):
    if op == "union":
        return unary_union(gs)
    acc = gs[0]
    for g in gs[1:]:
        acc = {"intersection": acc.intersection, "xor": acc.symmetric_difference}.get(
            op, acc.difference)(g)
    return acc


def overlay(name, gs):
    scale = sum(g.area for g in gs)
    for op in ("union", "intersection", "difference", "xor"):
        want = reference(gs, op).area
        try:
            r = cellar.polygons(gs, op)
        except cellar.Error as e:
            fail("%s %s" % (name, op), repr(e))
            continue
        g = r.geometry
        good = abs(r.area - want) <= 1e-9 * max(scale, 1e-300)
        check("%s %s: area %.12g, shapely's %.12g" % (name, op, r.area, want), good)
        check("%s %s: the geometry is valid, of that area" % (name, op),
              g.is_valid and abs(g.area - r.area) <= 1e-9 * max(scale, 1e-300),
              "%s %s" % (explain_validity(g), g.area))


if HAVE_SHAPELY:
    for i in range(6):
        overlay("random convex pair %d" % i, [convex(0, 0, 1), convex(rng.random(), rng.random(), 1)])
    for i in range(3):
        overlay("random convex set of 4 (%d)" % i,
                [convex(rng.random() * 2, rng.random() * 2, 1) for _ in range(4)])
    overlay("polygons with holes", [holed(0, 0, 1), holed(0.6, 0.3, 1), convex(0.2, 0.1, 0.8)])
    overlay("touching squares", [box(0, 0, 1, 1), box(1, 0, 2, 1), box(0, 1, 2, 2),
                                 box(0.5, 0.5, 1.5, 1.5)])
    mp = MultiPolygon([box(0, 0, 1, 1), box(2, 0, 3, 1)])
    overlay("a MultiPolygon and a bar", [mp, box(0.5, 0.25, 2.5, 0.75)])
    r = cellar.polygons([mp, box(0.5, 0.25, 2.5, 0.75)], "union")
    check("a MultiPolygon is one input (2 membership columns)", r.membership.shape[1] == 2)
    lon = cellar.polygons([[np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)]], "union")
    check("a ring of arrays: the unit square's area 1", lon.area == 1.0)

# ---- 3D volumes ---------------------------------------------------------------------------------


def box_solid(lo, hi):
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    V = np.array([[(lo, hi)[x][0], (lo, hi)[y][1], (lo, hi)[z][2]]
                  for x in (0, 1) for y in (0, 1) for z in (0, 1)])
    return V, np.array(TRIS)


def inter_vol(boxes):
    lo = np.max([b[0] for b in boxes], axis=0)
    hi = np.min([b[1] for b in boxes], axis=0)
    return float(np.prod(np.clip(hi - lo, 0, None)))


def union_vol(boxes):
    from itertools import combinations
    return sum((-1) ** (k + 1) * inter_vol(c) for k in range(1, len(boxes) + 1)
               for c in combinations(boxes, k))


two = [((0, 0, 0), (2, 2, 2)), ((1, 1, 1), (3, 3.5, 3))]  # 8 + 10 - 1
r = cellar.solids([box_solid(*b) for b in two], "union")
check("two boxes' union: volume %r, closed form 17" % r.volume, abs(r.volume - 17) < 1e-12)
r = cellar.solids([box_solid(*b) for b in two], "intersection")
check("two boxes' intersection: volume %r, closed form 1" % r.volume, abs(r.volume - 1) < 1e-12)
for i in range(3):
    bs = []
    for _ in range(4):
        lo = rng.integers(0, 128, 3) / 64  # on a binary grid: no snapping
        bs.append((lo, lo + rng.integers(32, 96, 3) / 64))
    want = union_vol(bs)
    r = cellar.solids([box_solid(*b) for b in bs], "union")
    check("4 random boxes (%d): union %.12g, inclusion-exclusion %.12g" % (i, r.volume, want),
          abs(r.volume - want) <= 1e-9 * want)
    want = inter_vol(bs[:2])
    r = cellar.solids([box_solid(*b) for b in bs[:2]], "intersection")
    check("2 random boxes (%d): intersection %.12g, closed form %.12g" % (i, r.volume, want),
          abs(r.volume - want) <= 1e-9 * max(want, 1))


class Mesh:  # trimesh-like
    def __init__(self, V, F):
        self.vertices, self.faces = V, F


r = cellar.solids([Mesh(*box_solid((0, 0, 0), (1, 1, 1))), Mesh(*box_solid((0.5, 0, 0), (2, 1, 1)))],
                  "union")
check("objects with .vertices and .faces: union volume 2", abs(r.volume - 2) < 1e-12)

# ---- errors -------------------------------------------------------------------------------------


def raises(name, fn, status, pattern):
    try:
        fn()
    except cellar.Error as e:
        check("%s: status %d, %r" % (name, e.status, str(e)),
              e.status == status and re.search(pattern, str(e)) and isinstance(e, ValueError))
        return
    except Exception as e:  # noqa: BLE001
        fail(name, "raised %r, not cellar.Error" % e)
        return
    fail(name, "no error")


seg = np.array([[0, 0, 1, 1], [0, 1, 1, 0], [0, 0, 1, 0]], float)
seg[1, 2] = np.nan
raises("a NaN segment coordinate", lambda: cellar.arrangement2d(seg), 422, r"\[1\]\[1\]\[0\]")
raises("a NaN polygon coordinate",
       lambda: cellar.polygons([[[[0, 0], [1, 0], [1, 1]]], [[[0, 0], [1, 0], [1, float("nan")]]]]),
       422, r"polygons\[1\] ring 0 point 2")
raises("an infinite solid vertex",
       lambda: cellar.solids([(np.where(np.arange(8)[:, None] == 3, np.inf,
                                        box_solid((0, 0, 0), (1, 1, 1))[0]), TRIS)]),
       422, r"solids\[0\]")
raises("a bad op", lambda: cellar.polygons(SQ_HOLE, "unoin"), 422, r"^op")
raises("an op index out of range", lambda: cellar.polygons(SQ_HOLE, ["-", 0, 7]), 422,
       r"op.*7.*out of range")
raises("a bad fields name", lambda: cellar.arrangement2d([[0, 0, 1, 1]], fields=["V", "FX"]),
       422, r"options\.fields\[1\]")
raises("a field refers to one not named", lambda: cellar.arrangement2d([[0, 0, 1, 1]],
                                                                      fields="FV"),
       422, r"refers to \"V\"")
raises("a face index out of range",
       lambda: cellar.solids([box_solid((0, 0, 0), (1, 1, 1)),
                              (box_solid((0, 0, 0), (1, 1, 1))[0], TRIS[:-1] + [[0, 1, 9]])]),
       422, r"solids\[1\]\.FV\[11\]")
raises("segments of a bad shape", lambda: cellar.arrangement2d(np.zeros((3, 3))), 422,
       r"segments")
raises("a bad fill", lambda: cellar.polygons(SQ_HOLE, fill="evenodd"), 422, r"fill")
raises("run_json of no JSON", lambda: cellar.run_json("{"), 400, r".")

# ---- progress and cancel ------------------------------------------------------------------------
big = rng.random((120000, 2, 2))
big[:, 1] = big[:, 0] + (big[:, 1] - 0.5) * 0.05
seen = []
t0 = time.monotonic()
r = cellar.arrangement2d(big, fields="stats", progress=lambda s, f: seen.append((s, f)))
full = time.monotonic() - t0
fr = [f for _, f in seen]
check("progress: %d reports, fractions never go back, the last 1 (%.2f s)" % (len(seen), full),
      len(seen) > 3 and all(a <= b for a, b in zip(fr, fr[1:])) and fr[-1] == 1.0
      and 0 <= fr[0] < 0.5, str(fr[:5] + fr[-3:]))
check("progress: the stages are those of stage_names('lines')",
      {s for s, _ in seen} <= set(cellar.stage_names("lines")) and len({s for s, _ in seen}) > 2,
      "%s vs %s" % ({s for s, _ in seen}, cellar.stage_names("lines")))


class Stop(Exception):
    pass


def stop_at_first(s, f):
    raise Stop(s)


t0 = time.monotonic()
try:
    cellar.arrangement2d(big, fields="stats", progress=stop_at_first)
    fail("an exception in progress cancels the run", "it ran to the end")
except Stop:
    dt = time.monotonic() - t0
    check("an exception in progress cancels the run and comes out (%.2f s of %.2f)" % (dt, full),
          dt < full / 2)


def interrupt_at_first(s, f):
    raise KeyboardInterrupt


try:
    cellar.polygons([[np.array([[0, 0], [1, 0], [1, 1]])]], progress=interrupt_at_first)
    fail("KeyboardInterrupt in progress", "it ran to the end")
except KeyboardInterrupt:
    ok("KeyboardInterrupt in progress: the run is canceled and it comes out")

old = signal.getsignal(signal.SIGINT)
signal.signal(signal.SIGINT, signal.default_int_handler)
timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
t0 = time.monotonic()
timer.start()
try:
    cellar.arrangement2d(big, fields="stats")
    fail("SIGINT during a run", "it ran to the end (%.2f s)" % (time.monotonic() - t0))
except KeyboardInterrupt:
    dt = time.monotonic() - t0
    check("SIGINT at 0.3 s: KeyboardInterrupt after %.2f s (the whole run: %.2f s)" % (dt, full),
          dt < max(0.3 + full / 3, 0.9) and dt < full)
timer.join()
signal.signal(signal.SIGINT, old)
r = cellar.arrangement2d([[0, 0, 1, 1], [0, 1, 1, 0], [0, 0, 1, 0]])
check("a run after the cancel works", r.stats["F"] == 1)

# the calls from several threads at once (reentrant)
outs = [None] * 4


def work(i):
    outs[i] = cellar.polygons(SQ_HOLE, "union", threads=1).area


ts = [threading.Thread(target=work, args=(i,)) for i in range(4)]
[t.start() for t in ts]
[t.join() for t in ts]
check("four Python threads at once give the same area", len(set(outs)) == 1 and outs[0] is not None,
      str(outs))

# ---- the README's examples ----------------------------------------------------------------------
m = re.search(r"<!-- python-examples -->(.*?)<!-- /python-examples -->", readme, re.S)
blocks = re.findall(r"```python\n(.*?)```", m.group(1), re.S) if m else []
check("the README's From Python section has 3 examples", len(blocks) == 3, str(len(blocks)))
import contextlib, io as _io  # noqa: E401
WANT = ["[array([1, 0, 2, 3], dtype=uint32), array([3, 2, 4, 5], dtype=uint32)] 2", "6.625", "1.875"]
for i, b in enumerate(blocks):
    out = _io.StringIO()
    try:
        with contextlib.redirect_stdout(out):
            exec(compile(b, "README example %d" % (i + 1), "exec"), {})
        last = out.getvalue().strip().splitlines()[-1]
        check("README example %d runs and prints %s" % (i + 1, WANT[i]), last.endswith(WANT[i]), last)
    except Exception as e:  # noqa: BLE001
        fail("README example %d runs" % (i + 1), repr(e))

sys.exit(summary())
