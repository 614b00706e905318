#!/usr/bin/env python3
"""winding3d.py — solids that pass through themselves, by winding number (issue 26).

Usage: winding3d.py [BUILD_DIR]   (tests/t_winding3d.sh runs it; the binaries are $CELLAR_BIN,
default build/cellar, and $CELLAR_BUILD/tests/ref/cgal_bool, default build; a BUILD_DIR argument
sets both.  CELLAR_STRESS=N: N random rounds of every random family instead of the default
sample of 90 box cases, 4 rings and 10 CGAL scenes; CELLAR_DUMP=DIR keeps the inputs of every
failing case in DIR/CASE)

A solid may be several overlapping closed surfaces, pass through itself or have inside-out
parts: every cell gets the solid's winding number there, and fill (positive, nonzero, odd)
says which cells are inside.  Families, each written as ONE solid (one OFF file) unless said:
  boxes      2 to 5 axis-aligned boxes (on the lattice {0, 1/4, ..., 1}, so that faces coincide
             and boxes touch; on tenths, which are no dyadic values; or uniform doubles), at
             random one of them inside out (faces reversed): the union's volume under the three
             fill rules against the exact reference by coordinate compression (the winding of an
             elementary box is the sum of +1 / -1 over the boxes covering it); and the merged
             boxes as solid 0 with another box as solid 1 (a file of its own): intersection and
             difference (solid 0's inside by the positive and by the odd rule);
  pentagram  the prism on the star polygon {5/2} (caps: fans of five triangles from the centre,
             so that the inner pentagon is covered twice): positive = star outline * h, odd =
             (outline - inner pentagon) * h, the cells of winding 2 add up to the pentagon's,
             and membership's "data" has a 2;
  twice      a box whose surface is given twice (duplicated vertices, shared vertices, and as
             one object of an OBJ file, less a second object): positive = nonzero = the box,
             odd = 0;
  inverted   an inside-out box beside a box: positive = the box, nonzero = odd = both; a box and
             itself inside out: 0; a hollow box (an inside-out box inside a box, apart from its
             walls or on its floor): the shell's volume under every rule;
  frame      a square frame (small integers) as one tube of 4 mitred segments whose end caps lie
             on one another: a closed surface touching itself in a face, the frame under every
             rule; with a 5th segment on the 1st: 8 positive, 6 odd;
  ring       a square tube swept about z along a regular N-gon over N + 4 segments (the last 4
             on the first 4, with the same doubles; as duplicated and as shared vertices), with
             end caps: positive = nonzero = the closed ring, odd = the ring minus the 4 doubled
             segments, the cells of winding 2 add up to those segments; swept once around, its
             end caps on one another: the ring; swept twice around (its caps coincide, facing
             opposite ways): positive = the ring, odd = 0.  The ring's volumes: divergence
             theorem on the closed ring's and the segments' meshes;
  cgal       2 to 4 closed meshes (tests/data/mesh/real's knight, bumpy, bunny and cheburashka,
             turned cubes, icosahedra), normalised and moved by random rigid motions so that
             they overlap, as one solid: the union's volume against CGAL's union of the same
             meshes as separate solids (tests/ref/cgal_bool; its volume leaves out cavities, as
             the positive rule does), and the intersection with another mesh against CGAL's
             (union, then intersection with it);
  cow        tests/data/mesh/real/cow.off, which passes through itself: accepted, with a warning
             that says so.
A solid whose signed volume is negative is turned over as a whole, with a warning "inward
oriented" (core/solid.c, check_volume: a mesh oriented inward is taken as its solid): its
windings are the opposite of the input's (a box inside out alone is a box; boxes whose inside-out
box outweighs the others likewise), and the references follow.  On every case, the invariants:
every bounded cell has a positive volume; for every solid, the sum over the cells of (winding
number * volume) is the absolute value of the signed volume of its input surface (divergence
theorem on its faces, fan-triangulated), with the warning exactly when that is negative; and the
warning that a solid passes through itself, where expected (and not where its surfaces are
apart), in its documented form, its point on both faces it names (or, for a pair overlapping in
a plane, on the first, the second in its plane).  Agreement: within the snapping bound,
stats.precision times the boundary area of the inputs, plus 1e-9 relative (as real3d.py).

Prints "ok ..." / "FAIL ..." per check and "N passed, N failed" last.
"""
import json
import math
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from tally import fail, ok, summary  # noqa: E402
from offio import read_off  # noqa: E402

if len(sys.argv) > 1:
    CEL = os.path.join(sys.argv[1], "cellar")
    BUILD = sys.argv[1]
else:
    BUILD = os.environ.get("CELLAR_BUILD", "build") or "build"
    CEL = os.environ.get("CELLAR_BIN", "") or os.path.join(BUILD, "cellar")
CGAL = os.path.join(BUILD, "tests/ref/cgal_bool")
HERE = os.path.dirname(os.path.abspath(__file__))
REAL = os.path.join(HERE, "data/mesh/real")
STRESS = int(os.environ.get("CELLAR_STRESS", "0") or 0)
DUMP = os.environ.get("CELLAR_DUMP", "")
TIMEOUT = 300
WORST = [0.0, ""]  # worst |ours - reference| / bound


# ---- meshes -------------------------------------------------------------------------------

def write_off(path, V, Fc):
    with open(path, "w") as f:
        f.write("OFF\n%d %d 0\n" % (len(V), len(Fc)))
        for v in V:
            f.write("%.17g %.17g %.17g\n" % tuple(v))
        for fa in Fc:
            f.write(" ".join(map(str, [len(fa)] + list(fa))) + "\n")
    return path


