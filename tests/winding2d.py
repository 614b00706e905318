#!/usr/bin/env python3
"""winding2d.py — the 2D polygons' fill rules (issue 26): "odd" (the default), "nonzero" and
"positive", each polygon's inside by the winding number of its rings.

Closed forms: two squares overlapping in one polygon, a hole turning either way, a square
turning clockwise, a pentagram (one ring crossing itself: winding 2 over its centre), and a
Boolean of such polygons.  Random families, hard on purpose: star rings {n/k} with jitter, some
turning clockwise, some on a coarse lattice (shared vertices and collinear edges), some far from
the origin.  On every case, for every face of the arrangement:
  - its winding numbers (membership "data", 1 when absent, 0 when the polygon is not listed)
    equal the winding numbers of the input rings about a point inside the face, counted here
    in Python (shapely's representative_point on the face's polygon from V, FV and holes);
  - for every polygon, the sum over faces of area * winding number is the signed area of the
    polygon's rings (the shoelace sum);
  - the result's area equals the area of the faces the rule and the op select, and (against
    GEOS) the area of the faces that shapely's own polygonize of the ring lines gives, selected
    by the same rule from their winding numbers: within the snapping bound (the rings'
    perimeter times the grid step).
Prints "ok ..." / "FAIL ..." lines and "N passed, N failed".
CELLAR_STRESS=N: N seeds per random family (default 6).
"""
import json
import math
import os
import random
import subprocess
import sys
import tempfile

from shapely.geometry import LineString, Polygon
from shapely.ops import polygonize, unary_union
from tally import fail, ok, summary

BIN = os.environ.get("CELLAR_BIN", "build/cellar")
RULES = ("odd", "nonzero", "positive")


def inside(w, rule):
    return w % 2 == 1 if rule == "odd" else w != 0 if rule == "nonzero" else w > 0


def winding(rings, p):
    """The winding number of closed rings (lists of (x, y)) about point p."""
    x, y = p
    w = 0
    for r in rings:
        n = len(r)
        for i in range(n):
            (x0, y0), (x1, y1) = r[i], r[(i + 1) % n]
            if y0 <= y < y1 or y1 <= y < y0:
                c = (x1 - x0) * (y - y0) - (x - x0) * (y1 - y0)
                if y1 > y0 and c > 0:
                    w += 1
                elif y1 < y0 and c < 0:
                    w -= 1
    return w


def shoelace(rings):
    s = 0.0
    for r in rings:
        n = len(r)
        for i in range(n):
            s += r[i][0] * r[(i + 1) % n][1] - r[(i + 1) % n][0] * r[i][1]
    return s / 2


def perimeter(polys):
    return sum(math.dist(r[i], r[(i + 1) % len(r)]) for p in polys for r in p for i in range(len(r)))


def evaluate(op, ins):
    """op as the API takes it, on a list of booleans (one per polygon)."""
    if op == "union":
        return any(ins)
    if op == "intersection":
        return all(ins)
    if op == "difference":
        return ins[0] and not any(ins[1:])
    if op == "xor":
        return sum(ins) % 2 == 1
    raise ValueError(op)


def run(req):
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as f:
        json.dump(req, f)
        path = f.name
    try:
        p = subprocess.run([BIN, "run", path], capture_output=True, text=True, timeout=300)
    finally:
        os.unlink(path)
    if p.returncode != 0:
        raise RuntimeError("cellar exited %d: %s" % (p.returncode, p.stderr[:300]))
    return json.loads(p.stdout)


def faces_of(d, origin):
    """The faces as shapely polygons, from V, FV and holes, moved by -origin (exact for points
    near it: far from 0 areas are computed near it)."""
    V = [(x - origin[0], y - origin[1]) for x, y in d["V"]]
    holes = d.get("holes", {})
    out = []
    for f, cyc in enumerate(d["FV"]):
        hs = [[V[v] for v in h] for h in holes.get(str(f), [])]
        out.append(Polygon([V[v] for v in cyc], hs))
    return out


