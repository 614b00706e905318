#!/usr/bin/env python3
"""contacts3d.py — the 3D Booleans on solids that touch, against closed forms and CGAL Nef.

Usage: contacts3d.py BUILD_DIR   (tests/t_contacts3d.sh runs it; CELLAR_STRESS=N runs N seeds of
every family instead of 4; CELLAR_DUMP=DIR keeps the inputs of every failing scene in DIR, with
a README of the expected and the wrong values)

Families: boxes, tetrahedra, triangular prisms and cubes turned about random axes, each with every
kind of contact it can make:
  v-f        a vertex on a face              v-e        a vertex on an edge
  v-v        a vertex on a vertex            e-e-cross  two edges crossing at a point
  e-e-col    collinear edges overlapping (partly, one inside the other, or equal)
  e-f        an edge in a face (wholly or partly)
  f-f        coplanar faces overlapping (partly, one inside the other, equal, sharing sides)
from outside (two solids on either side of the contact plane; the family's solid plays either
part, its partner is drawn from all the kinds that can play the other) and from inside (the
family's solid inside a box touching its walls from inside: a vertex on a wall, on an edge or
in a corner of the box, an edge along an edge of the box or in a wall, a face on a wall or on
three walls).  A third solid is added at every third seed: outside, a box on the far side of the
contact plane against the first solid's extreme plane; inside, a box on the container's lid.

Each scene is built in a local frame whose contact plane is z = 0, where every contact is exact
on the doubles: the touching features share their doubles (the tetrahedron's apex is the box
corner; a vertex on an axis-parallel edge has that edge's y; both solids' contact features have
z = 0), and what need not be exact (a vertex inside a face, two edges crossing) has a margin.
It is then placed in one of four ways, by seed (4 consecutive seeds of a family: all four):
  axis, on-grid     a random signed permutation of the axes, all coordinates multiples of 1/8
                    (a turned cube's vertices are dyadic: its rotation is rounded to 2^-10);
  axis, off-grid    the same with coordinates that are no dyadic values (0.1, 1/3, uniform
                    doubles, far from the origin: 1e4 + 0.1), the cubes turned in doubles: the
                    contacts still hold on the doubles (equal doubles stay equal), and still after
                    snapping to the grid (equal doubles snap alike);
  tilted, dyadic    the scene (coordinates multiples of 1/8) turned about a random axis by a
                    rotation rounded to 2^-10, every image exact (checked): contacts on slanted
                    planes, still exact on the doubles;
  tilted, off-grid  the same moved far from the origin (1e4 + 0.1, ...), every image exact.
Closed forms: every solid's volume, exactly (rationals, from its doubles; a face that is not
planar on the doubles is written as triangles, so that the solid is the same for everyone);
solids with disjoint interiors add up, an inner solid is inside its container: union = the sum
over the solids in no other, intersection = the inner solid's volume (container and inner alone)
or 0, difference = the first solid minus those it contains (0 when it is the inner one).

For each scene, first: the two solids touch as the family says, at a point, along a segment or
in pieces of faces (where CGAL Nef finds that their boundaries meet: cgal_nef --op contact, whose
vertices, edges and facets tell).  Then for union, intersection and difference: cellar's volume
(cellar solids ... --op OP) against the closed form and against CGAL Nef's (tests/ref/cgal_nef,
exact on the same doubles, whatever the contact), both within the snapping bound (precision *
the inputs' boundary area, plus 1e-12 relative, as real3d.py); and Nef's volume against the
closed form within 1e-9 of the inputs' volume sum (the reference checked too), and Nef's input
volumes likewise.

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

from tally import fail, ok, summary
from fractions import Fraction as Fr

B = sys.argv[1] if len(sys.argv) > 1 else "build"
CEL = os.path.join(B, "cellar")
NEF = os.path.join(B, "tests/ref/cgal_nef")
STRESS = int(os.environ.get("CELLAR_STRESS", "0") or 0)
DUMP = os.environ.get("CELLAR_DUMP", "")
WORST = [0.0, ""]  # worst |cellar - reference| / bound
NEF_WORST = [0.0, ""]  # worst |Nef - closed form| / the inputs' volume sum

TRIG = 2.0 ** -10  # rotations are rounded to this in the dyadic scenes


class Retry(Exception):
    """The random draw does not fit (a degenerate shape, a margin not kept): draw again."""


# ---- random values -------------------------------------------------------------------------

SPECIAL = ([k * 0.1 for k in range(1, 40)] + [k / 3 for k in range(1, 13)] +
           [k / 7 for k in range(1, 20)])


class Gen:
    """The scene's random values: multiples of 1/8 (coarse) or any doubles."""

    def __init__(self, rnd, coarse):
        self.r = rnd
        self.coarse = coarse

    def c(self, lo, hi):
        """A value in (lo, hi), at least 15% of the width from either end."""
        w = hi - lo
        a, b = lo + 0.15 * w, hi - 0.15 * w
        if self.coarse:
            k0, k1 = math.ceil(a * 8), math.floor(b * 8)
            if k0 > k1:
                raise Retry
            return self.r.randint(k0, k1) / 8
        if self.r.random() < 0.3:
            s = [x for x in SPECIAL if a <= x <= b] + [-x for x in SPECIAL if a <= -x <= b]
            if s:
                return self.r.choice(s)
        return lo + w * self.r.uniform(0.15, 0.85)

    def q(self, x):
        """A derived value onto the grid of the scene (1/8), or as it is."""
        return round(x * 8) / 8 if self.coarse else x

    def t(self, x):
        """A cosine or sine: rounded to TRIG in a coarse scene."""
        return round(x / TRIG) * TRIG if self.coarse else x

    def unit(self, theta):
        return self.t(math.cos(theta)), self.t(math.sin(theta))

    def rotation(self):
        u = [self.r.gauss(0, 1) for _ in range(3)]
        n = math.sqrt(sum(x * x for x in u))
        x, y, z = (t / n for t in u)
        a = self.r.uniform(0.3, math.pi - 0.3)
        c, s = math.cos(a), math.sin(a)
        R = [[c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s],
             [y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s],
             [z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)]]
        return [[self.t(v) for v in row] for row in R]


# ---- solids ---------------------------------------------------------------------------------