def write_obj(path, objects):
    """objects: [(name, V, Fc)]; each an object "o" of its own."""
    with open(path, "w") as f:
        base = 1
        for name, V, Fc in objects:
            f.write("o %s\n" % name)
            for v in V:
                f.write("v %.17g %.17g %.17g\n" % tuple(v))
            for fa in Fc:
                f.write("f " + " ".join(str(i + base) for i in fa) + "\n")
            base += len(V)
    return path


def merge(parts):
    """One vertex list and face list of several (V, Fc)."""
    V, Fc = [], []
    for pv, pf in parts:
        Fc += [[i + len(V) for i in f] for f in pf]
        V += [list(v) for v in pv]
    return V, Fc


def inverted(mesh):
    V, Fc = mesh
    return V, [list(reversed(f)) for f in Fc]


def cross(u, w):
    return [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]]


def signed_volume(V, Fc):
    """Divergence theorem over the faces, fan-triangulated, about the bounding box centre."""
    lo = [min(v[i] for v in V) for i in range(3)]
    hi = [max(v[i] for v in V) for i in range(3)]
    c = [(lo[i] + hi[i]) / 2 for i in range(3)]
    terms = []
    for f in Fc:
        p0 = [V[f[0]][k] - c[k] for k in range(3)]
        for i in range(1, len(f) - 1):
            p1 = [V[f[i]][k] - c[k] for k in range(3)]
            p2 = [V[f[i + 1]][k] - c[k] for k in range(3)]
            n = cross(p1, p2)
            terms.append((p0[0] * n[0] + p0[1] * n[1] + p0[2] * n[2]) / 6)
    return math.fsum(terms)


def area(V, Fc):
    a = []
    for f in Fc:
        p0 = V[f[0]]
        n = [0.0, 0.0, 0.0]
        for i in range(1, len(f) - 1):
            p1, p2 = V[f[i]], V[f[i + 1]]
            c = cross([p1[k] - p0[k] for k in range(3)], [p2[k] - p0[k] for k in range(3)])
            n = [n[k] + c[k] for k in range(3)]
        a.append(math.sqrt(sum(x * x for x in n)) / 2)
    return math.fsum(a)


# a box's corners: index 4 * ix + 2 * iy + iz; its faces facing out
CUBE_F = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]


def box(lo, hi):
    return [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])], \
        [list(f) for f in CUBE_F]


def triangulated(mesh):
    V, Fc = mesh
    return V, [[f[0], f[i], f[i + 1]] for f in Fc for i in range(1, len(f) - 1)]


def icosahedron():
    p = (1 + math.sqrt(5)) / 2
    V = []
    for a in (-1, 1):
        for b in (-p, p):
            V += [[0, a, b], [a, b, 0], [b, 0, a]]
    Fc = []
    for i in range(12):
        for j in range(i + 1, 12):
            for k in range(j + 1, 12):
                if all(abs(sum((V[x][t] - V[y][t]) ** 2 for t in range(3)) - 4) < 1e-9
                       for x, y in ((i, j), (j, k), (i, k))):
                    n = cross([V[j][t] - V[i][t] for t in range(3)], [V[k][t] - V[i][t] for t in range(3)])
                    Fc.append([i, j, k] if sum(n[t] * V[i][t] for t in range(3)) > 0 else [i, k, j])
    assert len(Fc) == 20
    return V, Fc


def rotation(u, a):
    n = math.sqrt(sum(x * x for x in u))
    x, y, z = (t / n for t in u)
    c, s = math.cos(a), math.sin(a)
    return [[c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s],
            [y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s],
            [z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)]]


def moved(mesh, R, sc, t):
    V, Fc = mesh
    return [[sum(R[a][b] * v[b] for b in range(3)) * sc + t[a] for a in range(3)] for v in V], Fc


def normalised(mesh):
    """Centred on the origin, its largest extent 1."""
    V, Fc = mesh
    lo = [min(v[i] for v in V) for i in range(3)]
    hi = [max(v[i] for v in V) for i in range(3)]
    c = [(lo[i] + hi[i]) / 2 for i in range(3)]
    e = max(hi[i] - lo[i] for i in range(3))
    return [[(v[i] - c[i]) / e for i in range(3)] for v in V], Fc


# ---- running ------------------------------------------------------------------------------

