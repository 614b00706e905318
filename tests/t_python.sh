#!/bin/sh
# t_python.sh — the Python package (python/) installed as README "From Python" says: a venv
# with --system-site-packages (Debian's NumPy, SciPy, shapely), `pip install --no-index
# ./python` (the in-tree build backend: nothing downloaded), the wheel bundling
# $CELLAR_BUILD/lib/libcellar.so.0 and loading it from outside the source tree, a pure wheel
# without it, every wheel's RECORD hashes right, a clear ImportError when no library loads;
# then tests/python_check.py in the venv (the library's arrays against the CLI's npz, areas
# against shapely, volumes against closed forms, errors, progress, Ctrl-C, the README's
# examples).
# Under `make check` ($CELLAR_SANITIZED) the library is the sanitized build/san one: python
# runs it with the ASan runtime preloaded (`gcc -print-file-name=libasan.so`) and
# detect_leaks=0 (CPython's own allocations are not freed at exit).
# Usage: CELLAR_BUILD=build tests/t_python.sh   (tests/run.sh sets CELLAR_BUILD and CELLAR_BIN)
set -u
cd "$(dirname "$0")/.." || exit 1
. tests/lib.sh
export CELLAR_BUILD="${CELLAR_BUILD:-build}"
export CELLAR_BIN="${CELLAR_BIN:-$CELLAR_BUILD/cellar}"
case $CELLAR_BIN in /*) ;; *) CELLAR_BIN="$(pwd)/$CELLAR_BIN" ;; esac
[ -x "$CELLAR_BIN" ] || give_up "$CELLAR_BIN is not built"
LIB=$(realpath -e "$CELLAR_BUILD/lib/libcellar.so.0" 2>/dev/null) ||
    give_up "$CELLAR_BUILD/lib/libcellar.so.0 is not built (make $CELLAR_BUILD/lib/libcellar.so.0.3.0)"
need_python "venv, ensurepip, numpy, scipy.sparse, shapely" \
    "python3-venv python3-pip python3-numpy python3-scipy python3-shapely"

PRE=""
if ldd "$LIB" | grep -q libasan; then
    PRE=$(gcc -print-file-name=libasan.so)
    [ -e "$PRE" ] || give_up "the sanitized $LIB needs the ASan runtime: gcc -print-file-name=libasan.so"
fi

V=$T/venv
"$PY" -m venv --system-site-packages "$V" >"$T/venv.log" 2>&1 ||
    { cat "$T/venv.log"; give_up "$PY -m venv failed: apt-get install python3-venv python3-pip"; }
SITE=$("$V/bin/python" -c 'import sysconfig; print(sysconfig.get_path("platlib"))')

# the install, with no index, the library bundled
if CELLAR_LIBRARY="$LIB" "$V/bin/pip" install --no-index --no-cache-dir --disable-pip-version-check \
    ./python >"$T/pip.log" 2>&1; then
    pass "pip install --no-index ./python into a venv with --system-site-packages"
else
    tail -n 20 "$T/pip.log"
    give_up "pip install --no-index ./python failed"
fi
check "the wheel bundles the library as cellar/libcellar.so.0" cmp -s "$LIB" "$SITE/cellar/libcellar.so.0"
(cd "$T" && env -u CELLAR_LIBRARY LD_PRELOAD="$PRE" ASAN_OPTIONS=detect_leaks=0 "$V/bin/python" -c \
    'import cellar; print(cellar._lib.path, cellar.version(), cellar.__file__)') >"$T/where" 2>&1
check "outside the tree, import cellar loads the bundled copy ($(cut -d' ' -f1 "$T/where"))" \
    grep -q "^$SITE/cellar/libcellar.so.0 " "$T/where"

# wheels: tagged for the platform with the library, py3-none-any without; RECORD right
mkdir -p "$T/whl"
CELLAR_LIBRARY="$LIB" "$V/bin/pip" wheel --no-index --no-deps --disable-pip-version-check \
    -w "$T/whl" ./python >"$T/wheel.log" 2>&1
CELLAR_LIBRARY=/nonexistent "$V/bin/pip" wheel --no-index --no-deps --disable-pip-version-check \
    -w "$T/whl" ./python >>"$T/wheel.log" 2>&1
check "a platform wheel with the library, a pure one without ($(ls "$T/whl" | tr '\n' ' '))" \
    sh -c "ls '$T/whl'/cellar-*-py3-none-linux_*.whl && ls '$T/whl'/cellar-*-py3-none-any.whl" \
    >/dev/null 2>&1
cat >"$T/record.py" <<'PY'
import base64, hashlib, sys, zipfile
for w in sys.argv[1:]:
    z = zipfile.ZipFile(w)
    rec = [n for n in z.namelist() if n.endswith(".dist-info/RECORD")][0]
    rows = [r.rsplit(",", 2) for r in z.read(rec).decode().splitlines()]
    names = {p for p, _, _ in rows}
    assert names == set(z.namelist()), (w, names ^ set(z.namelist()))
    for p, h, n in rows:
        if p == rec:
            continue
        d = z.read(p)
        want = "sha256=" + base64.urlsafe_b64encode(hashlib.sha256(d).digest()).rstrip(b"=").decode()
        assert h == want and int(n) == len(d), (w, p)
    assert b"Requires-Dist: numpy" in z.read(rec.replace("RECORD", "METADATA")), w
PY
check "every wheel's RECORD lists its files with their sha256 and sizes" \
    "$PY" "$T/record.py" "$T"/whl/*.whl

# no library anywhere: an ImportError naming what was tried (unless one is installed)
TOP=$(pwd)
(cd "$T" && CELLAR_LIBRARY=/nonexistent/libcellar.so.0 PYTHONPATH="$TOP/python" "$PY" -c \
    'import cellar' 2>&1 | tail -n 6) >"$T/noimp" 2>&1
if ldconfig -p 2>/dev/null | grep -q 'libcellar\.so\.0 '; then
    check "no CELLAR_LIBRARY, nothing bundled: the installed libcellar.so.0 loads" \
        sh -c "! grep -q Error '$T/noimp'"
else
    check "no library: ImportError naming CELLAR_LIBRARY, the loader and find_library" \
        sh -c "grep -q 'ImportError: cellar: libcellar.so.0 could not be loaded' '$T/noimp' &&
               grep -q 'CELLAR_LIBRARY=/nonexistent' '$T/noimp' &&
               grep -q \"find_library('cellar')\" '$T/noimp'"
fi
[ "$F" -eq 0 ] || cat "$T/noimp" "$T/where"

# the checker, in the venv, from the repository's top (not python/: the installed package)
mkdir -p "$T/check"
LD_PRELOAD="$PRE" ASAN_OPTIONS=detect_leaks=0 "$V/bin/python" tests/python_check.py "$T/check" \
    >"$T/py.out" 2>"$T/py.err"
rc=$?
tally_file "$T/py.out"
grep -qE '^[0-9]+ passed, [0-9]+ failed' "$T/py.out" ||
    { tail -n 8 "$T/py.err"; fail "tests/python_check.py exited $rc without a summary line"; }
finish