class Solid:
    def __init__(self, V, Fc, name):
        self.V = [[float(t) for t in v] for v in V]
        self.F = [list(f) for f in Fc]
        self.name = name
        self.orient()
        self.split()

    def split(self):
        """A face that is not planar on the doubles (a cube turned in doubles) is written as the
        triangles of a fan, so that the solid is the same for cellar, CGAL and the closed form."""
        out = []
        for f in self.F:
            if len(f) > 3:
                p = [[Fr(t) for t in self.V[i]] for i in f]
                u = [p[1][k] - p[0][k] for k in range(3)]
                w = [p[2][k] - p[0][k] for k in range(3)]
                n = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]]
                if any(sum(n[k] * (q[k] - p[0][k]) for k in range(3)) != 0 for q in p[3:]):
                    out.extend([f[0], f[i], f[i + 1]] for i in range(1, len(f) - 1))
                    continue
            out.append(f)
        self.F = out

    def orient(self):
        """Every face outward (the solids are convex: away from the centroid)."""
        n = len(self.V)
        c = [sum(v[k] for v in self.V) / n for k in range(3)]
        for f in self.F:
            nv = [0.0, 0.0, 0.0]
            for i in range(len(f)):
                p, q = self.V[f[i]], self.V[f[(i + 1) % len(f)]]
                nv[0] += (p[1] - q[1]) * (p[2] + q[2])
                nv[1] += (p[2] - q[2]) * (p[0] + q[0])
                nv[2] += (p[0] - q[0]) * (p[1] + q[1])
            fc = [sum(self.V[i][k] for i in f) / len(f) for k in range(3)]
            if sum(nv[k] * (fc[k] - c[k]) for k in range(3)) < 0:
                f.reverse()

    def volume(self):
        """Exact, on the doubles (each face a fan from its first vertex)."""
        s = Fr(0)
        P3 = [[Fr(t) for t in v] for v in self.V]
        for f in self.F:
            a = P3[f[0]]
            for i in range(1, len(f) - 1):
                b, d = P3[f[i]], P3[f[i + 1]]
                s += (a[0] * (b[1] * d[2] - b[2] * d[1]) - a[1] * (b[0] * d[2] - b[2] * d[0]) +
                      a[2] * (b[0] * d[1] - b[1] * d[0]))
        return s / 6

    def area(self):
        a = 0.0
        for f in self.F:
            p0 = self.V[f[0]]
            n = [0.0, 0.0, 0.0]
            for i in range(1, len(f) - 1):
                p1, p2 = self.V[f[i]], self.V[f[i + 1]]
                u = [p1[k] - p0[k] for k in range(3)]
                w = [p2[k] - p0[k] for k in range(3)]
                n = [n[0] + u[1] * w[2] - u[2] * w[1], n[1] + u[2] * w[0] - u[0] * w[2],
                     n[2] + u[0] * w[1] - u[1] * w[0]]
            a += math.sqrt(sum(x * x for x in n)) / 2
        return a

    def bbox(self):
        return ([min(v[k] for v in self.V) for k in range(3)],
                [max(v[k] for v in self.V) for k in range(3)])

    def write(self, path):
        with open(path, "w") as f:
            f.write("OFF\n%d %d 0\n" % (len(self.V), len(self.F)))
            for v in self.V:
                f.write("%r %r %r\n" % tuple(v))
            for fa in self.F:
                f.write(" ".join(map(str, [len(fa)] + fa)) + "\n")


CUBE_F = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
PRISM_F = [[0, 1, 2], [3, 4, 5], [0, 1, 4, 3], [1, 2, 5, 4], [2, 0, 3, 5]]
TET_F = [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]]


def box(lo, hi, name="box"):
    return Solid([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])],
                 CUBE_F, name)


def tet(pts, name="tet"):
    s = Solid(pts, TET_F, name)
    if abs(s.volume()) < 0.02:
        raise Retry  # too flat
    return s


def prism(tri, t0, t1, axis, name="prism"):
    """The triangle tri (2D) extruded from t0 to t1 along axis 0 (x: tri in yz), 1 (y: tri in
    xz) or 2 (z: tri in xy)."""
    V = []
    for t in (t0, t1):
        for a, b in tri:
            V.append([t, a, b] if axis == 0 else [a, t, b] if axis == 1 else [a, b, t])
    s = Solid(V, PRISM_F, name)
    if abs(s.volume()) < 0.02:
        raise Retry
    return s


def zs(s, h):
    """The far side of a solid touching z = 0 from side s (+1 above, -1 below)."""
    return h if s > 0 else -h


# 2D helpers, exact

def cross2(o, a, b):
    return (Fr(a[0]) - Fr(o[0])) * (Fr(b[1]) - Fr(o[1])) - (Fr(a[1]) - Fr(o[1])) * (Fr(b[0]) - Fr(o[0]))


def inner_point(g, pts):
    """A random point of the convex polygon pts, on the grid: the weighted mean of its vertices
    with weights in [0.2, 1]."""
    w = [g.r.uniform(0.2, 1) for _ in pts]
    sw = sum(w)
    return (g.q(sum(wi * q[0] for wi, q in zip(w, pts)) / sw),
            g.q(sum(wi * q[1] for wi, q in zip(w, pts)) / sw))


def depth(poly, p):
    """The signed distance (approximate, exact sign) of p inside the convex polygon poly: > 0
    inside, < 0 outside."""
    n = len(poly)
    area = sum(cross2((0, 0), poly[i], poly[(i + 1) % n]) for i in range(n))
    sg = 1 if area > 0 else -1
    d = None
    for i in range(n):
        a, b = poly[i], poly[(i + 1) % n]
        ln = math.hypot(b[0] - a[0], b[1] - a[1])
        e = sg * float(cross2(a, b, p)) / ln
        d = e if d is None else min(d, e)
    return d


def seg_cross(a1, a2, b1, b2):
    """The parameters (t, u) of the crossing of two segments, exact, or None when parallel."""
    rx, ry = Fr(a2[0]) - Fr(a1[0]), Fr(a2[1]) - Fr(a1[1])
    qx, qy = Fr(b2[0]) - Fr(b1[0]), Fr(b2[1]) - Fr(b1[1])
    d = rx * qy - ry * qx
    if d == 0:
        return None
    wx, wy = Fr(b1[0]) - Fr(a1[0]), Fr(b1[1]) - Fr(a1[1])
    t = (wx * qy - wy * qx) / d
    u = (wx * ry - wy * rx) / d
    return t, u