def cellar(files, op, fill=None, extra=None):
    opts = {"fields": ["stats", "membership", "result"]}
    if fill:
        opts["fill"] = fill
    if extra:
        opts.update(extra)
    try:
        r = subprocess.run([CEL, "--quiet", "solids"] + files + ["--op", op, "--options", json.dumps(opts)],
                           capture_output=True, text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        return None, "timed out after %d s" % TIMEOUT
    if r.returncode:
        return None, "exit %d: %s" % (r.returncode, r.stderr.strip()[:300])
    try:
        return json.loads(r.stdout), None
    except ValueError as e:
        return None, "bad JSON (%s): %s" % (e, r.stdout[:200])


def cgal(files, op, out=None):
    args = [CGAL, "--op", op] + (["--out", out] if out else []) + files
    try:
        r = subprocess.run(args, capture_output=True, text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        return None, "timed out after %d s" % TIMEOUT
    if r.returncode:
        return None, "exit %d: %s" % (r.returncode, r.stderr.strip()[:200])
    return json.loads(r.stdout.strip().split("\n")[-1]), None


def dump(case, files, why):
    if not DUMP:
        return
    d = os.path.join(DUMP, case.replace(" ", "_").replace("/", "_"))
    os.makedirs(d, exist_ok=True)
    for f in files:
        shutil.copy(f, d)
    with open(os.path.join(d, "README"), "a") as f:
        f.write(why + "\n")


def windings(out, nsolids):
    """The winding number of every solid in every bounded cell, from the membership CSR;
    None and why when it cannot be read."""
    m = out.get("membership")
    if not isinstance(m, dict) or m.get("format") != "csr":
        return None, "no CSR membership in the output"
    ncell, ns = m["shape"]
    if ns != nsolids:
        return None, "membership shape %r for %d solids" % (m["shape"], nsolids)
    ip, ix, data = m["indptr"], m["indices"], m.get("data")
    if len(ip) != ncell + 1 or ip[-1] != len(ix) or (data is not None and len(data) != len(ix)):
        return None, "membership is inconsistent: %d cells, indptr %d, indices %d, data %s" % (
            ncell, len(ip), len(ix), "-" if data is None else len(data))
    W = [[0] * nsolids for _ in range(ncell)]
    for c in range(ncell):
        for q in range(ip[c], ip[c + 1]):
            w = 1 if data is None else data[q]
            if w == 0:
                return None, "cell %d lists solid %d with winding 0" % (c, ix[q])
            W[c][ix[q]] = w
    if data is not None and all(w == 1 for w in data):
        return None, "membership has data though every winding is 1"
    return W, None


def near(name, got, want, bound, files=()):
    q = abs(got - want) / bound if bound > 0 else (0.0 if got == want else math.inf)
    if q > WORST[0]:
        WORST[0], WORST[1] = q, name
    if abs(got - want) <= bound:
        ok("%s: %.12g (reference %.12g, %.2f of the bound)" % (name, got, want, q))
        return True
    why = "%.17g, reference %.17g, bound %.3g" % (got, want, bound)
    fail(name, why)
    dump(name, files, name + ": " + why)
    return False


def closest_on_triangle(p, a, b, c):
    """The point of triangle abc closest to p (Ericson, Real-Time Collision Detection 5.1.5)."""
    def sub(u, w):
        return [u[0] - w[0], u[1] - w[1], u[2] - w[2]]

    def dot(u, w):
        return u[0] * w[0] + u[1] * w[1] + u[2] * w[2]

    def at(o, u, t):
        return [o[k] + t * u[k] for k in range(3)]

    ab, ac, ap = sub(b, a), sub(c, a), sub(p, a)
    d1, d2 = dot(ab, ap), dot(ac, ap)
    if d1 <= 0 and d2 <= 0:
        return a
    bp = sub(p, b)
    d3, d4 = dot(ab, bp), dot(ac, bp)
    if d3 >= 0 and d4 <= d3:
        return b
    vc = d1 * d4 - d3 * d2
    if vc <= 0 and d1 >= 0 and d3 <= 0:
        return at(a, ab, d1 / (d1 - d3))
    cp = sub(p, c)
    d5, d6 = dot(ab, cp), dot(ac, cp)
    if d6 >= 0 and d5 <= d6:
        return c
    vb = d5 * d2 - d1 * d6
    if vb <= 0 and d2 >= 0 and d6 <= 0:
        return at(a, ac, d2 / (d2 - d6))
    va = d3 * d6 - d5 * d4
    if va <= 0 and d4 - d3 >= 0 and d5 - d6 >= 0:
        return at(b, sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6)))
    den = 1 / (va + vb + vc)
    v, w = vb * den, vc * den
    return [a[k] + ab[k] * v + ac[k] * w for k in range(3)]


def plane_distance(V, fa, fb):
    """How far face fb's vertices are from face fa's plane (its Newell normal)."""
    n = [0.0, 0.0, 0.0]
    for i in range(len(fa)):
        c = cross(V[fa[i]], V[fa[(i + 1) % len(fa)]])
        n = [n[k] + c[k] for k in range(3)]
    ln = math.sqrt(sum(x * x for x in n))
    o = V[fa[0]]
    return max(abs(sum(n[k] * (V[j][k] - o[k]) for k in range(3))) / ln for j in fb)


def face_distance(p, V, f):
    return min(math.dist(p, closest_on_triangle(p, V[f[0]], V[f[i]], V[f[i + 1]]))
               for i in range(1, len(f) - 1))


SELF = re.compile(r"^solids\[(\d+)\]: the surface passes through itself: (\d+) pairs? of its faces cross or "
                  r"overlap, the first faces (\d+) and (\d+) near \(([^,]+), ([^,]+), ([^)]+)\)$")


