"""cellar — exact 2D/3D cellular arrangements and Booleans, from Python (python/README.md).

    import cellar
    r = cellar.arrangement2d([[0, 0, 2, 2], [0, 2, 2, 0], [0, 0, 2, 0]])
    r["V"], r["EV"], r.FV, r.stats["F"]

The calls run libcellar (include/cellar.h) through ctypes: the same core, checks, limits and
messages as the CLI and the daemon, with arrays in and arrays out (no JSON on the way but the
few numbers of the stats).  A call returns a Result: a dict of NumPy arrays named as the CLI's
`--format npz` names them ("V", "EV", "FV.indptr", "operators.d1.data", "result.area", ...),
copied out of the library's result, which is freed before the call returns; plus .dim, .stats
and conveniences (.FV, .operators, .membership, .geometry, .area, .volume).

Errors raise cellar.Error (a ValueError) with .status (422 bad input, 503 out of memory, 500 a
bug of ours) and the library's message, which names the input element.  Ctrl-C cancels a run
(the library stops within a progress report) and raises KeyboardInterrupt.

Threads: each call runs the library on a worker thread of its own (which starts the
library's worker threads) while the calling thread waits in short joins, so that Ctrl-C is
seen; calls from many Python threads at once are fine (the library is reentrant).
"""
import ctypes as C
import json
import threading
import time

import numpy as np

from . import _lib
from ._lib import lib

__version__ = "0.3.0"
__all__ = ["arrangement2d", "polygons", "polygons_packed", "solids", "run_json", "version", "stage_names",
           "Result", "Error"]

_DTYPES = {1: np.float64, 2: np.int32, 3: np.uint32, 4: np.int8, 5: np.uint64}


class Error(ValueError):
    """A failed call: .status is the library's status (an HTTP code: 400 not JSON, 422 bad
    input, option or limit, 500 a bug of ours, 503 out of memory), str(e) its message, which
    names the input element ("polygons[3] ring 1 point 4: expected finite numbers")."""

    def __init__(self, status, message):
        super().__init__(message)
        self.status = status
        self.message = message

    def __repr__(self):
        return "cellar.Error(%d, %r)" % (self.status, self.message)


def version():
    """The library's version string ("0.3.0"): cellar_version() of the loaded libcellar."""
    return lib.cellar_version().decode()


def stage_names(kind):
    """The stages a run of kind ("lines", "polygons", "solids") reports to progress, in order."""
    out, i = [], 0
    while True:
        s = lib.cellar_stage_name(kind.encode(), i)
        if s is None:
            return out
        out.append(s.decode())
        i += 1


# ---- results ----------------------------------------------------------------------------------

def _rows(ptr, idx):
    return [idx[ptr[i]:ptr[i + 1]] for i in range(len(ptr) - 1)]