# ---- features: what a solid offers the contact plane z = 0 ----------------------------------
#
# poly: a face in z = 0 (its vertices, in order, and its axis-parallel edges); seg: an edge in
# z = 0 (its two ends); point: a vertex in z = 0.  The solid lies on side s of the plane and
# touches it only there.

class Feat:
    def __init__(self, kind, pts, axis_edges=()):
        self.kind = kind  # "poly", "seg", "point"
        self.pts = pts
        self.axis_edges = list(axis_edges)


def poly_solid(shape, g, s, c, want_axis=False):
    """A solid of shape with a face in z = 0 around c (inside it, with a margin)."""
    cx, cy = c
    if shape == "box" or (shape == "prism" and (want_axis or g.r.random() < 0.5)):
        x0, x1 = cx - g.c(0.4, 1.6), cx + g.c(0.4, 1.6)
        y0, y1 = cy - g.c(0.4, 1.6), cy + g.c(0.4, 1.6)
        h = g.c(0.4, 2.0)
        rect = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
        edges = [((x0, y0), (x1, y0)), ((x1, y0), (x1, y1)), ((x1, y1), (x0, y1)), ((x0, y1), (x0, y0))]
        if shape == "box":
            sol = box([x0, y0, min(0.0, zs(s, h))], [x1, y1, max(0.0, zs(s, h))], "box")
        elif g.r.random() < 0.5:  # along x: the triangle in yz
            sol = prism([(y0, 0.0), (y1, 0.0), (g.c(y0 - 0.5, y1 + 0.5), zs(s, h))], x0, x1, 0, "prism")
        else:
            sol = prism([(x0, 0.0), (x1, 0.0), (g.c(x0 - 0.5, x1 + 0.5), zs(s, h))], y0, y1, 1, "prism")
        return sol, Feat("poly", rect, edges)
    if shape in ("prism", "tet"):
        # a triangle with one edge parallel to x, c inside
        y0 = cy - g.c(0.3, 1.2)
        x0, x1 = cx - g.c(0.6, 1.8), cx + g.c(0.6, 1.8)
        x2, y2 = g.c(x0 + 0.2, x1 - 0.2), cy + g.c(0.6, 2.0)
        tri = [(x0, y0), (x1, y0), (x2, y2)]
        if depth(tri, c) < 0.05:
            raise Retry
        h = g.c(0.4, 2.0)
        if shape == "prism":
            sol = prism(tri, 0.0, zs(s, h), 2, "prism")
        else:
            sol = tet([[x, y, 0.0] for x, y in tri] + [[g.c(x0, x1), g.c(y0, y2), zs(s, h)]], "tet")
        return sol, Feat("poly", tri, [((x0, y0), (x1, y0))])
    if shape == "rotcube":
        if want_axis:
            raise Retry
        L = g.c(0.6, 2.0)
        co, si = g.unit(g.r.uniform(0.2, math.pi / 2 - 0.2))
        a, b = (L * co, L * si), (-L * si, L * co)
        q = (g.q(cx - (a[0] + b[0]) * g.r.uniform(0.3, 0.7)),
             g.q(cy - (a[1] + b[1]) * g.r.uniform(0.3, 0.7)))
        V = []
        for i in (0, 1):
            for j in (0, 1):
                for k in (0, 1):
                    V.append([q[0] + (i * a[0] + j * b[0]), q[1] + (i * a[1] + j * b[1]), zs(s, k * L)])
        sq = [tuple(V[0][:2]), tuple(V[4][:2]), tuple(V[6][:2]), tuple(V[2][:2])]
        if depth(sq, c) < 0.05:
            raise Retry
        return Solid(V, CUBE_F, "rotcube"), Feat("poly", sq)
    raise ValueError(shape)


def seg_solid(shape, g, s, q1, q2=None, d=None, inside_x=False, L=None):
    """A solid of shape with an edge in z = 0: from q1 to q2 (tet, prism: q2 given; a prism's
    edge is parallel to x or y), or from q1 along the unit vector d (rotcube: its length is the
    cube's edge, L or drawn).  inside_x: the solid stays in x >= q1.x (an edge along y, along
    the container's edge)."""
    if shape == "tet":
        if inside_x:
            lo, hi = min(q1[1], q2[1]), max(q1[1], q2[1])
            rs = [[q1[0] + g.c(0.3, 1.5), g.c(lo - 0.5, hi + 0.5), zs(s, g.c(0.3, 1.5))]
                  for _ in range(2)]
        else:
            dx, dy = q2[0] - q1[0], q2[1] - q1[1]
            ln = math.hypot(dx, dy)
            nx, ny = -dy / ln, dx / ln
            rs = []
            for side in (1, -1):
                t = g.r.uniform(0.2, 0.8)
                off = side * g.r.uniform(0.3, 1.2)
                rs.append([g.q(q1[0] + t * dx + off * nx), g.q(q1[1] + t * dy + off * ny),
                           zs(s, g.c(0.3, 1.5))])
        return tet([[q1[0], q1[1], 0.0], [q2[0], q2[1], 0.0]] + rs, "tet"), Feat("seg", [q1, q2])
    if shape == "prism":
        if q1[1] == q2[1]:
            axis, U, t0, t1 = 1, q1[1], q1[0], q2[0]  # along x: the triangle in (y, z)
        elif q1[0] == q2[0]:
            axis, U, t0, t1 = 0, q1[0], q1[1], q2[1]
        else:
            raise ValueError("a prism's edge is parallel to an axis")
        if inside_x:
            if axis != 0:
                raise ValueError("inside_x needs an edge along y")
            d1, d2 = g.c(0.2, 1.2), g.c(0.2, 1.2)
            h1, h2 = g.c(0.2, 1.2), g.c(0.2, 1.2)
            if abs(d1 * h2 - d2 * h1) < 0.1:
                raise Retry
            tri = [(U, 0.0), (U + d1, zs(s, h1)), (U + d2, zs(s, h2))]
        else:
            tri = [(U, 0.0), (U + g.c(0.2, 1.2), zs(s, g.c(0.3, 1.2))),
                   (U - g.c(0.2, 1.2), zs(s, g.c(0.3, 1.2)))]
        lo, hi = min(t0, t1), max(t0, t1)
        # prism() puts the extrusion coordinate first: along x it is (x, y, z) = (t, a, b)
        sol = prism(tri, lo, hi, 0 if axis == 1 else 1, "prism")
        return sol, Feat("seg", [q1, q2])
    if shape == "rotcube":
        L = L or g.c(0.6, 2.0)
        co, si = d
        ph = g.r.uniform(0.25, math.pi / 2 - 0.25)
        cp, sp = g.t(math.cos(ph)), g.t(math.sin(ph))
        V = []
        for i in (0, 1):
            for j in (0, 1):
                for k in (0, 1):
                    x, y, z = i * L, j * L, k * L
                    y1, z1 = y * cp - z * sp, y * sp + z * cp  # about x, the edge (x, 0, 0) fixed
                    x2, y2 = x * co - y1 * si, x * si + y1 * co  # about z
                    V.append([q1[0] + x2, q1[1] + y2, zs(s, z1)])
        zmin = sorted(abs(v[2]) for v in V)
        if zmin[2] < 0.1 * L:
            raise Retry
        return Solid(V, CUBE_F, "rotcube"), Feat("seg", [q1, (V[4][0], V[4][1])])
    raise ValueError(shape)


