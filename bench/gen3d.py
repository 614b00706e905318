#!/usr/bin/env python3
"""gen3d.py — 3D inputs for the tests and the benchmark: closed solids, deterministic by seed.

Usage:
  gen3d.py cubes N SEED [--size S]   N randomly rotated cubes in [0,1]^3
  gen3d.py grid K [--step H]         a K x K x K grid of overlapping axis-aligned unit cubes
  gen3d.py tets N SEED [--size S]    N random tetrahedra in [0,1]^3
  gen3d.py larcubes FILE             the cuboids of a LAR.jl input (tests/data/mesh/
                                     fivecubes-input.json: 1-based FV in cuboid order)
  gen3d.py mesh FILE.off SCENE       a mesh (as read) and a second solid made from it:
                                     SCENE rot, box or shell (below)
  gen3d.py refine FILE.off N SCENE   the mesh refined to exactly N triangles (N >= its face
                                     count, even), then as mesh: SCENE rot, box or shell
Output (at least one; default --json -):
  --json PATH     a cellar request {"kind": "solids", "solids": [{"V": [[x,y,z],...],
                  "FV": [[v,...],...]}, ...]} (0-based indices; '-' = stdout)
  --options JSON  the request's "options" object, verbatim (e.g. '{"fields":["stats"]}')
  --off DIR       DIR/s0000.off, DIR/s0001.off, ...: one OFF file per solid, same order
  --info          one JSON line on stderr: counts and, for grid, the closed-form union volume
                  and arrangement counts

Every solid is closed and outward oriented (each face counter-clockwise seen from outside).
Both outputs print each coordinate with repr(), the shortest string that reads back as the same
double, so cellar (strtod) and cgal_bool (strtod) see identical numbers.  Standard library only;
random.Random(SEED) draws the same numbers on every machine (Python 3.2 and later); the rotations
also go through the C library's sin and cos, which glibc rounds correctly but others may not.

cubes: like the LAR.jl example examples/3d/randomcubes.jl (a cube of edge 0.5 centred at the
  origin, scaled by a random factor, rotated, translated by a random point of [0,1]^3), with the
  rotation about a random axis (uniform on the sphere) by a random angle (uniform in [0, 2pi)).
  Cube i: centre uniform in [0,1]^3, edge S * (0.5 + u), u uniform in [0,1) (mean S).  Default
  S = 0.5 * (10 / N)^(1/3): 0.5 for N = 10 (as the LAR.jl examples: fivecubes-input.json has
  edges 0.50 to 0.84), and for any N the cubes' total volume N * 1.25 * S^3 = 15.6 / 10 stays
  the same, so every point is covered by about as many cubes and the arrangement grows about
  linearly with N rather than as N^3.  A rotated cube's vertices are rounded to doubles: its
  quads are planar only up to rounding (the 3D pipeline must cope).
grid: cube (i, j, k), 0 <= i, j, k < K, is [H i, H i + 1] x [H j, H j + 1] x [H k, H k + 1],
  H = 0.5 by default, so neighbours overlap by half along each axis.  When 1/H = m is an
  integer (H = 0.5: m = 2), every plane x = H t, 0 <= t <= L with L = K - 1 + m, is a face
  plane of some cube, and every point of the box [0, H (K-1) + 1]^3 lies in some cube, so:
    union volume    (H (K - 1) + 1)^3              K = 10, H = 0.5: 5.5^3 = 166.375
    bounded cells   L^3 small cubes of edge H      K = 10, H = 0.5: 11^3 = 1331
    vertices        (L + 1)^3                                       1728
    edges           3 L (L + 1)^2                                   4752
    faces           3 L^2 (L + 1)                                   4356
  (V - E + F - C = 1: a ball).  Small cube t covers [H t, H (t+1)] per axis and lies in the
  cubes i with t - m + 1 <= i <= t: 1 to m^3 of them.  All faces are axis-aligned and many are
  coplanar and overlapping: the hard case of the pipeline's coplanar merging.
tets: tetrahedron i: centre uniform in [0,1]^3, four vertices centre + S * (uniform in
  [-1/2, 1/2])^3, redrawn while its volume is below S^3 / 100 (slivers).  Default S = twice
  the cubes' (1 for N = 10): a random tetrahedron fills only about 1/70 of its box.
mesh: the mesh M of FILE.off (its numbers kept as read) and, as tests/real3d.py builds them
  against CGAL:  rot    M turned by 0.7 rad about the axis (0.3, 1, 0.2) through the centre c of
                        its bounding box and moved by (0.15, 0.1, 0.05) * its largest extent e;
                 box    the box [c - (0.3, 0.2, *) e, c + (0.1, 0.25, *) e], z from 0.1 e below
                        M to 0.1 e above: through M from top to bottom;
                 shell  M scaled by 0.8 about c (inside M: the union is M, the difference a
                        shell).
refine: every face of FILE.off cut into a fan of triangles; k the most rounds such that
  N / 4^k is a whole number M of at least those triangles with M minus them even; the longest
  edges (ties by vertex indices) split at their midpoints, two triangles an edge, until there
  are M; then k rounds of Loop subdivision (every triangle into four, the surface smoothed:
  a real mesh refined as a scanner would give it, with no two triangles in one plane).  The
  surface stays closed and oriented; that it does not intersect itself is checked with CGAL
  (bench/mesh3.py does so for each size).
larcubes: faces grouped into solids by shared vertices, each quad [a,b,c,d] (LAR cuboid order)
  made the cycle [a,b,d,c], each face turned outward (the solids are convex).
"""
import json
import math
import os
import random
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
from offio import read_off  # noqa: E402  (tests/offio.py: one OFF reader for tests and bench)

