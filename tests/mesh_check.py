#!/usr/bin/env python3
"""mesh_check.py — files cellar writes (--format stl, 3mf) opened by independent readers: the
binary STL by Python's struct, the 3MF package by zipfile and xml.etree (run by t_meshio.sh).

Usage: mesh_check.py stl FILE.stl TRIANGLES VOLUME
       mesh_check.py 3mf FILE.3mf OBJECTS VOLUME
       mesh_check.py count RESULT.json result|cells   prints the triangles of the result's
                     boundary or of all its cells (a face of n ring vertices and h holes is
                     n - 2 + 2h triangles), its cells, and the volume (of the result, or of
                     all the cells)
STL: the 80-byte header does not start with "solid", the count at byte 80 is TRIANGLES and the
size 84 + 50 n, every coordinate finite, each stored normal the unit normal of its triangle (or
0), the signed volume of the triangles VOLUME.  3MF: the three parts, the content types of .rels
and .model, the relationship of type 3dmodel to /3D/3dmodel.model, the model in the core
namespace with OBJECTS objects, each a mesh whose triangles index its own vertices and use every
one of them, the build's items naming those objects, the volume of them all VOLUME.  Prints
"ok NAME" / "FAIL NAME: why" and "N passed, N failed" last."""
import math
import struct
import sys
import xml.etree.ElementTree as ET
import zipfile

P = F = 0


def ok(name):
    global P
    P += 1
    print("ok " + name)


def fail(name, why):
    global F
    F += 1
    print("FAIL %s: %s" % (name, why))


def signed_volume(tris):
    v = 0.0
    for a, b, c in tris:
        v += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
              a[2] * (b[0] * c[1] - b[1] * c[0]))
    return v / 6


def check_stl(path, want_tris, want_vol):
    data = open(path, "rb").read()
    name = path.split("/")[-1]
    if data[:5].lower() == b"solid":
        fail(name, "the header starts with \"solid\" (readers would take it for ASCII)")
    (n,) = struct.unpack_from("<I", data, 80)
    if len(data) != 84 + 50 * n:
        return fail(name, "%d bytes for %d triangles (want %d)" % (len(data), n, 84 + 50 * n))
    if n != want_tris:
        return fail(name, "%d triangles, want %d" % (n, want_tris))
    tris = []
    for t in range(n):
        vals = struct.unpack_from("<12fH", data, 84 + 50 * t)
        if not all(math.isfinite(x) for x in vals[:12]):
            return fail(name, "triangle %d: a value not finite" % t)
        nrm, a, b, c = vals[0:3], vals[3:6], vals[6:9], vals[9:12]
        e1 = [b[i] - a[i] for i in range(3)]
        e2 = [c[i] - a[i] for i in range(3)]
        x = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
             e1[0] * e2[1] - e1[1] * e2[0]]
        ln = math.sqrt(sum(q * q for q in x))
        if ln > 0 and any(abs(nrm[i] - x[i] / ln) > 1e-5 for i in range(3)):
            return fail(name, "triangle %d: normal %s is not its unit normal" % (t, nrm))
        tris.append((a, b, c))
    vol = signed_volume(tris)
    if abs(vol - want_vol) > 1e-6 * max(1.0, abs(want_vol)):
        return fail(name, "volume %r, want %r" % (vol, want_vol))
    ok("%s: struct reads %d triangles, volume %g" % (name, n, vol))


NS = "{http://schemas.microsoft.com/3dmanufacturing/core/2015/02}"