def point_solid(shape, g, s, p, region=None):
    """A solid of shape with a vertex at p in z = 0 (its only point there).  region: (xlo, ylo),
    either None: its other vertices have x > xlo, y > ylo (a vertex in the container's edge or
    corner)."""
    if shape == "tet":
        for _ in range(50):
            cx, cy = p[0] + g.r.uniform(-0.6, 0.6), p[1] + g.r.uniform(-0.6, 0.6)
            R = g.r.uniform(0.5, 1.4)
            a0 = g.r.uniform(0, 2 * math.pi)
            base = [[g.q(cx + R * math.cos(a0 + 2 * math.pi * k / 3 + g.r.uniform(-0.3, 0.3))),
                     g.q(cy + R * math.sin(a0 + 2 * math.pi * k / 3 + g.r.uniform(-0.3, 0.3))),
                     zs(s, g.c(0.4, 2.0))] for k in range(3)]
            if region is not None:
                base = [[p[0] + abs(b[0] - p[0]) + 0.25 if region[0] is not None else b[0],
                         p[1] + abs(b[1] - p[1]) + 0.25 if region[1] is not None else b[1], b[2]]
                        for b in base]
            try:
                return tet([[p[0], p[1], 0.0]] + base, "tet"), Feat("point", [p])
            except Retry:
                continue
        raise Retry
    if shape == "rotcube":
        if region is not None:
            raise ValueError("a cube has no vertex that fits an edge or a corner from inside")
        L = g.c(0.6, 2.0)
        R = g.rotation()
        off = []
        for i in (0, 1):
            for j in (0, 1):
                for k in (0, 1):
                    off.append([i * L * R[t][0] + j * L * R[t][1] + k * L * R[t][2] for t in range(3)])
        zk = sorted(range(8), key=lambda n: s * off[n][2])
        e = off[zk[0]]
        if s * (off[zk[1]][2] - e[2]) < 0.1 * L:
            raise Retry
        V = [[p[0] + (o[0] - e[0]), p[1] + (o[1] - e[1]), o[2] - e[2]] for o in off]
        return Solid(V, CUBE_F, "rotcube"), Feat("point", [p])
    raise ValueError(shape)


def axis_seg(g):
    """Two ends of an axis-parallel edge through the origin's neighbourhood."""
    a, b = -g.c(0.4, 1.5), g.c(0.4, 1.5)
    o = g.c(-0.5, 0.5)
    return ((a, o), (b, o)) if g.r.random() < 0.5 else ((o, a), (o, b))


def axis_unit(q1, q2):
    return (1.0, 0.0) if q1[1] == q2[1] else (0.0, 1.0)


def host_with_axis_edge(shape, g, s):
    """A solid below (s) whose feature has an axis-parallel edge: a face (box, prism, tet) or an
    edge parallel to an axis (prism, tet, rotcube).  Returns solid, feature, the edge."""
    use_seg = shape == "rotcube" or (shape in ("prism", "tet") and g.r.random() < 0.5)
    if use_seg:
        q1, q2 = axis_seg(g)
        if shape == "rotcube":
            sol, ft = seg_solid(shape, g, s, q1, d=axis_unit(q1, q2))
        else:
            sol, ft = seg_solid(shape, g, s, q1, q2)
        return sol, ft, (ft.pts[0], ft.pts[1])
    sol, ft = poly_solid(shape, g, s, (0.0, 0.0), want_axis=True)
    return sol, ft, g.r.choice(ft.axis_edges)


def any_feature(shape, g, s):
    """A solid of shape below with any feature it can offer."""
    kinds = {"box": ["poly"], "prism": ["poly", "seg"], "tet": ["poly", "seg", "point"],
             "rotcube": ["poly", "seg", "point"]}[shape]
    k = g.r.choice(kinds)
    if k == "poly":
        return poly_solid(shape, g, s, (0.0, 0.0))
    if k == "point":
        return point_solid(shape, g, s, (0.0, 0.0))
    if shape == "prism":
        q1, q2 = axis_seg(g)
        return seg_solid(shape, g, s, q1, q2)
    if shape == "rotcube":
        co, si = g.unit(g.r.uniform(0, 2 * math.pi))
        return seg_solid(shape, g, s, (g.c(-1, 1), g.c(-1, 1)), d=(co, si))
    ang = g.r.uniform(0, math.pi)
    L = g.r.uniform(0.8, 2.5)
    q1 = (g.c(-1, 0), g.c(-1, 0))
    q2 = (g.q(q1[0] + L * math.cos(ang)), g.q(q1[1] + L * math.sin(ang)))
    if q1 == q2:
        raise Retry
    return seg_solid(shape, g, s, q1, q2)


# ---- scenes ---------------------------------------------------------------------------------
#
# A scene: solids (local frame) and for each its container's index or None; the solids with the
# same container have disjoint interiors.

SHAPES = ["box", "tet", "prism", "rotcube"]
POINTS = ["tet", "rotcube"]
SEGS = ["tet", "prism", "rotcube"]


def pick_role(g, shape, mine, other_set):
    """Whether the family's shape plays the role it can (mine) or the other one."""
    if shape not in mine:
        return False
    if shape not in other_set:
        return True
    return g.r.random() < 0.5