def crossings(name, out, solids, expect):
    """The warnings that a solid passes through itself: present when expect[s] is True, absent
    when False; when present, in the documented form, and its point (when the solid's faces are
    known: not None) within a few grid steps of both faces it names, or, where the pair overlaps
    in a plane, of the first (core/arr3.c self_report: "overlapping: a vertex of one"), the
    second then in the first's plane."""
    st = out["stats"]
    h = st["precision"]
    seen = {}
    for x in st.get("warnings", []):
        if "passes through itself" not in x:
            continue
        m = SELF.match(x)
        if not m:
            fail("%s: self-crossing warning in its form" % name, x)
            continue
        seen[int(m.group(1))] = m
    for s, mesh in enumerate(solids):
        m = seen.get(s)
        if m is None:
            if expect[s]:
                fail("%s: solid %d warned to pass through itself" % (name, s),
                     "warnings %r" % st.get("warnings", []))
            elif expect[s] is False:
                ok("%s: solid %d not warned to pass through itself" % (name, s))
            continue
        if expect[s] is False:
            fail("%s: solid %d not warned to pass through itself" % (name, s), m.group(0))
            continue
        if mesh is None:
            ok("%s: solid %d warned to pass through itself (%s)" % (name, s, m.group(0)))
            continue
        V, Fc = mesh
        fa, fb = int(m.group(3)), int(m.group(4))
        p = [float(m.group(k)) for k in (5, 6, 7)]
        scale = max(abs(x) for v in V for x in v)
        tol = 4 * h + 1e-8 * scale
        if int(m.group(2)) < 1 or fa == fb or max(fa, fb) >= len(Fc):
            fail("%s: solid %d self-crossing warning names two of its faces" % (name, s), m.group(0))
            continue
        da, db = face_distance(p, V, Fc[fa]), face_distance(p, V, Fc[fb])
        what = m.group(0)[len("solids[0]: the surface passes through itself: "):]
        if da <= tol and db <= tol:
            ok("%s: solid %d warned to pass through itself, faces %d and %d at the point named (%s)"
               % (name, s, fa, fb, what))
        elif da <= tol and plane_distance(V, Fc[fa], Fc[fb]) <= tol:
            ok("%s: solid %d warned to pass through itself, coplanar faces %d and %d, the point on "
               "the first (%s)" % (name, s, fa, fb, what))
        else:
            fail("%s: solid %d self-crossing warning's faces at its point" % (name, s),
                 "%s: distances %.3g and %.3g, tolerance %.3g" % (m.group(0), da, db, tol))


def invariants(name, out, solids, files, crossing=None, located=True):
    """solids: [(V, Fc)] the input solids in order.  Every bounded cell's volume > 0; for every
    solid, sum over the cells of winding * volume == its signed volume.  crossing: per solid (or
    one value for all), whether it is warned to pass through itself (None: either way); located:
    whether the warning's point is checked against the faces it names."""
    if not isinstance(crossing, list):
        crossing = [crossing] * len(solids)
    if "stats" in out:
        crossings(name, out, solids if located else [None] * len(solids), crossing)
    st = out.get("stats", {})
    vols = st.get("volumes")
    h = st.get("precision")
    if vols is None or h is None:
        fail("%s: invariants" % name, "no stats.volumes or stats.precision")
        return None
    W, why = windings(out, len(solids))
    if W is None:
        fail("%s: membership" % name, why)
        dump(name, files, why)
        return None
    if len(W) != len(vols):
        fail("%s: membership" % name, "%d rows for %d cell volumes" % (len(W), len(vols)))
        return None
    bad = [(c, v) for c, v in enumerate(vols) if not v > 0]
    if bad:
        fail("%s: every cell's volume > 0" % name, "cells %r" % bad[:5])
        dump(name, files, "cell volumes %r" % bad[:5])
    else:
        ok("%s: all %d cell volumes > 0 (least %.3g)" % (name, len(vols), min(vols) if vols else 0))
    a = sum(area(*s) for s in solids)
    warns = st.get("warnings", [])
    for s, mesh in enumerate(solids):
        sv = signed_volume(*mesh)
        flipped = any(x.startswith("solids[%d]: inward oriented" % s) for x in warns)
        if abs(sv) <= h * area(*mesh):
            pass  # no volume (parts that cancel): either way
        elif (sv < 0) != flipped:
            fail("%s: solid %d turned over when inward" % (name, s),
                 "signed volume %.17g, warnings %r" % (sv, warns))
        elif sv < 0:
            ok("%s: solid %d, of negative signed volume, turned over (%s)" % (
                name, s, [x for x in warns if "inward" in x][0]))
        sv = abs(sv)
        got = math.fsum(W[c][s] * vols[c] for c in range(len(vols)))
        near("%s: solid %d sum(winding * volume) = signed volume" % (name, s), got, sv,
             h * a + 1e-9 * abs(sv), files)
    return W


def volume_check(name, files, areas, op, fill, want):
    out, err = cellar(files, op, fill)
    if out is None:
        fail("%s %s %s: cellar" % (name, op, fill or "positive"), err)
        dump(name, files, err)
        return None
    near("%s %s %s" % (name, op, fill or "positive"), out["result"]["volume"], want,
         out["stats"]["precision"] * sum(areas) + 1e-9 * abs(want), files)
    return out


# ---- boxes: coordinate compression ------------------------------------------------------------

def compress(boxes):
    """boxes: [(lo, hi, sign, solid)]; yields (volume, {solid: winding}) of every elementary
    box of the coordinate compression."""
    axes = [sorted(set([b[0][i] for b in boxes] + [b[1][i] for b in boxes])) for i in range(3)]
    for i in range(len(axes[0]) - 1):
        for j in range(len(axes[1]) - 1):
            for k in range(len(axes[2]) - 1):
                lo = (axes[0][i], axes[1][j], axes[2][k])
                hi = (axes[0][i + 1], axes[1][j + 1], axes[2][k + 1])
                w = {}
                for blo, bhi, sg, s in boxes:
                    if all(blo[t] <= lo[t] and hi[t] <= bhi[t] for t in range(3)):
                        w[s] = w.get(s, 0) + sg
                yield (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]), w


RULES = {"positive": lambda w: w > 0, "nonzero": lambda w: w != 0, "odd": lambda w: w % 2 == 1}