class Result(dict):
    """The result of a call: a dict of NumPy arrays by the names of the CLI's `--format npz`
    (README "NumPy arrays"): "V" (n, dim) float64, "EV" (m, 2), rows of different lengths as
    "K.indptr"/"K.indices" (FV, FE, CF, CV, 2D exterior, result.FV, result.FE), holes as
    "holes.face"/"holes.indptr"/"holes.indices", matrices as "operators.d1.shape/indptr/
    indices/data" and "membership.*", and the Boolean's "result.*" ("result.area" (2D) and
    "result.volume" (3D) are 1-element arrays).  Only the arrays the fields asked for are there.

    Attributes and conveniences:
      dim          2 or 3
      stats        dict: the result's stats (counts, precision, ms per stage, warnings), or
                   {} when the fields leave them out
      V, EV        r["V"], r["EV"] (None when absent)
      FV, FE, CF, CV, exterior
                   lists of arrays, one per row (None when absent; 3D exterior: the array)
      holes        dict face -> list of cycles (arrays)
      operators    dict "d1", "d2"[, "d3"] -> scipy.sparse.csr_matrix (without scipy: a tuple
                   (data, indices, indptr, shape) that csr_matrix takes)
      membership   csr_matrix (cells x inputs; the winding numbers where "membership.data" is
                   there, else ones), or the tuple without scipy; None when absent
      area, volume the Boolean result's area (2D) / volume (3D) as a float, or None
      seconds      the wall time of the library's call itself (no conversion, no copying;
                   stats["ms"]["total"] is the arrangement's stages alone)
      geometry     (2D Booleans, shapely installed) the result as a shapely Polygon (one
                   polygon) or MultiPolygon (any other number), outer rings counter-clockwise
    """

    def __init__(self, arrays, dim, stats):
        super().__init__(arrays)
        self.dim = dim
        self.stats = stats
        self.seconds = None

    def __repr__(self):
        return "cellar.Result(dim=%d, %s)" % (self.dim, ", ".join(
            "%s: %s %s" % (k, v.dtype, v.shape) for k, v in self.items()))

    def _rows_of(self, name):
        if name + ".indptr" not in self:
            return None
        return _rows(self[name + ".indptr"], self[name + ".indices"])

    @property
    def V(self):
        return self.get("V")

    @property
    def EV(self):
        return self.get("EV")

    @property
    def FV(self):
        return self._rows_of("FV")

    @property
    def FE(self):
        return self._rows_of("FE")

    @property
    def CF(self):
        return self._rows_of("CF")

    @property
    def CV(self):
        return self._rows_of("CV")

    @property
    def exterior(self):
        if "exterior" in self:
            return self["exterior"]
        return self._rows_of("exterior")

    def _holes(self, prefix):
        if prefix + "holes.face" not in self:
            return None
        out = {}
        cyc = _rows(self[prefix + "holes.indptr"], self[prefix + "holes.indices"])
        for f, c in zip(self[prefix + "holes.face"].tolist(), cyc):
            out.setdefault(f, []).append(c)
        return out

    @property
    def holes(self):
        return self._holes("")

    def _matrix(self, prefix):
        if prefix + "indptr" not in self:
            return None
        ind, ptr = self[prefix + "indices"], self[prefix + "indptr"]
        data = self.get(prefix + "data")
        if data is None:
            data = np.ones(len(ind), np.int8)
        shape = tuple(int(x) for x in self[prefix + "shape"])
        try:
            import scipy.sparse
        except ImportError:
            return (data, ind, ptr, shape)
        return scipy.sparse.csr_matrix((data, ind, ptr), shape=shape)

    @property
    def operators(self):
        names = sorted({k.split(".")[1] for k in self if k.startswith("operators.")})
        if not names:
            return None
        return {n: self._matrix("operators.%s." % n) for n in names}

    @property
    def membership(self):
        return self._matrix("membership.")

    @property
    def area(self):
        a = self.get("result.area")
        return None if a is None else float(a.reshape(-1)[0])

    @property
    def volume(self):
        a = self.get("result.volume")
        return None if a is None else float(a.reshape(-1)[0])

    @property
    def geometry(self):
        if self.dim != 2 or "result.FV.indptr" not in self:
            return None
        import shapely.geometry as sg
        V = self.get("result.V")
        if V is None:
            V = self["V"]
        holes = self._holes("result.") or {}
        polys = []
        for p, shell in enumerate(_rows(self["result.FV.indptr"], self["result.FV.indices"])):
            polys.append(sg.Polygon(V[shell], [V[h] for h in holes.get(p, [])]))
        return polys[0] if len(polys) == 1 else sg.MultiPolygon(polys)


def _result(r):
    """Copies every array out of the C result r and frees it."""
    try:
        arrays = {}
        for i in range(lib.cellar_result_count(r)):
            a = lib.cellar_result_array(r, i).contents
            dt = np.dtype(_DTYPES[a.dtype])
            n = a.rows * a.cols
            if n:
                buf = (C.c_char * (n * dt.itemsize)).from_address(a.data)
                x = np.frombuffer(buf, dt).copy()
            else:
                x = np.zeros(0, dt)
            arrays[a.name.decode()] = x.reshape(a.rows, a.cols) if a.cols > 1 else x
        rest = json.loads(lib.cellar_result_json(r).decode())
        return Result(arrays, rest.get("dim", lib.cellar_result_dim(r)), rest.get("stats", {}))
    finally:
        lib.cellar_result_free(r)


# ---- calls: options, a worker thread, Ctrl-C --------------------------------------------------

def _fields(fields):
    if fields is None:
        return None
    if isinstance(fields, str):
        return fields.encode()
    return ",".join(fields).encode()


def _op(op):
    if op is None:
        return None
    if isinstance(op, str):
        return op.encode()
    return json.dumps(op).encode()


