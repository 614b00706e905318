#!/usr/bin/env python3
"""geojson_check.py — validates cellar's GeoJSON maps with shapely (GEOS), a real validator.

Usage: geojson_check.py CELLAR_BIN WORKDIR [REQUEST.json ...]
Runs `cellar run --format geojson` (and `--cells all` for Boolean requests) on every request
given and on random Boolean requests made here (hard on purpose: shared edges and vertices,
holes touching the shell and each other, thin wedges, far from the origin), then checks every
map:
  - RFC 7946 shape: a FeatureCollection of Features; rings closed, at least 4 positions;
    shells counter-clockwise, holes clockwise;
  - every Polygon and MultiPolygon is valid for shapely (explain_validity says why not);
  - a Boolean's first Feature is its result region (MultiPolygon) with the result's area, within
    the snapping bound (the input rings' perimeter times the grid step: the positions are the
    input's own coordinates where input points snapped, the area is the grid's);
  - with --cells all, the selected faces are exactly those of result.cells, and their union is
    the result region (the area of the symmetric difference within the bound);
  - dangling edges are LineStrings, never ring parts.
Prints "ok ..." / "FAIL ..." lines and "N passed, N failed".
"""
import json
import math
import os
import random
import subprocess
import sys

from shapely.geometry import shape
from shapely.ops import unary_union
from shapely.validation import explain_validity
from tally import fail, ok, summary


def run(binary, path, *extra):
    r = subprocess.run([binary, "run", *extra, path], capture_output=True, text=True, timeout=300)
    if r.returncode != 0:
        raise RuntimeError("cellar run %s %s: exit %d: %s" % (" ".join(extra), path, r.returncode,
                                                              r.stderr[:300]))
    return json.loads(r.stdout)


def ring_area(ring):
    x0, y0 = ring[0][0], ring[0][1]
    s = 0.0
    for (ax, ay), (bx, by) in zip(ring, ring[1:]):
        s += (ax - x0) * (by - y0) - (bx - x0) * (ay - y0)
    return s / 2


def check_rings(what, polys):
    """polys: list of polygons, each a list of rings; returns a list of problems."""
    bad = []
    for q, poly in enumerate(polys):
        for h, ring in enumerate(poly):
            if len(ring) < 4 or ring[0] != ring[-1]:
                bad.append("%s polygon %d ring %d: %d positions or not closed" % (what, q, h,
                                                                                  len(ring)))
                continue
            a = ring_area(ring)
            if (h == 0) != (a > 0):
                bad.append("%s polygon %d ring %d: %s, area %g" %
                           (what, q, h, "shell not counter-clockwise" if h == 0
                            else "hole not clockwise", a))
    return bad


def perimeter_bound(req, step):
    polys = req.get("polygons")
    if isinstance(polys, list) and all(isinstance(p, list) for p in polys):
        per = 0.0
        for poly in polys:
            for ring in poly:
                for a, b in zip(ring, ring[1:] + ring[:1]):
                    per += math.hypot(b[0] - a[0], b[1] - a[1])
        return per * step
    return None


def check_map(name, req, res, gj, cells):
    what = "%s%s" % (name, " cells=all" if cells else "")
    if gj.get("type") != "FeatureCollection" or not isinstance(gj.get("features"), list):
        fail(what + ": not a FeatureCollection")
        return
    feats = gj["features"]
    problems = []
    nvalid = 0
    for i, f in enumerate(feats):
        g = f.get("geometry") or {}
        t = g.get("type")
        if f.get("type") != "Feature" or t not in ("Polygon", "MultiPolygon", "LineString"):
            problems.append("feature %d: type %s / %s" % (i, f.get("type"), t))
            continue
        if t == "LineString":
            if not (f["properties"].get("dangling") is True and len(g["coordinates"]) == 2):
                problems.append("feature %d: a LineString that is not a dangling edge" % i)
            continue
        polys = [g["coordinates"]] if t == "Polygon" else g["coordinates"]
        problems += check_rings("feature %d" % i, polys)
        s = shape(g)
        if not s.is_valid:
            problems.append("feature %d (%s): invalid: %s" % (i, t, explain_validity(s)))
        else:
            nvalid += 1
    if problems:
        fail("%s: %s" % (what, "; ".join(problems[:4])))
    else:
        ok("%s: %d features valid (shapely), rings closed and oriented" % (what, nvalid))
    result = res.get("result")
    if result is None:
        return
    step = res["stats"]["precision"]
    bound = perimeter_bound(req, step)
    first = feats[0] if feats else {}
    if (first.get("geometry") or {}).get("type") != "MultiPolygon" or \
            first.get("properties", {}).get("result") is not True:
        fail(what + ": the first feature is not the result MultiPolygon")
        return
    region = shape(first["geometry"])
    area = result["area"]
    tol = (bound if bound is not None else 0) + 1e-9 * max(1.0, area)
    if abs(region.area - area) <= tol and len(first["geometry"]["coordinates"]) == len(result["FV"]):
        ok("%s: result region: %d polygons, area %.12g (result %.12g, bound %.2g)" %
           (what, len(result["FV"]), region.area, area, tol))
    else:
        fail("%s: result region: %d polygons (result %d), area %.17g, result %.17g, bound %.3g" %
             (what, len(first["geometry"]["coordinates"]), len(result["FV"]), region.area, area,
              tol))
    if not cells:
        return
    faces = [f for f in feats[1:] if f["geometry"]["type"] == "Polygon"]
    sel = sorted(f["properties"]["face"] for f in faces if f["properties"].get("selected"))
    if sel != sorted(result["cells"]) or len(faces) != res["membership"]["shape"][0]:
        fail("%s: selected faces %s, result.cells %s" % (what, sel[:10], result["cells"][:10]))
        return
    union = unary_union([shape(f["geometry"]) for f in faces if f["properties"]["selected"]])
    diff = union.symmetric_difference(region).area if sel else region.area
    if diff <= tol:
        ok("%s: the selected faces' union is the result region (difference %.2g)" % (what, diff))
    else:
        fail("%s: the selected faces' union differs from the region by %.17g (bound %.3g)" %
             (what, diff, tol))


