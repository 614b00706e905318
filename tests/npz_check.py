"""npz_check.py — `cellar run --format npz` read by numpy and scipy (tests/t_npz.sh).

For each request: the result's JSON (`cellar run`) and its npz (`--format npz`) are made, the
npz is loaded with numpy.load(allow_pickle=False), and
- the README's python block (the two lines) runs as written where the result has operators;
- V is float64 (n, dim) equal to the JSON's; EV int (m, 2) equal;
- every row array (FV, FE, CF, CV, exterior, result.FV, result.FE) rebuilt from indptr and
  indices equals the JSON's rows; holes rebuilt by face equal the JSON's holes;
- the operators as scipy.sparse.csr_matrix equal the JSON's CSR, and d1 @ d2 = 0 (d2 @ d3 = 0);
- membership as a csr_matrix equals the JSON's; result.cells and the 3D exterior equal;
- json holds exactly the keys that are not arrays, with their values;
- nothing else is in the file.
Usage: python3 tests/npz_check.py TMPDIR   (CELLAR_BIN names the binary)
"""
import io, json, os, re, subprocess, sys

import numpy
import scipy.sparse

from tally import ok, fail, summary

BIN = os.environ.get("CELLAR_BIN", "build/cellar")
tmp = sys.argv[1]

readme = open("README.md").read()
m = re.search(r"### NumPy arrays.*?```python\n(.*?)```", readme, re.S)
README_LINES = m.group(1) if m else None

SQ = ('"polygons": [[[[0, 0], [2, 0], [2, 2], [0, 2]]], [[[1, 1], [3, 1], [3, 3], [1, 3]], '
      '[[1.5, 1.5], [2.5, 1.5], [2.5, 2.5]]]], "op": ["-", 0, 1]')
TET = ('"solids": [{"V": [[0,0,0],[1,0,0],[0,1,0],[0,0,1]], "FV": [[0,2,1],[0,1,3],[0,3,2],[1,2,3]]},'
       '{"V": [[0.25,0.25,0.25],[1.25,0.25,0.25],[0.25,1.25,0.25],[0.25,0.25,1.25]],'
       '"FV": [[0,2,1],[0,1,3],[0,3,2],[1,2,3]]}]')
BOX = ('"solids": [{"V": [[0,0,0],[4,0,0],[4,4,0],[0,4,0],[0,0,1],[4,0,1],[4,4,1],[0,4,1]],'
       '"FV": [[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,7]]},'
       '{"V": [[1,1,1],[3,1,1],[3,3,1],[1,3,1],[1,1,2],[3,1,2],[3,3,2],[1,3,2]],'
       '"FV": [[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,7]]}]')
REQUESTS = {
    "nested squares with operators, dangling kept, exterior last":
        '{"kind": "lines", "lines": [[[0,0],[8,0]],[[8,0],[8,8]],[[8,8],[0,8]],[[0,8],[0,0]],'
        '[[2,2],[6,2]],[[6,2],[6,6]],[[6,6],[2,6]],[[2,6],[2,2]],[[3,3],[4,4.5]],'
        '[[9,0],[10,1]],[[9,1],[10,0]]], "options": {"operators": true, "keep_dangling": true,'
        ' "exterior_last": true}}',
    "examples/orthogonal.json": open("examples/orthogonal.json").read(),
    "2000 random segments, operators":
        None,  # made below with cellar gen
    "polygons, nonzero, operators": '{"kind": "polygons", %s, "options": {"operators": true, '
                                    '"fill": "nonzero"}}' % SQ,
    "polygons, fields result": '{"kind": "polygons", %s, "options": {"fields": ["result"]}}' % SQ,
    "examples/polygons.json": open("examples/polygons.json").read(),
    "svg floor plan": None,
    "solids intersection, operators": '{"kind": "solids", %s, "op": "intersection", '
                                      '"options": {"operators": true}}' % TET,
    "solids with a face with a hole, operators": '{"kind": "solids", %s, "options": '
                                                 '{"operators": true}}' % BOX,
    "examples/solids-op.json": open("examples/solids-op.json").read(),
}


def sh(args, stdin=None):
    return subprocess.run(args, input=stdin, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          check=True).stdout


REQUESTS["2000 random segments, operators"] = sh(
    [BIN, "gen", "lines", "2000", "0.05", "5", "--options",
     '{"operators": true, "keep_dangling": true}']).decode()
REQUESTS["svg floor plan"] = sh([BIN, "svg", "examples/floorplan.svg", "--format", "request"]).decode()

ROWS = {"FV", "FE", "CF", "CV"}


def rows_of(z, name):
    ptr, idx = z[name + ".indptr"], z[name + ".indices"]
    if ptr.dtype.kind != "i" or idx.dtype.kind != "i" or ptr[0] != 0:
        raise AssertionError("%s: indptr %s, indices %s" % (name, ptr.dtype, idx.dtype))
    return [idx[ptr[i]:ptr[i + 1]].tolist() for i in range(len(ptr) - 1)]


def csr(z, name):
    return scipy.sparse.csr_matrix((z[name + ".data"], z[name + ".indices"], z[name + ".indptr"]),
                                   shape=tuple(z[name + ".shape"]))