def random_box(rnd, mode):
    lo, hi = [], []
    for _ in range(3):
        if mode == "lattice":
            a, b = sorted(rnd.sample(range(5), 2))
            a, b = a / 4, b / 4
        elif mode == "tenths":
            a, b = sorted(rnd.sample(range(11), 2))
            a, b = a / 10, b / 10
        else:
            a, b = sorted((rnd.random(), rnd.random()))
            if b - a < 0.05:
                a, b = max(0.0, a - 0.05), min(1.0, b + 0.05)
        lo.append(a)
        hi.append(b)
    return lo, hi


def boxes_case(tmp, seed):
    rnd = random.Random(seed)
    mode = ("lattice", "tenths", "float")[seed % 3]
    k = rnd.randint(2, 5)
    flip = rnd.randrange(k) if seed % 4 == 1 or (seed % 4 == 3 and rnd.random() < 0.5) else -1
    bs = [random_box(rnd, mode) for _ in range(k)]
    name = "boxes seed %d (%s, %d boxes%s)" % (seed, mode, k,
                                               ", box %d inside out" % flip if flip >= 0 else "")
    meshes = [box(lo, hi) if i != flip else inverted(box(lo, hi)) for i, (lo, hi) in enumerate(bs)]
    M = merge(meshes)
    fm = write_off(os.path.join(tmp, "boxes.off"), *M)
    am = area(*M)
    sg = -1 if signed_volume(*M) < -1e-9 * am else 1  # turned over when inward (not on noise)
    if sg < 0:
        name += " (inward)"
    cells = list(compress([(lo, hi, (-1 if i == flip else 1) * sg, 0) for i, (lo, hi) in enumerate(bs)]))
    out = None
    for fill, rule in RULES.items():
        want = math.fsum(v for v, w in cells if rule(w.get(0, 0)))
        o = volume_check(name, [fm], [am], "union", fill, want)
        out = out or o
    if out is not None:
        invariants(name, out, [M], [fm])
    # the merged boxes and another box, a solid of its own
    blo, bhi = random_box(rnd, mode)
    Bm = box(blo, bhi)
    fb = write_off(os.path.join(tmp, "other.off"), *Bm)
    cells = list(compress([(lo, hi, (-1 if i == flip else 1) * sg, 0) for i, (lo, hi) in enumerate(bs)]
                          + [(blo, bhi, 1, 1)]))
    areas = [am, area(*Bm)]
    out = None
    for fill in ("positive", "odd"):
        rule = RULES[fill]
        inter = math.fsum(v for v, w in cells if rule(w.get(0, 0)) and w.get(1, 0) > 0)
        diff = math.fsum(v for v, w in cells if rule(w.get(0, 0)) and not w.get(1, 0) > 0)
        o = volume_check(name + " and a box", [fm, fb], areas, "intersection", fill, inter)
        volume_check(name + " and a box", [fm, fb], areas, "difference", fill, diff)
        out = out or o
    if out is not None:
        # (solid 0's warning was checked above)
        invariants(name + " and a box", out, [M, Bm], [fm, fb], [None, False], located=False)


# ---- pentagram prism --------------------------------------------------------------------------

def shoelace(P):
    return math.fsum(P[i][0] * P[(i + 1) % len(P)][1] - P[(i + 1) % len(P)][0] * P[i][1]
                     for i in range(len(P))) / 2


def pentagram(tmp, h=1.0, z0=0.0):
    outer = [(math.cos(math.pi / 2 + 2 * math.pi * i / 5), math.sin(math.pi / 2 + 2 * math.pi * i / 5))
             for i in range(5)]
    star = [outer[(2 * i) % 5] for i in range(5)]  # {5/2}: turns twice, counterclockwise
    # the inner pentagon: where the star's non-adjacent edges cross
    inner = []
    for i in range(5):
        for j in range(i + 2, 5):
            if (j + 1) % 5 == i:
                continue
            (ax, ay), (bx, by) = star[i], star[(i + 1) % 5]
            (cx, cy), (dx, dy) = star[j], star[(j + 1) % 5]
            den = (bx - ax) * (dy - cy) - (by - ay) * (dx - cx)
            t = ((cx - ax) * (dy - cy) - (cy - ay) * (dx - cx)) / den
            u = ((cx - ax) * (by - ay) - (cy - ay) * (bx - ax)) / den
            if 0 < t < 1 and 0 < u < 1:
                inner.append((ax + t * (bx - ax), ay + t * (by - ay)))
    assert len(inner) == 5

    def by_angle(P):
        return sorted(P, key=lambda p: math.atan2(p[1], p[0]))

    a_in = shoelace(by_angle(inner))
    a_out = shoelace(by_angle(inner + outer))
    n = 5
    V = [[x, y, z0] for x, y in star] + [[x, y, z0 + h] for x, y in star]
    V += [[0.0, 0.0, z0], [0.0, 0.0, z0 + h]]  # the caps' centres
    Fc = [[i, (i + 1) % n, n + (i + 1) % n, n + i] for i in range(n)]
    Fc += [[2 * n + 1, n + i, n + (i + 1) % n] for i in range(n)]  # top fan, facing up
    Fc += [[2 * n, (i + 1) % n, i] for i in range(n)]  # bottom fan, facing down
    name = "pentagram prism"
    f = write_off(os.path.join(tmp, "pentagram.off"), V, Fc)
    a = area(V, Fc)
    out = volume_check(name, [f], [a], "union", "positive", a_out * h)
    volume_check(name, [f], [a], "union", "nonzero", a_out * h)
    volume_check(name, [f], [a], "union", "odd", (a_out - a_in) * h)
    if out is None:
        return
    W = invariants(name, out, [(V, Fc)], [f], True)
    if W is None:
        return
    d = out.get("membership", {}).get("data")
    if d is not None and 2 in d and all(w in (1, 2) for w in d):
        ok("%s: membership data has winding 2 (%r)" % (name, d))
    else:
        fail("%s: membership data has winding 2, and only 1 and 2" % name, "data %r" % (d,))
    vols = out["stats"]["volumes"]
    near("%s: the cells of winding 2 are the inner pentagon" % name,
         math.fsum(vols[c] for c in range(len(vols)) if W[c][0] == 2), a_in * h,
         out["stats"]["precision"] * a + 1e-9 * a_in * h, [f])