def reference_area(polys, op, rule):
    """GEOS's arrangement of the ring lines (shapely polygonize), each piece selected by the
    winding numbers about a point inside it."""
    lines = []
    for p in polys:
        for r in p:
            for i in range(len(r)):
                a, b = r[i], r[(i + 1) % len(r)]
                if a != b:
                    lines.append(LineString([a, b]))
    area = 0.0
    for piece in polygonize(unary_union(lines)):
        q = piece.representative_point()
        ins = [inside(winding(p, (q.x, q.y)), rule) for p in polys]
        if evaluate(op, ins):
            area += piece.area
    return area


def check(name, polys, op, expect=None):
    """polys: a list of polygons, each a list of rings of (x, y).  expect: {rule: area}."""
    bound = None
    origin = polys[0][0][0]
    local = [[[(x - origin[0], y - origin[1]) for x, y in r] for r in p] for p in polys]
    for rule in RULES:
        req = {"kind": "polygons", "polygons": [[[list(pt) for pt in r] for r in p] for p in polys],
               "op": op, "options": {"fill": rule}}
        tag = "%s %s %s" % (name, op, rule)
        try:
            d = run(req)
        except Exception as e:  # noqa: BLE001 - reported as a failure
            fail(tag, str(e))
            continue
        step = d["stats"].get("precision", 0)
        bound = 4 * perimeter(polys) * step + 1e-12
        faces = faces_of(d, origin)
        m = d["membership"]
        ptr, idx, data = m["indptr"], m["indices"], m.get("data")
        bad = []
        sums = [0.0] * len(polys)
        chosen = 0.0
        for f, poly in enumerate(faces):
            got = {}
            for k in range(ptr[f], ptr[f + 1]):
                got[idx[k]] = data[k] if data else 1
            q = poly.representative_point()
            ws = [winding(p, (q.x, q.y)) for p in local]
            for i, w in enumerate(ws):
                want = (w % 2) if rule == "odd" else w
                if got.get(i, 0) != want:
                    bad.append("face %d polygon %d: %s, rings wind %d" % (f, i, got.get(i, 0), w))
                sums[i] += poly.area * w
            if evaluate(op, [inside(w, rule) for w in ws]):
                chosen += poly.area
        if bad:
            fail(tag + ": membership is the rings' winding numbers", "; ".join(bad[:3]))
        else:
            ok(tag + ": membership is the rings' winding numbers (%d faces)" % len(faces))
        off = ["polygon %d: %.12g, rings %.12g" % (i, sums[i], shoelace(p))
               for i, p in enumerate(local) if abs(sums[i] - shoelace(p)) > bound]
        if off:
            fail(tag + ": sum(area * winding) = the rings' signed area",
                 "; ".join(off[:3]) + " (bound %.3g)" % bound)
        else:
            ok(tag + ": every polygon's sum(area * winding) is its rings' signed area")
        area = d["result"]["area"]
        if abs(area - chosen) > bound:
            fail(tag + ": result area is the selected faces'", "%.12g vs %.12g" % (area, chosen))
        else:
            ok(tag + ": result area %.12g is the selected faces'" % area)
        ref = reference_area(local, op, rule)
        if abs(area - ref) > bound:
            fail(tag + ": result area against GEOS", "%.12g vs %.12g (bound %.3g)" % (area, ref, bound))
        else:
            ok(tag + ": result area against GEOS's polygonize: %.12g (reference %.12g)" % (area, ref))
        if expect and rule in expect:
            if abs(area - expect[rule]) > bound:
                fail(tag + ": closed form", "%.12g, expected %.12g" % (area, expect[rule]))
            else:
                ok(tag + ": closed form %.12g" % expect[rule])


def square(x0, y0, x1, y1, cw=False):
    r = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
    return r[::-1] if cw else r