def star(rng, cx, cy, r, n, hole):
    pts = []
    for i in range(n):
        a = 2 * math.pi * (i + 0.2 + 0.6 * rng.random()) / n
        rad = r * (0.4 + 0.6 * rng.random())
        pts.append([cx + rad * math.cos(a), cy + rad * math.sin(a)])
    poly = [pts]
    if hole:
        s = r * (0.1 + 0.1 * rng.random())
        poly.append([[cx - s, cy - s], [cx - s, cy + s], [cx + s, cy + s], [cx + s, cy - s]])
    return poly


def random_requests(rng, n):
    ops = ["union", "intersection", "difference", "xor"]
    out = []
    for k in range(n):
        fam = k % 4
        if fam == 0:  # stars with holes
            polys = [star(rng, rng.random(), rng.random(), 1, rng.randint(5, 20), rng.random() < .5)
                     for _ in range(rng.randint(2, 5))]
        elif fam == 1:  # lattice rectangles: shared edges, vertices on edges
            polys = []
            for _ in range(rng.randint(2, 6)):
                x0, y0 = rng.randint(0, 7), rng.randint(0, 7)
                x1, y1 = x0 + rng.randint(1, 5), y0 + rng.randint(1, 5)
                polys.append([[[x0, y0], [x1, y0], [x1, y1], [x0, y1]]])
        elif fam == 2:  # holes touching the shell and each other at a vertex; a thin wedge
            polys = [[[[0, 0], [8, 0], [8, 8], [0, 8]], [[0, 4], [2, 3], [2, 5]],
                      [[2, 5], [4, 4], [4, 6]]],
                     [[[rng.randint(1, 6), 0], [8, 7.9 + 0.1 * rng.random()], [8, 8]]],
                     [[[2, 5], [6, 5], [6, 7], [2, 7]]]]
        else:  # far from the origin, shared vertices
            ox, oy = 4.2e6 + rng.random(), -3.1e6 + rng.random()
            polys = [[[[ox, oy], [ox + 10, oy], [ox + 10, oy + 10], [ox, oy + 10]]],
                     [[[ox + 10, oy + 10], [ox + 20, oy + 5], [ox + 5, oy + 3 * rng.random()]]],
                     star(rng, ox + 5, oy + 5, 6, 9, True)]
        out.append({"kind": "polygons", "polygons": polys, "op": ops[k % 4 if fam != 3 else
                                                                        rng.randint(0, 3)]})
    return out


def main():
    binary, work = sys.argv[1], sys.argv[2]
    paths = list(sys.argv[3:])
    rng = random.Random(12)
    for i, req in enumerate(random_requests(rng, int(os.environ.get("CELLAR_GEOJSON_N", "40")))):
        p = os.path.join(work, "random%03d.json" % i)
        with open(p, "w") as fh:
            json.dump(req, fh)
        paths.append(p)
    for p in paths:
        name = os.path.basename(p)
        try:
            with open(p) as fh:
                req = json.load(fh)
            if "options" in req:
                req["options"].pop("fields", None)  # every field: the stats give the grid step
            q = os.path.join(work, "full-" + name)
            with open(q, "w") as fh:
                json.dump(req, fh)
            res = run(binary, q)
            check_map(name, req, res, run(binary, q, "--format", "geojson"), False)
            if req.get("kind") == "polygons":
                check_map(name, req, res, run(binary, q, "--format", "geojson", "--cells", "all"),
                          True)
        except (RuntimeError, ValueError, subprocess.TimeoutExpired) as e:
            fail("%s: %s" % (name, e))
    return summary()


if __name__ == "__main__":
    sys.exit(main())