# Faces of the cube whose corner (i, j, k) in {0,1}^3 is index 4 i + 2 j + k, outward.
CUBE_FV = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
# Faces of a positively oriented tetrahedron 0, 1, 2, 3 (det(v1-v0, v2-v0, v3-v0) > 0), outward.
TET_FV = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]


def default_size(n):
    return 0.5 * (10.0 / max(n, 1)) ** (1.0 / 3.0)


def rotation(rng):
    """Rodrigues' matrix of a rotation about a random unit axis by a random angle."""
    z = rng.uniform(-1.0, 1.0)
    phi = rng.uniform(0.0, 2.0 * math.pi)
    r = math.sqrt(max(0.0, 1.0 - z * z))
    x, y = r * math.cos(phi), r * math.sin(phi)
    a = rng.uniform(0.0, 2.0 * math.pi)
    c, s, t = math.cos(a), math.sin(a), 1.0 - math.cos(a)
    return [[t * x * x + c, t * x * y - s * z, t * x * z + s * y],
            [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c]]


def cubes(n, seed, size):
    rng = random.Random(seed)
    out = []
    for _ in range(n):
        centre = [rng.random() for _ in range(3)]
        edge = size * (0.5 + rng.random())
        R = rotation(rng)
        V = []
        for i in (0, 1):
            for j in (0, 1):
                for k in (0, 1):
                    p = [edge * (i - 0.5), edge * (j - 0.5), edge * (k - 0.5)]
                    V.append([centre[r] + R[r][0] * p[0] + R[r][1] * p[1] + R[r][2] * p[2]
                              for r in range(3)])
        out.append((V, CUBE_FV))
    return out


def grid(k, step):
    out = []
    for i in range(k):
        for j in range(k):
            for l in range(k):
                o = (step * i, step * j, step * l)
                V = [[o[0] + a, o[1] + b, o[2] + c] for a in (0.0, 1.0) for b in (0.0, 1.0)
                     for c in (0.0, 1.0)]
                out.append((V, CUBE_FV))
    return out


def det3(a, b, c):
    return (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
            a[2] * (b[0] * c[1] - b[1] * c[0]))