def star(n, k, cx, cy, radius, phase=0.0, jitter=0.0, rng=None, cw=False, lattice=None):
    pts = []
    for i in range(n):
        a = phase + 2 * math.pi * i * k / n
        rr = radius * (1 + (rng.uniform(-jitter, jitter) if rng else 0))
        x, y = cx + rr * math.cos(a), cy + rr * math.sin(a)
        if lattice:
            x, y = round(x / lattice) * lattice, round(y / lattice) * lattice
        pts.append((x, y))
    out = []
    for p in pts:  # no repeated points in a row
        if not out or out[-1] != p:
            out.append(p)
    if len(out) > 1 and out[0] == out[-1]:
        out.pop()
    return out[::-1] if cw else out


def closed_forms():
    check("two overlapping squares as one polygon", [[square(0, 0, 2, 2), square(1, 1, 3, 3)]],
          "union", {"odd": 6, "nonzero": 7, "positive": 7})
    check("a hole turning clockwise", [[square(0, 0, 4, 4), square(1, 1, 3, 3, cw=True)]], "union",
          {"odd": 12, "nonzero": 12, "positive": 12})
    check("a hole turning counter-clockwise", [[square(0, 0, 4, 4), square(1, 1, 3, 3)]], "union",
          {"odd": 12, "nonzero": 16, "positive": 16})
    check("a square turning clockwise", [[square(0, 0, 2, 2, cw=True)]], "union",
          {"odd": 4, "nonzero": 4, "positive": 0})
    # the pentagram {5/2} of circumradius 1: its ring's signed area S is 5 T + 2 P (five points
    # of area T winding 1, the inner pentagon of area P winding 2; P's circumradius is
    # sin 18 / sin 54 of the tips')
    ring = star(5, 2, 0, 0, 1, math.pi / 2)
    S = shoelace([ring])
    P = 2.5 * math.sin(math.radians(72)) * (math.sin(math.radians(18)) / math.sin(math.radians(54))) ** 2
    check("pentagram", [[ring]], "union", {"odd": S - 2 * P, "nonzero": S - P, "positive": S - P})
    check("overlapping squares and a square", [[square(0, 0, 2, 2), square(1, 1, 3, 3)],
                                               [square(1.5, 0, 2.5, 3)]], "intersection",
          {"odd": 2, "nonzero": 2.5, "positive": 2.5})


def random_family(fam, seeds):
    for seed in range(seeds):
        rng = random.Random(1000 * hash(fam) % 100003 + seed)
        far = fam == "far"
        lattice = 0.25 if fam == "lattice" else None
        off = (1e6, -2e6) if far else (0, 0)
        polys = []
        for _ in range(rng.randint(1, 3)):
            rings = []
            for _ in range(rng.randint(1, 3)):
                n = rng.randint(3, 9)
                k = rng.randint(1, max(1, n // 2))
                if math.gcd(n, k) != 1:
                    k = 1
                cx, cy = off[0] + rng.uniform(-1, 1), off[1] + rng.uniform(-1, 1)
                r = star(n, k, cx, cy, rng.uniform(0.5, 2), rng.uniform(0, math.pi),
                         0.0 if lattice else 0.3, rng, rng.random() < 0.3, lattice)
                if len(r) >= 3 and abs(shoelace([r])) > 1e-9:
                    rings.append(r)
            if rings:
                polys.append(rings)
        if not polys:
            continue
        op = rng.choice(["union", "intersection", "difference", "xor"]) if len(polys) > 1 else "union"
        check("%s seed %d (%d polygons)" % (fam, seed, len(polys)), polys, op)


def main():
    seeds = int(os.environ.get("CELLAR_STRESS", "0") or 0) or 6
    closed_forms()
    for fam in ("stars", "lattice", "far"):
        random_family(fam, seeds)
    return summary()


if __name__ == "__main__":
    sys.exit(main())