def check_3mf(path, want_objects, want_vol):
    name = path.split("/")[-1]
    z = zipfile.ZipFile(path)
    names = set(z.namelist())
    need = {"[Content_Types].xml", "_rels/.rels", "3D/3dmodel.model"}
    if not need <= names:
        return fail(name, "parts %s, want %s" % (sorted(names), sorted(need)))
    if z.testzip() is not None:
        return fail(name, "a bad CRC")
    ct = ET.fromstring(z.read("[Content_Types].xml"))
    defaults = {d.get("Extension"): d.get("ContentType") for d in ct}
    if defaults.get("model") != "application/vnd.ms-package.3dmanufacturing-3dmodel+xml" or \
            defaults.get("rels") != "application/vnd.openxmlformats-package.relationships+xml":
        return fail(name, "content types %s" % defaults)
    rels = ET.fromstring(z.read("_rels/.rels"))
    targets = [r.get("Target") for r in rels
               if r.get("Type") == "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"]
    if targets != ["/3D/3dmodel.model"]:
        return fail(name, "3dmodel relationships %s" % targets)
    model = ET.fromstring(z.read("3D/3dmodel.model"))
    if model.tag != NS + "model":
        return fail(name, "root %s" % model.tag)
    objs = model.findall(NS + "resources/" + NS + "object")
    if len(objs) != want_objects:
        return fail(name, "%d objects, want %d" % (len(objs), want_objects))
    ids = set()
    vol = 0.0
    for o in objs:
        ids.add(o.get("id"))
        vs = [tuple(float(v.get(k)) for k in "xyz")
              for v in o.findall(NS + "mesh/" + NS + "vertices/" + NS + "vertex")]
        ts = [tuple(int(t.get(k)) for k in ("v1", "v2", "v3"))
              for t in o.findall(NS + "mesh/" + NS + "triangles/" + NS + "triangle")]
        used = set()
        for t in ts:
            if not all(0 <= i < len(vs) for i in t) or len(set(t)) != 3:
                return fail(name, "object %s: triangle %s of %d vertices" % (o.get("id"), t,
                                                                             len(vs)))
            used.update(t)
        if len(used) != len(vs):
            return fail(name, "object %s: %d vertices, %d used" % (o.get("id"), len(vs),
                                                                  len(used)))
        vol += signed_volume([(vs[a], vs[b], vs[c]) for a, b, c in ts])
    items = [i.get("objectid") for i in model.findall(NS + "build/" + NS + "item")]
    if sorted(items) != sorted(ids):
        return fail(name, "build items %s for objects %s" % (items, sorted(ids)))
    if abs(vol - want_vol) > 1e-9 * max(1.0, abs(want_vol)):
        return fail(name, "volume %r, want %r" % (vol, want_vol))
    ok("%s: zipfile + xml.etree read %d objects, volume %g" % (name, len(objs), vol))


def count_of(path, which):
    import json
    r = json.load(open(path))
    holes = r.get("holes") or {}

    def tris(faces):
        n = 0
        for s in faces:
            f = abs(s) - 1
            rings = [r["FV"][f]] + holes.get(str(f), [])
            n += sum(len(x) for x in rings) - 2 + 2 * (len(rings) - 1)
        return n
    if which == "result":
        print(tris(r["result"]["faces"]), 1, r["result"]["volume"])
    else:
        vol = 0.0
        V = r["V"]
        for cell in r["CF"]:
            for s in cell:
                f = abs(s) - 1
                ring = r["FV"][f] if s > 0 else r["FV"][f][::-1]
                # a fan of the outer ring less the holes' fans: the signed volume is exact for
                # planar faces whatever the triangulation
                for rr in [ring] + [h if s > 0 else h[::-1] for h in holes.get(str(f), [])]:
                    for k in range(1, len(rr) - 1):
                        vol += signed_volume([(V[rr[0]], V[rr[k]], V[rr[k + 1]])])
        print(sum(tris(c) for c in r["CF"]), len(r["CF"]), vol)


def main():
    if sys.argv[1] == "count":
        return count_of(sys.argv[2], sys.argv[3])
    kind, path, count, vol = sys.argv[1], sys.argv[2], int(sys.argv[3]), float(sys.argv[4])
    try:
        (check_stl if kind == "stl" else check_3mf)(path, count, vol)
    except Exception as e:  # a file the reader cannot take is a failure, not a crash
        fail(path, "%s: %s" % (type(e).__name__, e))
    print("%d passed, %d failed" % (P, F))
    sys.exit(1 if F else 0)


main()