def tets(n, seed, size):
    rng = random.Random(seed)
    out = []
    for _ in range(n):
        centre = [rng.random() for _ in range(3)]
        while True:
            V = [[centre[r] + size * (rng.random() - 0.5) for r in range(3)] for _ in range(4)]
            d = det3(*[[V[i][r] - V[0][r] for r in range(3)] for i in (1, 2, 3)])
            if abs(d) / 6.0 >= size ** 3 / 100.0:
                break
        if d < 0:
            V[1], V[2] = V[2], V[1]
        out.append((V, TET_FV))
    return out


def larcubes(path):
    with open(path) as f:
        d = json.load(f)
    V = d["V"]
    FV = [[q[0] - 1, q[1] - 1, q[3] - 1, q[2] - 1] for q in d["FV"]]
    parent = list(range(len(V)))  # union-find of the vertices over the faces

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for q in FV:
        for v in q[1:]:
            parent[find(v)] = find(q[0])
    groups = {}
    for q in FV:
        groups.setdefault(find(q[0]), []).append(q)
    out = []
    for faces in groups.values():
        used = sorted({v for q in faces for v in q})
        index = {v: i for i, v in enumerate(used)}
        W = [list(map(float, V[v])) for v in used]
        centre = [sum(w[r] for w in W) / len(W) for r in range(3)]
        F = []
        for q in faces:
            c = [index[v] for v in q]
            p = [W[v] for v in c]
            n = [0.0, 0.0, 0.0]  # Newell normal
            for a in range(len(p)):
                u, w = p[a], p[(a + 1) % len(p)]
                n[0] += (u[1] - w[1]) * (u[2] + w[2])
                n[1] += (u[2] - w[2]) * (u[0] + w[0])
                n[2] += (u[0] - w[0]) * (u[1] + w[1])
            fc = [sum(x[r] for x in p) / len(p) - centre[r] for r in range(3)]
            if sum(n[r] * fc[r] for r in range(3)) < 0:
                c.reverse()
            F.append(c)
        out.append((W, F))
    return out


def mesh(path, scene):
    V, F = read_off(path)
    return mesh_of(V, F, scene)


def mesh_of(V, F, scene):
    lo = [min(v[i] for v in V) for i in range(3)]
    hi = [max(v[i] for v in V) for i in range(3)]
    c = [(lo[i] + hi[i]) / 2 for i in range(3)]
    e = max(hi[i] - lo[i] for i in range(3))

    def turned(R, t, sc):
        return [[sum(R[a][b] * (v[b] - c[b]) for b in range(3)) * sc + c[a] + t[a]
                 for a in range(3)] for v in V]
    if scene == "rot":
        u = [0.3, 1, 0.2]
        n = math.sqrt(sum(x * x for x in u))
        x, y, z = (t / n for t in u)
        co, si = math.cos(0.7), math.sin(0.7)
        R = [[co + x * x * (1 - co), x * y * (1 - co) - z * si, x * z * (1 - co) + y * si],
             [y * x * (1 - co) + z * si, co + y * y * (1 - co), y * z * (1 - co) - x * si],
             [z * x * (1 - co) - y * si, z * y * (1 - co) + x * si, co + z * z * (1 - co)]]
        other = (turned(R, [0.15 * e, 0.1 * e, 0.05 * e], 1.0), F)
    elif scene == "box":
        bl = [c[0] - 0.3 * e, c[1] - 0.2 * e, lo[2] - 0.1 * e]
        bh = [c[0] + 0.1 * e, c[1] + 0.25 * e, hi[2] + 0.1 * e]
        other = ([[x, y, z] for x in (bl[0], bh[0]) for y in (bl[1], bh[1])
                  for z in (bl[2], bh[2])], CUBE_FV)
    elif scene == "shell":
        I = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
        other = (turned(I, [0, 0, 0], 0.8), F)
    else:
        raise ValueError("unknown scene '%s' (rot, box or shell)" % scene)
    return [(V, F), other]