def _call(fn, progress, precision=None, threads=0, fields=None, fill=None,
          keep_dangling=False, operators=False):
    """Runs fn(options_pointer, error_pointer) -> status on a worker thread, the calling thread
    waiting in short joins: on KeyboardInterrupt the cancel callback starts answering 1, the
    library returns 499 within a progress report, and KeyboardInterrupt is raised again.  An
    exception raised by progress cancels the run as well and is raised after it."""
    state = {"stop": False, "exc": None}

    def cancel_cb(_):
        return 1 if state["stop"] else 0

    def progress_cb(_, stage, fraction):
        if progress is None or state["stop"]:
            return
        try:
            progress(stage.decode() if stage else "", fraction)
        except BaseException as e:  # noqa: B902 — carried to the caller's thread
            state["exc"] = e
            state["stop"] = True

    o = _lib.Options()
    o.precision = float(precision) if precision else 0.0
    o.threads = int(threads or 0)
    o.fields = _fields(fields)
    o.fill = fill.encode() if fill else None
    o.keep_dangling = 1 if keep_dangling else 0
    o.operators = 1 if operators else 0
    cancel_c = _lib.CANCEL(cancel_cb)  # kept alive until the call returns
    progress_c = _lib.PROGRESS(progress_cb)
    o.cancel = cancel_c
    o.progress = progress_c
    err = _lib.Error_()
    box = {}

    done = threading.Event()

    def work():
        try:
            t0 = time.perf_counter()
            box["rc"] = fn(C.byref(o), C.byref(err))
            box["seconds"] = time.perf_counter() - t0
        except BaseException as e:  # noqa: B902
            box["exc"] = e
        finally:
            done.set()

    # An Event, not Thread.join(timeout): a KeyboardInterrupt inside join() can leave the
    # thread seen as ended while it runs (CPython gh-90882).
    t = threading.Thread(target=work, name="cellar", daemon=True)
    t.start()
    interrupted = False
    while not done.is_set():
        try:
            done.wait(0.05)
        except KeyboardInterrupt:
            interrupted = True
            state["stop"] = True
    t.join()
    del cancel_c, progress_c
    if "exc" in box:
        raise box["exc"]
    rc = box["rc"]
    err.seconds = box["seconds"]
    if interrupted:
        return rc, err, KeyboardInterrupt()
    if state["exc"] is not None:
        return rc, err, state["exc"]
    if rc == 499:
        return rc, err, KeyboardInterrupt()
    if rc:
        return rc, err, Error(rc, err.msg.decode(errors="replace"))
    return rc, err, None


def _run_result(fn, progress, **opts):
    r = C.c_void_p()
    rc, err, exc = _call(lambda o, e: fn(o, C.byref(r), e), progress, **opts)
    if exc is not None:
        if r.value and rc == 0:
            lib.cellar_result_free(r)
        raise exc
    res = _result(r)
    res.seconds = err.seconds
    return res


