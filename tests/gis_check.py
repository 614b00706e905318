"""gis_check.py — GIS layers overlaid by `cellar polygons`, against shapely's overlay
(tests/t_gis.sh).

Two layers made to be hard: parcels (brick-laid lots far from the origin at UTM coordinates,
sharing edges, one with a courtyard hole, one in two parts, attributes of every JSON type) and
zones (buffers that overlap each other and the parcels' corners, a strip lying along parcel
edges exactly, a zone with no attributes).  For each op over the layers (intersection, union,
difference, xor) the result's GeoJSON is checked as a GIS overlay:
- every feature's geometry is valid (OGC) and its "area" property is the geometry's area;
- each feature carries its parents' attributes: per layer L, "L" is the parent's index in L
  (or null) and "L.key" each of the parent's properties, exactly (no other key);
- for every choice of parents (p, z) — z or p may be none — the features with that choice
  cover exactly parcel p ∩ zone z ∩ the op's region (p minus every zone where z is none, ...):
  their total area equals shapely's, within the snapping bound;
- the features' total area with distinct geometry equals the op's region's.
The same layers are then written as a Shapefile and a GeoPackage with ogr2ogr, overlaid into a
GeoPackage (--format gpkg), and the GeoPackage is read with Python's sqlite3 (its geometry
blobs by the GeoPackage header and shapely's WKB reader): the same areas per parent pair, the
attributes carried.
Usage: python3 tests/gis_check.py TMPDIR   (CELLAR_BIN names the binary)
"""
import json, math, os, random, sqlite3, struct, subprocess, sys

import shapely.geometry as sg
import shapely.ops
import shapely.validation
import shapely.wkb

from tally import ok, fail, summary

BIN = os.environ.get("CELLAR_BIN", "build/cellar")
tmp = sys.argv[1]
rng = random.Random(28)
X0, Y0 = 500000.0, 4649776.0  # UTM 33N-like, far from the origin

# ---- the layers ---------------------------------------------------------------------------
parcels = []  # (shapely geometry, properties)
W, H = 37.5, 25.0
for j in range(6):
    for i in range(8):
        x = X0 + i * W + (W / 2 if j % 2 else 0)
        y = Y0 + j * H
        g = sg.box(x, y, x + W, y + H)
        props = {"id": 100 + len(parcels), "owner": rng.choice(["Ann", "Bob", "Müller", "Zoë"]),
                 "value": round(rng.uniform(1e4, 9e5), 2), "built": bool(j % 2),
                 "note": None}
        if (i, j) == (3, 2):  # a courtyard
            g = sg.Polygon(g.exterior.coords,
                           [sg.box(x + 10, y + 5, x + 20, y + 15).exterior.coords])
        parcels.append((g, props))
# a lot in two parts, beyond the bricks
parcels.append((sg.MultiPolygon([sg.box(X0 - 60, Y0, X0 - 40, Y0 + 20),
                                 sg.box(X0 - 35, Y0, X0 - 10, Y0 + 20)]),
                {"id": 999, "owner": "City", "value": 0, "built": False, "note": "split"}))

zones = []
for k in range(9):
    c = sg.Point(X0 + rng.uniform(0, 8 * W), Y0 + rng.uniform(0, 6 * H))
    zones.append((c.buffer(rng.uniform(8, 40), 16), {"code": "Z%d" % k, "level": k % 3}))
# a strip along parcel edges exactly (collinear overlaps) and touching a corner
zones.append((sg.box(X0 + W, Y0, X0 + 3 * W, Y0 + H), {"code": "strip", "level": 9}))
zones.append((sg.box(X0 - 60, Y0 + 20, X0 - 30, Y0 + 40), {}))  # touches the split lot


def fc(layer):
    return {"type": "FeatureCollection",
            "features": [{"type": "Feature", "properties": p, "geometry": sg.mapping(g)}
                         for g, p in layer]}


pa, zo = os.path.join(tmp, "parcels.geojson"), os.path.join(tmp, "zones.geojson")
json.dump(fc(parcels), open(pa, "w"))
json.dump(fc(zones), open(zo, "w"))

P = shapely.ops.unary_union([g for g, _ in parcels])
Z = shapely.ops.unary_union([g for g, _ in zones])
REGION = {"intersection": P.intersection(Z), "union": P.union(Z),
          "difference": P.difference(Z), "xor": P.symmetric_difference(Z)}
perimeter = sum(g.length for g, _ in parcels + zones)
TOL = perimeter * 2e-7 + 1e-6  # the snapping bound: the grid step is about extent * 2^-30


def expected(op):
    """{(p, z): area} of parcel p ∩ zone z ∩ the region (None: in none of that layer)."""
    reg = REGION[op]
    out = {}
    for pi, (pg, _) in enumerate(parcels + [(None, None)]):
        for zi, (zg, _) in enumerate(zones + [(None, None)]):
            if pg is None and zg is None:
                continue
            a = reg
            a = a.intersection(pg) if pg is not None else a.difference(P)
            a = a.intersection(zg) if zg is not None else a.difference(Z)
            if a.area > TOL:
                out[(pi if pg is not None else None, zi if zg is not None else None)] = a.area
    return out