def split_longest(V, T, n):
    """Splits the longest edges of the closed triangle mesh (V, T) at their midpoints, two
    triangles an edge, until it has n triangles (n - len(T) even); passes over the edges from
    the longest, an edge at most once a pass and no triangle twice a pass."""
    if (n - len(T)) % 2:
        raise ValueError("refine: %d - %d must be even" % (n, len(T)))
    while len(T) < n:
        edges = {}
        for t, (a, b, c) in enumerate(T):
            for u, v in ((a, b), (b, c), (c, a)):
                edges.setdefault((u, v) if u < v else (v, u), []).append(t)

        def len2(k):
            return sum((V[k[0]][i] - V[k[1]][i]) ** 2 for i in range(3))
        used = bytearray(len(T))
        todo = (n - len(T)) // 2
        split = {}
        for k in sorted(edges, key=lambda k: (-len2(k), k)):
            if todo == 0:
                break
            ts = edges[k]
            if len(ts) != 2 or used[ts[0]] or used[ts[1]]:
                continue
            used[ts[0]] = used[ts[1]] = 1
            split[k] = len(V)
            V.append([(V[k[0]][i] + V[k[1]][i]) / 2 for i in range(3)])
            todo -= 1
        if not split:
            raise ValueError("refine: no edge left to split")
        U = []
        for t, (a, b, c) in enumerate(T):
            if not used[t]:
                U.append([a, b, c])
                continue
            for u, v, w in ((a, b, c), (b, c, a), (c, a, b)):
                m = split.get((u, v) if u < v else (v, u))
                if m is not None:
                    U += [[u, m, w], [m, v, w]]
                    break
        T = U
    return V, T