# ---- a box twice; inside-out boxes ----------------------------------------------------------------

def twice(tmp):
    lo, hi = [0.1, 0.2, 0.3], [0.7, 0.9, 0.35]
    Bx = box(lo, hi)
    vb = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2])
    dup = merge([Bx, Bx])
    shared = (Bx[0], Bx[1] + Bx[1])
    for what, M in (("duplicated vertices", dup), ("shared vertices", shared)):
        name = "box twice (%s)" % what
        f = write_off(os.path.join(tmp, "twice.off"), *M)
        a = area(*M)
        out = volume_check(name, [f], [a], "union", "positive", vb)
        volume_check(name, [f], [a], "union", "nonzero", vb)
        volume_check(name, [f], [a], "union", "odd", 0.0)
        if out is not None:
            W = invariants(name, out, [M], [f], True)
            if W is not None:
                if len(W) == 1 and W[0][0] == 2:
                    ok("%s: one cell, winding 2" % name)
                else:
                    fail("%s: one cell, winding 2" % name, "windings %r" % W)
    # an OBJ object holding both surfaces is one solid; a second object is a solid of its own
    name = "box twice (OBJ object)"
    other = box([0.5, 0.5, 0.0], [1.0, 1.0, 1.0])
    f = write_obj(os.path.join(tmp, "twice.obj"), [("twice", dup[0], dup[1]), ("other", other[0], other[1])])
    a = [area(*dup), area(*other)]
    cells = list(compress([(lo, hi, 1, 0), (lo, hi, 1, 0), ([0.5, 0.5, 0.0], [1.0, 1.0, 1.0], 1, 1)]))
    for fill, rule in RULES.items():
        want = math.fsum(v for v, w in cells if rule(w.get(0, 0)) and not w.get(1, 0) > 0)
        out = volume_check(name + " minus a box", [f], a, "difference", fill, want)
        if fill == "odd" and out is not None:
            invariants(name, out, [dup, other], [f], [True, False])


def inside_out(tmp):
    Bn = box([0.0, 0.0, 0.0], [1.0, 0.5, 0.3])
    Bi = inverted(box([1.5, 0.1, 0.2], [1.9, 0.4, 1.1]))
    vn, vi = 0.15, 0.4 * 0.3 * 0.9
    M = merge([Bn, Bi])
    name = "inside-out box beside a box"
    f = write_off(os.path.join(tmp, "beside.off"), *M)
    a = area(*M)
    out = volume_check(name, [f], [a], "union", "positive", vn)
    volume_check(name, [f], [a], "union", "nonzero", vn + vi)
    volume_check(name, [f], [a], "union", "odd", vn + vi)
    if out is not None:
        W = invariants(name, out, [M], [f], False)
        if W is not None:
            if sorted(w[0] for w in W) == [-1, 1]:
                ok("%s: windings -1 and 1" % name)
            else:
                fail("%s: windings -1 and 1" % name, "windings %r" % W)
    # beside a box of the same volume: the signed volume is 0 but for rounding, which decides
    # nothing (core/solid.c some_part_thick: "its winding numbers are -1 and 1"); with a box
    # around the box and not the inside-out box, the intersection is the box
    M = merge([inverted(box([0.6, 0.2, 0.8], [0.9, 1.0, 0.9])), box([0.2, 0.2, 0.6], [0.5, 0.4, 1.0])])
    name = "inside-out box beside a box of the same volume"
    f = write_off(os.path.join(tmp, "same.off"), *M)
    Bc = box([0.1, 0.1, 0.5], [0.55, 0.45, 1.05])
    fc = write_off(os.path.join(tmp, "around.off"), *Bc)
    a = [area(*M), area(*Bc)]
    out = volume_check(name + " and a box around the box", [f, fc], a, "intersection", "positive", 0.024)
    volume_check(name + " and a box around the box", [f, fc], a, "difference", "positive", 0.0)
    volume_check(name + " and a box around the box", [f, fc], a, "difference", "nonzero", 0.024)
    if out is not None:
        invariants(name, out, [M, Bc], [f, fc], [False, False])
    # the inside-out box only: turned over, a box
    name = "inside-out box alone"
    f = write_off(os.path.join(tmp, "alone.off"), *Bi)
    a = area(*Bi)
    out = volume_check(name, [f], [a], "union", "positive", vi)
    volume_check(name, [f], [a], "union", "odd", vi)
    if out is not None:
        invariants(name, out, [Bi], [f], False)
    # a box and the same box inside out (its own vertices): winding 0 everywhere
    M = merge([Bn, inverted(Bn)])
    name = "box and itself inside out"
    f = write_off(os.path.join(tmp, "cancel.off"), *M)
    a = area(*M)
    out = None
    for fill in RULES:
        o = volume_check(name, [f], [a], "union", fill, 0.0)
        out = out or o
    if out is not None:
        invariants(name, out, [M], [f], True)
    # hollow: a box with an inside-out box inside it (not touching, then touching a wall)
    for what, ilo, ihi, cross_ in (("inside", [0.2, 0.3, 0.1], [0.7, 0.6, 0.8], False),
                                   ("on the floor", [0.2, 0.3, 0.0], [0.7, 0.6, 0.8], None)):
        olo, ohi = [0.0, 0.0, 0.0], [1.0, 1.0, 1.0]
        M = merge([box(olo, ohi), inverted(box(ilo, ihi))])
        name = "hollow box (%s)" % what
        f = write_off(os.path.join(tmp, "hollow.off"), *M)
        a = area(*M)
        want = 1.0 - (ihi[0] - ilo[0]) * (ihi[1] - ilo[1]) * (ihi[2] - ilo[2])
        out = None
        for fill in RULES:
            o = volume_check(name, [f], [a], "union", fill, want)
            out = out or o
        if out is not None:
            invariants(name, out, [M], [f], cross_)