def out_vf(g, shape):
    if pick_role(g, shape, POINTS, SHAPES):
        pt, host = shape, g.r.choice(SHAPES)
    else:
        pt, host = g.r.choice(POINTS), shape
    A, fa = poly_solid(host, g, -1, (0.0, 0.0))
    # a point well inside the face
    for _ in range(50):
        p = inner_point(g, fa.pts)
        if depth(fa.pts, p) > 0.08:
            break
    else:
        raise Retry
    Bs, _ = point_solid(pt, g, 1, p)
    return [A, Bs], "%s vertex on %s face" % (pt, host)


def out_ve(g, shape):
    if pick_role(g, shape, POINTS, SHAPES):
        pt, host = shape, g.r.choice(SHAPES)
    else:
        pt, host = g.r.choice(POINTS), shape
    A, fa, (e1, e2) = host_with_axis_edge(host, g, -1)
    if e1[1] == e2[1]:
        p = (g.c(min(e1[0], e2[0]), max(e1[0], e2[0])), e1[1])
    else:
        p = (e1[0], g.c(min(e1[1], e2[1]), max(e1[1], e2[1])))
    Bs, _ = point_solid(pt, g, 1, p)
    return [A, Bs], "%s vertex on %s edge (%s)" % (pt, host, fa.kind)


def out_vv(g, shape):
    if pick_role(g, shape, POINTS, SHAPES):
        pt, host = shape, g.r.choice(SHAPES)
    else:
        pt, host = g.r.choice(POINTS), shape
    A, fa = any_feature(host, g, -1)
    p = g.r.choice(fa.pts)
    Bs, _ = point_solid(pt, g, 1, p)
    return [A, Bs], "%s vertex on %s vertex (of its %s)" % (pt, host, fa.kind)


def seg_any(shape, g, s, through, avoid=None):
    """A solid with an edge crossing the point through (its middle part), not parallel to the
    direction avoid."""
    for _ in range(50):
        if shape == "prism":
            d = g.r.choice([(1.0, 0.0), (0.0, 1.0)])
        else:
            a = g.r.uniform(0, 2 * math.pi)
            d = (math.cos(a), math.sin(a))
        if avoid is not None:
            sn = abs(d[0] * avoid[1] - d[1] * avoid[0]) / math.hypot(*avoid)
            if sn < 0.3:
                continue
        t = g.r.uniform(0.3, 0.7)
        if shape == "rotcube":
            dd = (g.t(d[0]), g.t(d[1]))
            L = g.c(0.6, 2.0)  # seg_solid draws its own length: go back by a part of a typical one
            q1 = (g.q(through[0] - t * L * dd[0]), g.q(through[1] - t * L * dd[1]))
            return seg_solid(shape, g, s, q1, d=dd, L=L)
        L = g.r.uniform(1.0, 2.5)
        if shape == "prism":
            a, b = g.c(0.3, 1.2), g.c(0.3, 1.2)
            if d[0]:
                q1, q2 = (through[0] - a, through[1]), (through[0] + b, through[1])
            else:
                q1, q2 = (through[0], through[1] - a), (through[0], through[1] + b)
        else:
            q1 = (g.q(through[0] - t * L * d[0]), g.q(through[1] - t * L * d[1]))
            q2 = (g.q(through[0] + (1 - t) * L * d[0]), g.q(through[1] + (1 - t) * L * d[1]))
        if q1 == q2:
            continue
        return seg_solid(shape, g, s, q1, q2)
    raise Retry


def out_ee_cross(g, shape):
    other = g.r.choice(SEGS)
    low, up = (shape, other) if g.r.random() < 0.5 else (other, shape)
    if low == "prism":
        q1, q2 = axis_seg(g)
        A, fa = seg_solid(low, g, -1, q1, q2)
    elif low == "rotcube":
        co, si = g.unit(g.r.uniform(0, 2 * math.pi))
        A, fa = seg_solid(low, g, -1, (g.c(-1, 0), g.c(-1, 0)), d=(co, si))
    else:
        a = g.r.uniform(0, math.pi)
        L = g.r.uniform(1.0, 2.5)
        q1 = (g.c(-1, 0), g.c(-1, 0))
        A, fa = seg_solid(low, g, -1, q1, (g.q(q1[0] + L * math.cos(a)), g.q(q1[1] + L * math.sin(a))))
    a1, a2 = fa.pts
    t = g.r.uniform(0.35, 0.65)
    c = (g.q(a1[0] + t * (a2[0] - a1[0])), g.q(a1[1] + t * (a2[1] - a1[1])))
    Bs, fb = seg_any(up, g, 1, c, (a2[0] - a1[0], a2[1] - a1[1]))
    tu = seg_cross(a1, a2, fb.pts[0], fb.pts[1])
    if tu is None or not (0.1 < tu[0] < 0.9 and 0.1 < tu[1] < 0.9):
        raise Retry
    return [A, Bs], "%s edge crossing %s edge" % (up, low)


def out_ee_col(g, shape):
    if shape in SEGS and g.r.random() < 0.5:
        up, host = shape, g.r.choice(SHAPES)
    else:
        up, host = g.r.choice(SEGS), shape
    A, fa, (e1, e2) = host_with_axis_edge(host, g, -1)
    ax = 0 if e1[1] == e2[1] else 1  # the coordinate that varies along the edge
    a1, a2 = sorted((e1[ax], e2[ax]))
    fix = e1[1 - ax]
    how = g.r.choice(["partial", "inside", "around", "equal"])
    if up == "rotcube":
        how = g.r.choice(["from inside", "from an end"])
        b1 = g.c(a1, a2) if how == "from inside" else a1
        q1 = (b1, fix) if ax == 0 else (fix, b1)
        Bs, fb = seg_solid(up, g, 1, q1, d=(1.0, 0.0) if ax == 0 else (0.0, 1.0))
    else:
        if how == "partial":
            b1, b2 = g.c(a1, a2), a2 + g.c(0.2, 1.0)
        elif how == "inside":
            m = g.c(a1, a2)
            b1, b2 = g.c(a1, m), g.c(m, a2)
        elif how == "around":
            b1, b2 = a1 - g.c(0.2, 1.0), a2 + g.c(0.2, 1.0)
        else:
            b1, b2 = a1, a2
        if g.r.random() < 0.5:
            b1, b2 = b2, b1
        q1, q2 = ((b1, fix), (b2, fix)) if ax == 0 else ((fix, b1), (fix, b2))
        Bs, fb = seg_solid(up, g, 1, q1, q2)
    return [A, Bs], "%s edge along %s edge (%s, %s)" % (up, host, fa.kind, how)