def csr_json(o, ones=False):
    data = o.get("data") or [1] * len(o["indices"])
    return scipy.sparse.csr_matrix((data, o["indices"], o["indptr"]), shape=tuple(o["shape"]))


def check(name, req):
    path = os.path.join(tmp, "r.json")
    open(path, "w").write(req)
    res = json.loads(sh([BIN, "run", path]))
    raw = sh([BIN, "run", path, "--format", "npz"])
    if raw[:4] != b"PK\x03\x04":
        return fail(name, "not a zip")
    open(os.path.join(tmp, "result.npz"), "wb").write(raw)
    z = numpy.load(io.BytesIO(raw), allow_pickle=False)
    used = set()

    def take(k):
        used.add(k)
        return z[k]

    dim = res["dim"]
    try:
        rest = json.loads(take("json").tobytes())
        if "V" in res:
            V = take("V")
            assert V.dtype == numpy.float64 and V.shape == (len(res["V"]), dim), "V %s %s" % (V.dtype, V.shape)
            assert (V == numpy.array(res["V"], dtype=float).reshape(-1, dim)).all(), "V differs"
        if "EV" in res:
            EV = take("EV")
            assert EV.dtype.kind == "i" and EV.shape == (len(res["EV"]), 2), "EV %s" % (EV.shape,)
            assert EV.tolist() == res["EV"], "EV differs"

        def rows_check(prefix, obj):
            for k in ROWS | ({"exterior"} if dim == 2 else set()):
                if k in obj:
                    take(prefix + k + ".indptr"), take(prefix + k + ".indices")
                    assert rows_of(z, prefix + k) == obj[k], prefix + k + " differs"
            if "holes" in obj:
                f, ptr, idx = (take(prefix + "holes." + s) for s in ("face", "indptr", "indices"))
                back = {}
                for i in range(len(f)):
                    back.setdefault(str(f[i]), []).append(idx[ptr[i]:ptr[i + 1]].tolist())
                assert back == obj["holes"], prefix + "holes differ"

        rows_check("", res)
        if dim == 3 and "exterior" in res:
            assert take("exterior").tolist() == res["exterior"], "exterior differs"
        if "operators" in res:
            ops = res["operators"]
            mats = {}
            for d in ops:
                for s in ("shape", "indptr", "indices", "data"):
                    take("operators.%s.%s" % (d, s))
                mats[d] = csr(z, "operators." + d)
                assert (mats[d] != csr_json(ops[d])).nnz == 0, d + " differs"
            assert (mats["d1"] @ mats["d2"]).count_nonzero() == 0, "d1 d2 != 0"
            if "d3" in mats:
                assert (mats["d2"] @ mats["d3"]).count_nonzero() == 0, "d2 d3 != 0"
            # the README's lines, as written
            g = {"numpy": numpy, "scipy": scipy}
            os.chdir(tmp)
            try:
                exec(README_LINES, g)
            finally:
                os.chdir(os.path.dirname(os.path.abspath(__file__)) + "/..")
            assert (g["d1"] != mats["d1"]).nnz == 0 and (g["V"] == z["V"]).all(), "README's lines"
        if "membership" in res:
            mb = res["membership"]
            for s in ("shape", "indptr", "indices") + (("data",) if "data" in mb else ()):
                take("membership." + s)
            m = scipy.sparse.csr_matrix(
                (z["membership.data"] if "data" in mb else numpy.ones(len(mb["indices"])),
                 z["membership.indices"], z["membership.indptr"]), shape=tuple(z["membership.shape"]))
            assert (m != csr_json(mb)).nnz == 0, "membership differs"
            assert rest["membership"] == {"format": mb["format"]}, "membership in json"
        if "result" in res:
            r = res["result"]
            rows_check("result.", r)
            for k in ("cells", "faces"):
                if k in r:
                    assert take("result." + k).tolist() == r[k], "result." + k
            if "V" in r:
                RV = take("result.V")
                assert (RV == numpy.array(r["V"], dtype=float).reshape(-1, dim)).all(), "result.V"
            small = {k: v for k, v in r.items() if not isinstance(v, (list, dict))}
            assert rest.get("result") == small, "result in json: %s" % rest.get("result")
        # (two runs: their stats differ only in the milliseconds)
        for o in (res, rest):
            o.get("stats", {}).pop("ms", None)
        want = {k: v for k, v in res.items() if not isinstance(v, (list, dict)) or k == "stats"}
        got = {k: v for k, v in rest.items() if k not in ("membership", "result")}
        assert got == want, "json: %s" % sorted(got)
        extra = set(z.files) - used
        assert not extra, "arrays not accounted for: %s" % sorted(extra)
    except AssertionError as e:
        return fail(name, str(e))
    ok("%s: %d arrays" % (name, len(z.files)))


if README_LINES is None:
    fail("README: no python block under ### NumPy arrays")
for name, req in REQUESTS.items():
    check(name, req)

# a big one: 100 000 random segments with operators, every array against the JSON
req = sh([BIN, "gen", "lines", "100000", "0.02", "1", "--options", '{"operators": true}']).decode()
check("100 000 random segments, operators", req)
sys.exit(summary())