def _f64(a, what):
    try:
        x = np.ascontiguousarray(a, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise Error(422, "%s: expected numbers (%s)" % (what, e)) from None
    return x


def arrangement2d(segments, *, precision=None, fields=None, keep_dangling=False,
                  operators=False, threads=0, progress=None):
    """The 2D arrangement of line segments (the JSON kind "lines").

    segments: an (n, 2, 2) or (n, 4) array-like, each segment x1, y1, x2, y2.
    precision: the snapping grid step (None: the default from the extent; README "Requests").
    fields: names of the parts to return ("V", "EV", "FV", "FE", "holes", "exterior", "stats",
      "operators"), a list or a comma-separated string; None: all but the operators.
    keep_dangling: keep bridges and dangling edges.  operators: add ∂1, ∂2 ("operators.*").
    threads: worker threads (0: every CPU).  progress: callable(stage, fraction) told each
      stage and the fraction done (0 to 1, never going back); raising in it cancels the run.
    Returns a Result (V, EV, FV, FE, holes, exterior, stats, ...).  Raises Error (422 naming
    the segment, "lines[3]: ...") and KeyboardInterrupt when Ctrl-C cancels the run.
    """
    s = _f64(segments, "segments")
    if s.ndim == 3 and s.shape[1:] == (2, 2) or s.ndim == 2 and s.shape[1] == 4:
        s = np.ascontiguousarray(s.reshape(-1, 4))
    elif s.size == 0:
        s = s.reshape(0, 4)
    else:
        raise Error(422, "segments: expected an (n, 2, 2) or (n, 4) array, got shape %s"
                    % (s.shape,))
    n = len(s)
    return _run_result(lambda o, r, e: lib.cellar_arrangement2d(s.ctypes.data, n, o, r, e),
                       progress, precision=precision, threads=threads, fields=fields,
                       keep_dangling=keep_dangling, operators=operators)


def _rings_of(g, i):
    """The rings of one polygons() input as a list of (k, 2) float64 arrays."""
    gi = getattr(g, "__geo_interface__", None)
    if gi is not None:
        if gi["type"] == "Polygon":
            rings = gi["coordinates"]
        elif gi["type"] == "MultiPolygon":
            rings = [r for part in gi["coordinates"] for r in part]
        else:
            raise Error(422, "polygons[%d]: a %s, expected a Polygon or MultiPolygon"
                        % (i, gi["type"]))
        return [_f64(r, "polygons[%d]" % i)[:, :2] for r in rings]
    if isinstance(g, np.ndarray) and g.ndim == 2:
        g = [g]
    out = []
    for j, r in enumerate(g):
        x = _f64(r, "polygons[%d] ring %d" % (i, j))
        if x.ndim != 2 or x.shape[1] != 2:
            raise Error(422, "polygons[%d] ring %d: expected a (k, 2) array of points, got "
                        "shape %s" % (i, j, x.shape))
        out.append(x)
    return out


def polygons(geoms, op="union", *, fill=None, precision=None, fields=None, operators=False,
             threads=0, progress=None):
    """A Boolean over polygons with holes (the JSON kind "polygons").

    geoms: the inputs, each a shapely Polygon or MultiPolygon (any object with a
      __geo_interface__ of those types; a MultiPolygon is one input made of its parts' rings),
      or a list of rings, the outer first, then its holes, each ring a (k, 2) array-like
      (closed or not; any orientation), or a single (k, 2) NumPy array (one ring).
    op: "union", "intersection", "difference" (the first minus the others), "xor", or an
      expression over the inputs' indices as nested lists, such as ["-", 0, ["+", 1, 2]].
    fill: "odd" (default), "nonzero" or "positive": where an input's inside is.
    precision, fields, operators, threads, progress: as arrangement2d; fields may also name
      "membership" and "result" (["result"] is the result alone, with a "result.V" of its own).
    Returns a Result with the arrangement of every ring, "membership.*" (each face's inputs)
    and "result.*" (cells, FV, FE, holes, area); .geometry is the result as shapely geometry
    and .area its area.  Raises Error (422 naming the element: "polygons[3] ring 1 point 4:
    expected finite numbers") and KeyboardInterrupt on Ctrl-C.
    """
    rings_all, poly_off, ring_off = [], [0], [0]
    for i, g in enumerate(geoms):
        rings = _rings_of(g, i)
        for r in rings:
            rings_all.append(r)
            ring_off.append(ring_off[-1] + len(r))
        poly_off.append(len(rings_all))
    xy = (np.ascontiguousarray(np.concatenate(rings_all)) if rings_all
          else np.zeros((0, 2), np.float64))
    return polygons_packed(xy, ring_off, poly_off, op, fill=fill, precision=precision,
                           fields=fields, operators=operators, threads=threads,
                           progress=progress)


def polygons_packed(xy, ring_off, poly_off, op="union", *, fill=None, precision=None,
                    fields=None, operators=False, threads=0, progress=None):
    """polygons() of inputs already packed in arrays, as the library takes them (no Python
    object per polygon: the way for millions of rings).

    xy: (n, 2) float64, every ring's points one after the other; ring_off: ring r is
      xy[ring_off[r] .. ring_off[r+1]) (closed or not, at least 3 points); poly_off: input p is
      the rings poly_off[p] .. poly_off[p+1] (outer first, then holes).  Offsets of integers
      below 2^32.  Everything else as polygons().
    """
    xy = _f64(xy, "polygons: xy")
    if xy.ndim != 2 or xy.shape[1] != 2:
        raise Error(422, "polygons: xy: expected an (n, 2) array, got shape %s" % (xy.shape,))
    ro = np.asarray(ring_off)
    po = np.asarray(poly_off)
    for name, a in (("ring_off", ro), ("poly_off", po)):
        if a.ndim != 1 or not len(a) or (a.size and (a.min() < 0 or a.max() >= 2**32)):
            raise Error(422, "polygons: %s: expected offsets below 2^32, from 0" % name)
    ro = np.ascontiguousarray(ro, np.uint32)
    po = np.ascontiguousarray(po, np.uint32)
    if po[-1] >= len(ro) or ro[-1] > len(xy):
        raise Error(422, "polygons: poly_off ends at ring %d of %d, ring_off at point %d of %d"
                    % (po[-1], len(ro) - 1, ro[-1], len(xy)))
    npoly = len(po) - 1
    opb = _op(op if op is not None else "union")
    return _run_result(
        lambda o, r, e: lib.cellar_polygons(npoly, po.ctypes.data, ro.ctypes.data, xy.ctypes.data,
                                            opb, o, r, e),
        progress, precision=precision, threads=threads, fields=fields, fill=fill,
        operators=operators)


def _solid_of(s, i):
    """(V float64 (n, 3), F uint32 flat, face_off uint32 or None, nf) of one solids() input."""
    if hasattr(s, "vertices") and hasattr(s, "faces"):
        V, F = s.vertices, s.faces
    elif isinstance(s, dict):
        V, F = s["V"], s.get("FV", s.get("F"))
    else:
        V, F = s
    V = _f64(V, "solids[%d].V" % i)
    if V.ndim != 2 or V.shape[1] != 3:
        raise Error(422, "solids[%d].V: expected an (n, 3) array, got shape %s" % (i, V.shape))
    try:
        Fa = np.asarray(F)
        regular = Fa.dtype != object and Fa.ndim == 2
    except ValueError:
        regular = False
    if regular and Fa.shape[1] == 3:
        if Fa.size and (Fa.min() < 0 or Fa.max() >= 2**32):
            raise Error(422, "solids[%d].FV: a vertex index out of range" % i)
        return V, np.ascontiguousarray(Fa, np.uint32).reshape(-1), None, len(Fa)
    faces = [np.asarray(f) for f in F]
    off = np.zeros(len(faces) + 1, np.int64)
    for j, f in enumerate(faces):
        if f.ndim != 1 or f.size and f.min() < 0:
            raise Error(422, "solids[%d].FV[%d]: expected a list of vertex indices" % (i, j))
        off[j + 1] = off[j] + len(f)
    flat = (np.concatenate(faces) if faces else np.zeros(0)).astype(np.uint32)
    return V, np.ascontiguousarray(flat), off.astype(np.uint32), len(faces)


def solids(solids, op=None, *, fill=None, precision=None, fields=None, operators=False,
           threads=0, progress=None):
    """The 3D arrangement of closed solids and, with op, a Boolean over them (the JSON kind
    "solids").

    solids: each a pair (V, F): V an (n, 3) array of vertices, F an (m, 3) integer array of
      triangles or a list of polygons (lists of vertex indices), counter-clockwise seen from
      outside (a solid turned inside out is turned back, with a warning in stats); or a dict
      {"V", "FV"}; or any object with .vertices and .faces (a trimesh.Trimesh).
    op: None (the arrangement alone), "union", "intersection", "difference", "xor", or an
      expression over the solids' indices as nested lists (["-", 0, ["+", 1, 2]]).
    fill: "positive" (default), "nonzero" or "odd" (by the winding number).
    precision, fields, operators, threads, progress: as arrangement2d; 3D fields add "CF" and
      "CV" (and "membership", "result" with an op).
    Returns a Result: V, EV, FV, FE, holes, CF, CV, exterior, stats (with the cells'
    "volumes"), and with op "membership.*" and "result.*" (cells, faces, FV, FE, holes,
    volume); .volume is the result's volume.  Raises Error (422: "solids[1].FV[7][2]: expected
    a vertex index below 8") and KeyboardInterrupt on Ctrl-C.
    """
    parts = [_solid_of(s, i) for i, s in enumerate(solids)]
    arr = (_lib.Solid * max(len(parts), 1))()
    for i, (V, F, off, nf) in enumerate(parts):
        arr[i] = _lib.Solid(V.ctypes.data, len(V), F.ctypes.data if F.size else None,
                            off.ctypes.data if off is not None else None, nf)
    n = len(parts)
    opb = _op(op)
    return _run_result(lambda o, r, e: lib.cellar_solids(arr, n, opb, o, r, e), progress,
                       precision=precision, threads=threads, fields=fields, fill=fill,
                       operators=operators)


def run_json(request, *, threads=0, progress=None):
    """Runs a JSON request (README "Requests": {"kind": "lines"|"svg"|"polygons"|"solids",
    ...}), given as text or as a dict, as the CLI's `cellar run` does, and returns the result
    JSON parsed (a dict).  threads and progress as arrangement2d; the other options are the
    request's.  Raises Error (400 not JSON, 422 naming the JSON path) and KeyboardInterrupt on
    Ctrl-C."""
    body = request if isinstance(request, (str, bytes)) else json.dumps(request)
    if isinstance(body, str):
        body = body.encode()
    out, n = C.c_void_p(), C.c_size_t()
    rc, err, exc = _call(lambda o, e: lib.cellar_run_json(body, len(body), o, C.byref(out),
                                                          C.byref(n), e), progress,
                         threads=threads)
    try:
        if exc is not None:
            raise exc
        return json.loads(C.string_at(out.value, n.value).decode())
    finally:
        if out.value:
            lib.cellar_free(out)