def out_ef(g, shape):
    if pick_role(g, shape, SEGS, SHAPES):
        up, host = shape, g.r.choice(SHAPES)
    else:
        up, host = g.r.choice(SEGS), shape
    A, fa = poly_solid(host, g, -1, (0.0, 0.0))
    partly = g.r.random() < 0.3
    for _ in range(100):
        c = inner_point(g, fa.pts)
        if depth(fa.pts, c) < 0.1:
            continue
        if up == "prism":
            d = g.r.choice([(1.0, 0.0), (0.0, 1.0)])
        else:
            a = g.r.uniform(0, 2 * math.pi)
            d = g.unit(a)
        if up == "rotcube":
            Bs, fb = seg_solid(up, g, 1, c, d=d)
        else:
            L = g.r.uniform(0.3, 2.0)
            q2 = (g.q(c[0] + L * d[0]), g.q(c[1] + L * d[1])) if up == "tet" else \
                ((c[0] + g.c(0.1, L), c[1]) if d[0] else (c[0], c[1] + g.c(0.1, L)))
            if q2 == c:
                continue
            Bs, fb = seg_solid(up, g, 1, c, q2)
        e = depth(fa.pts, fb.pts[1])
        if (partly and e < -0.08) or (not partly and e > 0.05):
            return [A, Bs], "%s edge %s in %s face" % (up, "partly" if partly else "wholly", host)
    raise Retry


def out_ff(g, shape):
    other = g.r.choice(SHAPES)
    low, up = (shape, other) if g.r.random() < 0.5 else (other, shape)
    A, fa = poly_solid(low, g, -1, (0.0, 0.0))
    how = "overlap"
    if low == "box" and up == "box" and g.r.random() < 0.6:
        (x0, y0), (x1, y1) = fa.pts[0], fa.pts[2]
        how = g.r.choice(["equal", "flush side", "flush corner", "inside"])
        h = g.c(0.4, 2.0)
        if how == "equal":
            lo, hi = [x0, y0, 0.0], [x1, y1, h]
        elif how == "flush side":
            xe = g.c(x1, x1 + 1.5) if g.r.random() < 0.5 else g.c(x0, x1)
            lo, hi = [x0, g.c(y0, y1), 0.0], [xe, y1 + g.c(0.2, 1), h]
        elif how == "flush corner":
            lo, hi = [x0, y0, 0.0], [g.c(x0, x1), g.c(y1, y1 + 1.5), h]
        else:
            xm, ym = g.c(x0, x1), g.c(y0, y1)
            lo, hi = [g.c(x0, xm), g.c(y0, ym), 0.0], [g.c(xm, x1), g.c(ym, y1), h]
        return [A, box(lo, hi)], "box face on box face (%s)" % how
    for _ in range(50):
        c = inner_point(g, fa.pts)
        if depth(fa.pts, c) > 0.1:
            break
    else:
        raise Retry
    Bs, fb = poly_solid(up, g, 1, c)
    return [A, Bs], "%s face on %s face (%s)" % (up, low, how)


OUT = {"v-f": (out_vf, SHAPES), "v-e": (out_ve, SHAPES), "v-v": (out_vv, SHAPES),
       "e-e-cross": (out_ee_cross, SEGS), "e-e-col": (out_ee_col, SHAPES), "e-f": (out_ef, SHAPES),
       "f-f": (out_ff, SHAPES)}


def container(g, inner, flush):
    """The box around inner: its walls at flush[(axis, side)] where given, else at a margin."""
    lo, hi = inner.bbox()
    L, H = [], []
    for k in range(3):
        a = flush.get((k, 0))
        b = flush.get((k, 1))
        if a is None:
            a = lo[k] - g.r.uniform(0.2, 1.0)
            a = math.floor(a * 8) / 8 if g.coarse else a
        if b is None:
            b = hi[k] + g.r.uniform(0.2, 1.0)
            b = math.ceil(b * 8) / 8 if g.coarse else b
        L.append(a)
        H.append(b)
    return box(L, H, "container")


def in_vf(g, shape):
    I, _ = point_solid(shape, g, 1, (0.0, 0.0))
    return I, {(2, 0): 0.0}, "%s vertex on the container's wall" % shape


def in_ve(g, shape):
    p = (0.0, g.c(-1, 1))
    I, _ = point_solid(shape, g, 1, p, region=(0.0, None))
    return I, {(2, 0): 0.0, (0, 0): 0.0}, "%s vertex on the container's edge" % shape


def in_vv(g, shape):
    I, _ = point_solid(shape, g, 1, (0.0, 0.0), region=(0.0, 0.0))
    return I, {(2, 0): 0.0, (0, 0): 0.0, (1, 0): 0.0}, "%s vertex in the container's corner" % shape


def in_ee_col(g, shape):
    y1, y2 = -g.c(0.4, 1.5), g.c(0.4, 1.5)
    I, _ = seg_solid(shape, g, 1, (0.0, y1), (0.0, y2), inside_x=True)
    flush = {(2, 0): 0.0, (0, 0): 0.0}
    how = "along"
    if shape == "prism" and g.r.random() < 0.5:
        flush[(1, 0)] = y1  # its end triangle on the wall y = y1 too
        how = "along, its end on a wall"
    return I, flush, "%s edge along the container's edge (%s)" % (shape, how)


def in_ef(g, shape):
    q1 = (g.c(-1, 1), g.c(-1, 1))
    if shape == "rotcube":
        I, _ = seg_solid(shape, g, 1, q1, d=g.unit(g.r.uniform(0, 2 * math.pi)))
    elif shape == "prism":
        L = g.c(0.4, 2.0)
        q2 = (q1[0] + L, q1[1]) if g.r.random() < 0.5 else (q1[0], q1[1] + L)
        I, _ = seg_solid(shape, g, 1, q1, q2)
    else:
        a = g.r.uniform(0, 2 * math.pi)
        L = g.r.uniform(0.5, 2.0)
        q2 = (g.q(q1[0] + L * math.cos(a)), g.q(q1[1] + L * math.sin(a)))
        if q2 == q1:
            raise Retry
        I, _ = seg_solid(shape, g, 1, q1, q2)
    return I, {(2, 0): 0.0}, "%s edge in the container's wall" % shape