def loop_round(V, T):
    """One round of Loop subdivision of the closed triangle mesh (V, T): every triangle into
    four, edge points 3/8 (a + b) + 1/8 (c + d), old vertices moved by Loop's weights."""
    opp = {}
    nbr = [set() for _ in V]
    for a, b, c in T:
        for u, v, w in ((a, b, c), (b, c, a), (c, a, b)):
            opp.setdefault((u, v) if u < v else (v, u), []).append(w)
            nbr[u].add(v)
            nbr[v].add(u)
    W = []
    for i, v in enumerate(V):
        k = len(nbr[i])
        beta = (5 / 8 - (3 / 8 + math.cos(2 * math.pi / k) / 4) ** 2) / k
        s = [sum(V[j][a] for j in nbr[i]) for a in range(3)]
        W.append([(1 - k * beta) * v[a] + beta * s[a] for a in range(3)])
    mid = {}
    for e, ws in opp.items():
        if len(ws) != 2:
            raise ValueError("refine: the mesh is not closed and manifold")
        a, b = e
        c, d = ws
        mid[e] = len(W)
        W.append([3 / 8 * (V[a][i] + V[b][i]) + 1 / 8 * (V[c][i] + V[d][i]) for i in range(3)])
    U = []
    for a, b, c in T:
        ab = mid[(a, b) if a < b else (b, a)]
        bc = mid[(b, c) if b < c else (c, b)]
        ca = mid[(c, a) if c < a else (a, c)]
        U += [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
    return W, U


def refine(path, n, scene):
    V, F = read_off(path)
    T = []
    for f in F:
        T.extend([f[0], f[k], f[k + 1]] for k in range(1, len(f) - 1))
    if n < len(T):
        raise ValueError("refine: N = %d is below the mesh's %d triangles" % (n, len(T)))
    # the most Loop rounds k such that N / 4^k is a whole number of at least the mesh's
    # triangles, at an even distance from them (an edge split adds two)
    k = 0
    while n % 4 ** (k + 1) == 0 and n // 4 ** (k + 1) >= len(T) and \
            (n // 4 ** (k + 1) - len(T)) % 2 == 0:
        k += 1
    V, T = split_longest(V, T, n // 4 ** k)
    for _ in range(k):
        V, T = loop_round(V, T)
    return mesh_of(V, T, scene)


def write_json(solids, options, f):
    f.write('{"kind": "solids", ')
    if options is not None:
        f.write('"options": %s, ' % json.dumps(options, separators=(",", ":")))
    f.write('"solids": [')
    for s, (V, FV) in enumerate(solids):
        f.write(",\n" if s else "\n")
        f.write('{"V": [%s], "FV": [%s]}' % (
            ", ".join("[%r, %r, %r]" % tuple(v) for v in V),
            ", ".join("[%s]" % ", ".join(str(i) for i in q) for q in FV)))
    f.write("]}\n")


def write_off(solids, d):
    os.makedirs(d, exist_ok=True)
    for s, (V, FV) in enumerate(solids):
        with open(os.path.join(d, "s%04d.off" % s), "w") as f:
            f.write("OFF\n%d %d 0\n" % (len(V), len(FV)))
            for v in V:
                f.write("%r %r %r\n" % tuple(v))
            for q in FV:
                f.write("%d %s\n" % (len(q), " ".join(str(i) for i in q)))


def die(msg):
    sys.stderr.write("gen3d: %s\n(gen3d.py --help for usage)\n" % msg)
    sys.exit(2)


def main(argv):
    if not argv or argv[0] in ("-h", "--help"):
        sys.stdout.write(__doc__)
        return 0
    pos, opt = [], {}
    i = 0
    while i < len(argv):
        a = argv[i]
        if a in ("--size", "--step", "--json", "--off", "--options"):
            if i + 1 >= len(argv):
                die("%s needs a value" % a)
            opt[a] = argv[i + 1]
            i += 2
        elif a == "--info":
            opt[a] = True
            i += 1
        elif a.startswith("--"):
            die("unknown option %s" % a)
        else:
            pos.append(a)
            i += 1
    if not pos:
        die("no generator (cubes, grid, tets, larcubes, mesh or refine)")
    kind, args = pos[0], pos[1:]
    info = {"kind": kind}
    try:
        if kind in ("cubes", "tets") and len(args) == 2:
            n, seed = int(args[0]), int(args[1])
            size = float(opt.get("--size", (1 if kind == "cubes" else 2) * default_size(n)))
            if n < 1 or not size > 0:
                die("N must be >= 1 and S > 0")
            solids = (cubes if kind == "cubes" else tets)(n, seed, size)
            info["size"] = size
        elif kind == "grid" and len(args) == 1:
            k, h = int(args[0]), float(opt.get("--step", 0.5))
            if k < 1 or not 0 < h <= 1:
                die("K must be >= 1 and 0 < H <= 1")
            solids = grid(k, h)
            m = round(1 / h)
            if abs(m * h - 1) < 1e-12:
                L = k - 1 + m
                info.update(union_volume=(h * (k - 1) + 1) ** 3, cells=L ** 3,
                            V=(L + 1) ** 3, E=3 * L * (L + 1) ** 2, F=3 * L * L * (L + 1))
        elif kind == "larcubes" and len(args) == 1:
            solids = larcubes(args[0])
        elif kind == "mesh" and len(args) == 2:
            solids = mesh(args[0], args[1])
        elif kind == "refine" and len(args) == 3:
            solids = refine(args[0], int(args[1]), args[2])
        else:
            die("bad arguments for '%s'" % kind)
    except (ValueError, OSError, IndexError) as e:
        die(str(e))
    options = None
    if "--options" in opt:
        try:
            options = json.loads(opt["--options"])
        except ValueError as e:
            die("--options: %s" % e)
    if "--json" not in opt and "--off" not in opt:
        opt["--json"] = "-"
    if "--off" in opt:
        write_off(solids, opt["--off"])
    if "--json" in opt:
        if opt["--json"] == "-":
            write_json(solids, options, sys.stdout)
        else:
            with open(opt["--json"], "w") as f:
                write_json(solids, options, f)
    if "--info" in opt:
        info.update(solids=len(solids), vertices=sum(len(V) for V, _ in solids),
                    faces=sum(len(F) for _, F in solids))
        sys.stderr.write(json.dumps(info) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