# ---- a ring that overlaps itself ---------------------------------------------------------------

def ring_mesh(N, segs, R, w, phase, shared, caps):
    """A square tube (half width w, about radius R) swept about z along a regular N-gon over
    segs segments; section k is at angle phase + 2 pi (k mod N) / N, the same doubles for k and
    k + N (shared: the same vertices too)."""
    V, sec = [], []
    for k in range(segs + 1):
        if shared and k >= N:
            sec.append(sec[k - N])
            continue
        t = phase + 2 * math.pi * (k % N) / N
        c, s = math.cos(t), math.sin(t)
        idx = []
        for r, z in ((R - w, -w), (R + w, -w), (R + w, w), (R - w, w)):
            idx.append(len(V))
            V.append([r * c, r * s, z])
        sec.append(idx)
    Fc = []
    for k in range(segs):
        a, b = sec[k], sec[k + 1]
        for j in range(4):
            Fc.append([a[j], b[j], b[(j + 1) % 4], a[(j + 1) % 4]])
    if caps:
        Fc.append(list(sec[0]))
        Fc.append(list(reversed(sec[segs])))
    if signed_volume(V, Fc) < 0:
        Fc = [list(reversed(f)) for f in Fc]
    return V, Fc


def frame_seam(tmp):
    """A square frame (outer [0, 3]^2, hole [1, 2]^2, z in [0, 1]) as one tube of 4 mitred
    segments whose two end caps lie on one another (exact small integers): a closed surface
    that touches itself in that face; the frame, 8, under every rule.  With a fifth segment
    (the first one doubled, volume 2): 8 positive and nonzero, 6 odd."""
    inner = [(1, 1), (2, 1), (2, 2), (1, 2)]
    outer = [(0, 0), (3, 0), (3, 3), (0, 3)]
    for segs, want in ((4, {"positive": 8.0, "nonzero": 8.0, "odd": 8.0}),
                       (5, {"positive": 8.0, "nonzero": 8.0, "odd": 6.0})):
        V, sec = [], []
        for k in range(segs + 1):
            (ix, iy), (ox, oy) = inner[k % 4], outer[k % 4]
            sec.append(list(range(len(V), len(V) + 4)))
            V += [[ix, iy, 0], [ox, oy, 0], [ox, oy, 1], [ix, iy, 1]]
        Fc = [[sec[k][j], sec[k + 1][j], sec[k + 1][(j + 1) % 4], sec[k][(j + 1) % 4]]
              for k in range(segs) for j in range(4)]
        Fc += [list(sec[0]), list(reversed(sec[segs]))]
        if signed_volume(V, Fc) < 0:
            Fc = [list(reversed(f)) for f in Fc]
        name = "square frame of %d segments, %s" % (
            segs, "its end caps on one another" if segs == 4 else "the first doubled")
        f = write_off(os.path.join(tmp, "frame%d.off" % segs), V, Fc)
        a = area(V, Fc)
        out = None
        for fill, v in want.items():
            o = volume_check(name, [f], [a], "union", fill, v)
            out = out or o
        if out is not None:
            invariants(name, out, [(V, Fc)], [f], None if segs == 4 else True)


def ring(tmp, N, R, w, phase, shared, label, seams=True):
    closed = ring_mesh(N, N, R, w, phase, True, False)
    vring = signed_volume(*closed)
    vseg = math.fsum(signed_volume(*ring_mesh(N, 1, R, w, phase + 2 * math.pi * k / N, False, True))
                     for k in range(4))
    name = "ring %s (N %d, %d segments, %s vertices)" % (label, N, N + 4,
                                                         "shared" if shared else "duplicated")
    M = ring_mesh(N, N + 4, R, w, phase, shared, True)
    f = write_off(os.path.join(tmp, "ring.off"), *M)
    a = area(*M)
    out = volume_check(name, [f], [a], "union", "positive", vring)
    volume_check(name, [f], [a], "union", "nonzero", vring)
    volume_check(name, [f], [a], "union", "odd", vring - vseg)
    if out is not None:
        W = invariants(name, out, [M], [f], True)
        if W is not None:
            vols = out["stats"]["volumes"]
            near("%s: the cells of winding 2 are the 4 doubled segments" % name,
                 math.fsum(vols[c] for c in range(len(vols)) if W[c][0] == 2), vseg,
                 out["stats"]["precision"] * a + 1e-9 * vseg, [f])
    if shared or not seams:
        return
    # swept once around, its end caps on one another: a closed surface touching itself there
    name = "ring %s (N %d, closed by its two caps)" % (label, N)
    M = ring_mesh(N, N, R, w, phase, False, True)
    f = write_off(os.path.join(tmp, "seam.off"), *M)
    a = area(*M)
    out = volume_check(name, [f], [a], "union", "positive", vring)
    volume_check(name, [f], [a], "union", "odd", vring)
    if out is not None:
        invariants(name, out, [M], [f])
    # swept twice around: winding 2 everywhere, its two caps on one another facing opposite ways
    name = "ring %s (N %d, swept twice around)" % (label, N)
    M = ring_mesh(N, 2 * N, R, w, phase, False, True)
    f = write_off(os.path.join(tmp, "ring2.off"), *M)
    a = area(*M)
    out = volume_check(name, [f], [a], "union", "positive", vring)
    volume_check(name, [f], [a], "union", "odd", 0.0)
    if out is not None:
        invariants(name, out, [M], [f], True)