def in_ff(g, shape):
    I, fa = poly_solid(shape, g, 1, (0.0, 0.0))
    flush = {(2, 0): 0.0}
    how = "in a wall"
    if shape == "box" and g.r.random() < 0.6:
        lo, hi = I.bbox()
        how = g.r.choice(["corner", "side", "across"])
        flush[(0, 0)] = lo[0]
        if how in ("corner", "across"):
            flush[(1, 0)] = lo[1]
        if how == "across":
            flush[(1, 1)] = hi[1]
    return I, flush, "%s face on the container's wall (%s)" % (shape, how)


IN = {"v-f": (in_vf, POINTS), "v-e": (in_ve, ["tet"]), "v-v": (in_vv, ["tet"]),
      "e-e-col": (in_ee_col, ["tet", "prism"]), "e-f": (in_ef, SEGS), "f-f": (in_ff, SHAPES)}


def third_outside(g, solids):
    """A box below z = 0 against the lower solid's extreme x plane (disjoint from both)."""
    A = solids[0]
    lo, hi = A.bbox()
    xm = hi[0]
    y0 = g.c(lo[1] - 1, hi[1])
    y1 = g.c(max(y0, lo[1]) + 0.2, hi[1] + 1)
    return box([xm, y0, -g.c(0.3, 1.5)], [xm + g.c(0.3, 1.5), y1, 0.0], "box3")


def third_inside(g, C):
    lo, hi = C.bbox()
    x0 = g.c(lo[0] - 1, hi[0])
    y0 = g.c(lo[1] - 1, hi[1])
    x1, y1 = g.c(x0 + 0.3, hi[0] + 1), g.c(y0 + 0.3, hi[1] + 1)
    return box([x0, y0, hi[2]], [x1, y1, hi[2] + g.c(0.3, 1.2)], "box3")


# ---- frames ---------------------------------------------------------------------------------

OFF_BASES = [0.1, 1 / 3, -2 / 3, 1e4 + 0.1, 1e4 + 1 / 3, -1e4 - 0.3, 1e3 + 0.7, 123.456]
FAR_BASES = [1e4 + 0.1, 1e4 + 1 / 3, -1e4 - 0.3, 1e3 + 0.7, 2e3 + 1 / 3, -5e3 + 0.1]

VARIANTS = ["axis, on-grid", "axis, off-grid", "tilted, dyadic", "tilted, off-grid"]


def place(g, solids, variant):
    """Moves the local scene into its frame (see the file comment)."""
    if variant < 2:
        perm = [0, 1, 2]
        g.r.shuffle(perm)
        sign = [g.r.choice([-1.0, 1.0]) for _ in range(3)]
        if variant == 0:
            o = [g.r.randint(-80, 80) / 8 for _ in range(3)]
        else:
            o = [g.r.choice(OFF_BASES) for _ in range(3)]
        out = []
        for s in solids:
            V = [[sign[i] * v[perm[i]] + o[i] for i in range(3)] for v in s.V]
            out.append(Solid(V, s.F, s.name))
        return out
    for _ in range(30):
        M = g.rotation()
        if variant == 2:
            o = [g.r.randint(-80, 80) / 8 for _ in range(3)]
        else:
            o = [g.r.choice(FAR_BASES) for _ in range(3)]
        out = []
        exact = True
        for s in solids:
            V = []
            for v in s.V:
                w = [o[i] + (M[i][0] * v[0] + M[i][1] * v[1] + M[i][2] * v[2]) for i in range(3)]
                for i in range(3):
                    e = Fr(o[i]) + sum(Fr(M[i][k]) * Fr(v[k]) for k in range(3))
                    if Fr(w[i]) != e:
                        exact = False
                V.append(w)
            out.append(Solid(V, s.F, s.name))
        if exact:
            return out
    raise Retry


# ---- running and comparing ------------------------------------------------------------------

def cellar(files, op):
    opts = json.dumps({"fields": ["stats", "membership", "result"]})
    try:
        r = subprocess.run([CEL, "solids"] + files + ["--op", op, "--options", opts],
                           capture_output=True, text=True)
    except OSError as e:
        return None, str(e)
    if r.returncode:
        return None, (r.stderr.strip() or "exit %d" % r.returncode)[:200]
    try:
        return json.loads(r.stdout), None
    except ValueError:
        return None, "unreadable output"


def nef(files, op):
    try:
        r = subprocess.run([NEF, "--op", op] + files, capture_output=True, text=True)
    except OSError as e:
        return None, str(e)
    if r.returncode:
        return None, (r.stderr.strip() or "exit %d" % r.returncode)[:200]
    try:
        return json.loads(r.stdout.strip().split("\n")[-1]), None
    except ValueError:
        return None, "unreadable output"


def expected(vols, parent, order):
    """union, intersection, difference of the solids in order (see the file comment)."""
    top = [i for i in order if parent[i] is None]
    u = sum(vols[i] for i in top)
    inter = Fr(0)
    if len(order) == 2:
        a, b = order
        if parent[a] == b:
            inter = vols[a]
        elif parent[b] == a:
            inter = vols[b]
    f, rest = order[0], order[1:]
    if parent[f] is not None and parent[f] in rest:
        diff = Fr(0)
    else:
        diff = vols[f] - sum(vols[i] for i in rest if parent[i] == f)
    return {"union": u, "intersection": inter, "difference": diff}


CONTACT = {"v-f": "point", "v-e": "point", "v-v": "point", "e-e-cross": "point", "e-e-col": "edge",
           "e-f": "edge", "f-f": "face"}


def contact_ok(r, want):
    nv, ne, nf = r["vertices"], r["edges"], r["facets"]
    if r["volume"] != 0:
        return False
    if want == "point":
        return (nv, ne, nf) == (1, 0, 0)
    if want == "edge":
        return (nv, ne, nf) == (2, 1, 0)
    return nf >= 1