def check_overlay(name, feats, want, region, props_exact=True):
    got, geoms = {}, {}
    bad = []
    for f in feats:
        pr = f["properties"]
        g = f["geometry"]
        key = (pr.get("parcels"), pr.get("zones"))
        got[key] = got.get(key, 0) + g.area
        if not g.is_valid:
            bad.append("invalid %s: %s" % (key, shapely.validation.explain_validity(g)))
        if abs(pr["area"] - g.area) > TOL:
            bad.append("area property %r, geometry %r" % (pr["area"], g.area))
        wk = g.wkb
        geoms[wk] = g
        for lname, layer, idx in (("parcels", parcels, key[0]), ("zones", zones, key[1])):
            own = {k[len(lname) + 1:]: v for k, v in pr.items() if k.startswith(lname + ".")}
            if idx is None:
                if own:
                    bad.append("%s: no parent but attributes %r" % (lname, own))
                continue
            src = layer[idx][1]
            if props_exact:
                if own != src:
                    bad.append("%s %d: attributes %r, not %r" % (lname, idx, own, src))
            else:  # through a Shapefile: names cut to 10 characters, nulls and types vary
                for k, v in src.items():
                    if isinstance(v, (int, float, str)) and not isinstance(v, bool):
                        if k in own and own[k] != v and not (
                                isinstance(v, float) and abs(own[k] - v) < 1e-6):
                            bad.append("%s %d: %s = %r, not %r" % (lname, idx, k, own[k], v))
        extra = [k for k in pr if k not in ("area", "parcels", "zones")
                 and not k.startswith("parcels.") and not k.startswith("zones.")]
        if extra:
            bad.append("unknown keys %r" % extra)
    for k in set(got) | set(want):
        if abs(got.get(k, 0) - want.get(k, 0)) > TOL:
            bad.append("parents %r: area %r, shapely %r" % (k, got.get(k, 0), want.get(k, 0)))
    total = shapely.ops.unary_union(list(geoms.values())).area if geoms else 0
    if abs(total - region.area) > TOL:
        bad.append("the pieces cover %r, the region %r" % (total, region.area))
    if bad:
        fail(name, "; ".join(bad[:4]) + (" (+%d more)" % (len(bad) - 4) if len(bad) > 4 else ""))
    else:
        ok("%s: %d features, %d parent choices equal to shapely's overlay" %
           (name, len(feats), len(want)))


def run(args):
    p = subprocess.run([BIN] + args, capture_output=True)
    if p.returncode != 0:
        raise RuntimeError("cellar %s: exit %d: %s" % (" ".join(args), p.returncode,
                                                       p.stderr.decode()[:300]))
    return p.stdout


for op in ("intersection", "union", "difference", "xor"):
    try:
        out = json.loads(run(["polygons", pa, zo, "--op", op, "--format", "geojson"]))
    except Exception as e:
        fail("GeoJSON layers, %s" % op, str(e))
        continue
    feats = [{"properties": f["properties"], "geometry": sg.shape(f["geometry"])}
             for f in out["features"]]
    check_overlay("GeoJSON layers, %s" % op, feats, expected(op), REGION[op])

# an expression over the names equals the named op
try:
    a = json.loads(run(["polygons", pa, zo, "--op", '["-", "zones", "parcels"]',
                        "--format", "geojson"]))
    area = shapely.ops.unary_union([sg.shape(f["geometry"]) for f in a["features"]]).area
    want = Z.difference(P).area
    if abs(area - want) <= TOL and all(f["properties"]["parcels"] is None for f in a["features"]):
        ok("op [\"-\", \"zones\", \"parcels\"]: area %.6f = shapely's, no parcel parent" % area)
    else:
        fail("op zones - parcels", "area %r, shapely %r" % (area, want))
except Exception as e:
    fail("op zones - parcels", str(e))

# ---- a Shapefile and a GeoPackage in, a GeoPackage out ------------------------------------
shp, gpkg_in = os.path.join(tmp, "parcels.shp"), os.path.join(tmp, "zones.gpkg")
gpkg_out = os.path.join(tmp, "overlay.gpkg")


def gpkg_features(path):
    """The features of the one layer of a GeoPackage, by sqlite3: its columns and geometry."""
    db = sqlite3.connect(path)
    table, col = db.execute("SELECT table_name, column_name FROM gpkg_geometry_columns").fetchone()
    cur = db.execute('SELECT * FROM "%s"' % table)
    names = [d[0] for d in cur.description]
    feats = []
    for row in cur:
        rec = dict(zip(names, row))
        blob = rec.pop(col)
        rec.pop("fid", None)
        flags = blob[3]
        env = {0: 0, 1: 32, 2: 48, 3: 48, 4: 64}[(flags >> 1) & 7]
        if blob[:2] != b"GP":
            raise ValueError("not a GeoPackage geometry blob")
        feats.append({"properties": rec, "geometry": shapely.wkb.loads(bytes(blob[8 + env:]))})
    db.close()
    return feats


try:
    subprocess.run(["ogr2ogr", "-q", "-f", "ESRI Shapefile", shp, pa], check=True)
    subprocess.run(["ogr2ogr", "-q", "-f", "GPKG", gpkg_in, zo, "-nln", "zones"], check=True)
    run(["polygons", shp, gpkg_in, "--op", "intersection", "--format", "gpkg",
         "--output", gpkg_out])
    feats = gpkg_features(gpkg_out)
    for f in feats:  # GeoPackage integers may come back as floats
        for k in ("parcels", "zones"):
            v = f["properties"].get(k)
            f["properties"][k] = int(v) if v is not None else None
    check_overlay("Shapefile and GeoPackage layers into a GeoPackage, intersection", feats,
                  expected("intersection"), REGION["intersection"], props_exact=False)
except Exception as e:
    fail("Shapefile and GeoPackage layers into a GeoPackage", str(e))

sys.exit(summary())