# ---- against CGAL ---------------------------------------------------------------------------

SOURCES = {}


def source(kind):
    if kind not in SOURCES:
        if kind == "cube":
            SOURCES[kind] = triangulated(box([-0.5, -0.5, -0.5], [0.5, 0.5, 0.5]))
        elif kind == "icosahedron":
            SOURCES[kind] = normalised(icosahedron())
        else:
            SOURCES[kind] = normalised(read_off(os.path.join(REAL, kind + ".off")))
    return SOURCES[kind]


def random_motion(rnd, mesh, spread):
    R = rotation([rnd.random() - 0.5 for _ in range(3)], 2 * math.pi * rnd.random())
    return moved(mesh, R, 0.8 + 0.4 * rnd.random(), [spread * (rnd.random() - 0.5) for _ in range(3)])


CGAL_SETS = [["cube", "cube", "icosahedron"], ["decimated-knight", "decimated-knight"],
             ["bumpy", "decimated-knight", "icosahedron"], ["bunny", "cube"],
             ["icosahedron", "icosahedron", "cube", "cube"], ["bumpy", "bumpy"],
             ["cheburashka", "bunny", "cube"]]


def against_cgal(tmp, seed):
    rnd = random.Random(1000 + seed)
    kinds = CGAL_SETS[seed % len(CGAL_SETS)] if seed < len(CGAL_SETS) else \
        [rnd.choice(["cube", "icosahedron", "decimated-knight", "bumpy", "bunny", "cheburashka"])
         for _ in range(rnd.randint(2, 4))]
    name = "cgal seed %d (%s)" % (seed, " + ".join(kinds))
    parts = [random_motion(rnd, source(k), 0.5) for k in kinds]
    files = [write_off(os.path.join(tmp, "part%d.off" % i), *p) for i, p in enumerate(parts)]
    M = merge(parts)
    fm = write_off(os.path.join(tmp, "merged.off"), *M)
    am = area(*M)
    ref, err = cgal(files, "union", os.path.join(tmp, "U.off"))
    if ref is None:
        fail("%s union: CGAL" % name, err)
    out = None
    if ref is not None:
        out = volume_check(name, [fm], [am], "union", "positive", ref["volume"])
    # the merged solid and another mesh
    other = random_motion(rnd, source(rnd.choice(["cube", "icosahedron"])), 0.3)
    fb = write_off(os.path.join(tmp, "B.off"), *other)
    ab = area(*other)
    if ref is not None:
        ri, err = cgal([os.path.join(tmp, "U.off"), fb], "intersection")
        if ri is None:
            fail("%s and a solid intersection: CGAL" % name, err)
        else:
            volume_check(name + " and a solid", [fm, fb], [am, ab], "intersection", "positive", ri["volume"])
    if out is None:
        out, err = cellar([fm], "union")
        if out is None:
            fail("%s: cellar" % name, err)
            return
    invariants(name, out, [M], [fm])


# ---- the cow ---------------------------------------------------------------------------------

def cow():
    path = os.path.join(REAL, "cow.off")
    out, err = cellar([path], "union")
    if out is None:
        fail("cow: accepted", err)
        return
    ok("cow: accepted")
    invariants("cow", out, [read_off(path)], [path], True)


def main():
    global CEL
    if not os.path.exists(CEL):
        fail("%s is built" % CEL)
        return summary()
    rounds = STRESS if STRESS else 0
    with tempfile.TemporaryDirectory() as tmp:
        # one binary for the whole run, though the build directory be rebuilt meanwhile
        shutil.copy(CEL, os.path.join(tmp, "cellar"))
        CEL = os.path.join(tmp, "cellar")
        for s in range(rounds or 90):
            boxes_case(tmp, s)
        pentagram(tmp)
        twice(tmp)
        inside_out(tmp)
        frame_seam(tmp)
        ring(tmp, 16, 1.0, 0.2, 0.0, False, "a")
        ring(tmp, 16, 1.0, 0.2, 0.0, True, "a")
        rnd = random.Random(7)
        for s in range(rounds or 4):
            ring(tmp, rnd.randint(5, 40), 0.5 + rnd.random(), 0.05 + 0.15 * rnd.random(),
                 2 * math.pi * rnd.random(), False, "seed %d" % s, seams=STRESS > 0)
        if not os.access(CGAL, os.X_OK):
            fail("cgal_bool is built (%s)" % CGAL)
        else:
            for s in range(rounds or len(CGAL_SETS) + 3):
                against_cgal(tmp, s)
        cow()
    print("# worst: %.2f of the snapping bound (%s)" % (WORST[0], WORST[1]))
    return summary()


sys.exit(main())