def run_scene(tmp, name, solids, parent, pair, touch):
    order = list(range(len(solids)))
    files = []
    for k, i in enumerate(order):
        p = os.path.join(tmp, "s%d_%s.off" % (k, solids[i].name))
        solids[i].write(p)
        files.append(p)
    vols = [s.volume() for s in solids]
    for v in vols:
        if v <= 0:
            raise AssertionError("%s: a solid with volume %s" % (name, v))
    want = expected(vols, parent, order)
    areas = sum(solids[i].area() for i in order)
    vsum = float(sum(vols))
    failed = False
    log = []
    first = True
    # the two solids that touch: where Nef finds their boundaries meet is what the scene says
    r, e = nef([files[pair[0]], files[pair[1]]], "contact")
    if r is None:
        fail("%s: cgal_nef contact" % name, e)
        failed = True
    elif contact_ok(r, touch):
        ok("%s: they touch at a %s (Nef: %d vertices, %d edges, %d facets)" %
           (name, touch, r["vertices"], r["edges"], r["facets"]))
    else:
        got = "%d vertices, %d edges, %d facets" % (r["vertices"], r["edges"], r["facets"])
        fail("%s: they touch at a %s" % (name, touch), "Nef finds %s, volume %g" % (got, r["volume"]))
        failed = True
        log.append("contact: Nef finds %s" % got)
    for op in ("union", "intersection", "difference"):
        w = float(want[op])
        ref, e = nef(files, op)
        if ref is None:
            fail("%s %s: cgal_nef" % (name, op), e)
            failed = True
        else:
            if first:
                first = False
                got_in = ref["input_volumes"]
                bad = [k for k, i in enumerate(order) if abs(got_in[k] - float(vols[i])) > 1e-9 * vsum]
                if bad:
                    fail("%s: Nef input volumes = closed form" % name,
                         "%r, closed form %r" % (got_in, [float(vols[i]) for i in order]))
                    failed = True
                else:
                    ok("%s: Nef input volumes = closed form" % name)
            q = abs(ref["volume"] - w) / vsum
            if q > NEF_WORST[0]:
                NEF_WORST[0], NEF_WORST[1] = q, "%s %s" % (name, op)
            if abs(ref["volume"] - w) <= 1e-9 * vsum:
                ok("%s %s: Nef %.12g = closed form %.12g" % (name, op, ref["volume"], w))
            else:
                fail("%s %s: Nef = closed form" % (name, op),
                     "Nef %.17g, closed form %.17g" % (ref["volume"], w))
                failed = True
        got, e = cellar(files, op)
        if got is None:
            fail("%s %s: cellar refused" % (name, op), e)
            failed = True
            continue
        v = got["result"]["volume"]
        prec = got["stats"]["precision"]
        for what, r in (("closed form", w), ("Nef", None if ref is None else ref["volume"])):
            if r is None:
                continue
            bound = prec * areas + 1e-12 * abs(r)
            q = abs(v - r) / bound
            if q > WORST[0]:
                WORST[0], WORST[1] = q, "%s %s" % (name, op)
            if abs(v - r) <= bound:
                ok("%s %s: cellar %.12g = %s %.12g (%.2f of the bound)" % (name, op, v, what, r, q))
            else:
                fail("%s %s: cellar = %s" % (name, op, what),
                     "cellar %.17g, %s %.17g, bound %.3g (precision %g)" % (v, what, r, bound, prec))
                failed = True
                log.append("%s: cellar %.17g, %s %.17g, bound %.3g, precision %g" %
                           (op, v, what, r, bound, prec))
    if failed and DUMP:
        d = os.path.join(DUMP, re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("_"))
        os.makedirs(d, exist_ok=True)
        for f in files:
            shutil.copy(f, d)
        with open(os.path.join(d, "README"), "w") as fh:
            fh.write(name + "\n")
            fh.write("closed form: %s\n" % ", ".join("%s %.17g" % (k, float(x))
                                                     for k, x in want.items()))
            fh.write("input volumes: %r\nboundary area: %.17g\n" % ([float(x) for x in vols], areas))
            fh.write("\n".join(log) + "\n")
            fh.write("cellar solids %s --op OP --options '{\"fields\":[\"stats\",\"membership\",\"result\"]}'\n" %
                     " ".join(os.path.basename(f) for f in files))


def scene(tmp, fam, inside, kind, shape, seed):
    rnd = random.Random("%s %s %s %d" % (kind, shape, inside, seed))
    variant = (seed + sum(map(ord, kind + shape)) + (2 if inside else 0)) % 4
    g = Gen(rnd, variant != 1)
    three = seed % 3 == 2
    for _ in range(200):
        try:
            if inside:
                I, flush, what = IN[kind][0](g, shape)
                C = container(g, I, flush)
                solids, parent = [C, I], [None, 0]
                if three:
                    solids.append(third_inside(g, C))
                    parent.append(None)
            else:
                solids, what = OUT[kind][0](g, shape)
                parent = [None] * len(solids)
                if three:
                    solids.append(third_outside(g, solids))
                    parent.append(None)
            # the order of the files: the container first, mostly
            order = list(range(len(solids)))
            if not inside or g.r.random() < 0.25:
                g.r.shuffle(order)
            solids = [solids[i] for i in order]
            parent = [None if parent[i] is None else order.index(parent[i]) for i in order]
            pair = (order.index(0), order.index(1))
            solids = place(g, solids, variant)
            break
        except Retry:
            continue
    else:
        fail("%s seed %d: no scene drawn" % (fam, seed))
        return
    name = "%s seed %d [%s%s]: %s" % (fam, seed, VARIANTS[variant], ", 3 solids" if three else "", what)
    touch = "face" if "end on a wall" in what else CONTACT[kind]
    run_scene(tmp, name, solids, parent, pair, touch)


def main():
    for p in (CEL, NEF):
        if not os.access(p, os.X_OK):
            fail("%s is built" % p)
            return summary()
    seeds = STRESS if STRESS else 4
    with tempfile.TemporaryDirectory() as tmp:
        for kind, (_, shapes) in OUT.items():
            for shape in shapes:
                for s in range(seeds):
                    scene(tmp, "%s %s outside" % (shape, kind), False, kind, shape, s)
        for kind, (_, shapes) in IN.items():
            for shape in shapes:
                for s in range(seeds):
                    scene(tmp, "%s %s inside" % (shape, kind), True, kind, shape, s)
    print("# worst: %.2f of the snapping bound (%s)" % (WORST[0], WORST[1]))
    if NEF_WORST[0]:
        print("# Nef against the closed forms, worst: %.3g of the volume sum (%s)" %
              (NEF_WORST[0], NEF_WORST[1]))
    else:
        print("# Nef against the closed forms: equal on every volume")
    return summary()


sys.exit(main())
