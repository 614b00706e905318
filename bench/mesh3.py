#!/usr/bin/env python3
"""bench/mesh3.py — the Booleans of two real meshes: cellar's in-program time beside
Manifold's (npm manifold-3d, bench/manifold_bool.mjs) and CGAL's (corefinement, cgal_bool),
on the real meshes (part a) and on one of them refined up to millions of triangles (part b).

Usage: python3 bench/mesh3.py BUILD_DIR [--part a|b|all] [--sizes 10000,40000,...]
           [--meshes bunny,fandisk,...] [--threads T] [--repeat 5] [--timeout 900] [--no-cgal]
(make bench runs it after the other drivers; BENCH_MESH3_ARGS="..." passes it arguments).
Needs BUILD_DIR/cellar, BUILD_DIR/tests/ref/cgal_bool (make bench builds both), python3 and
GNU /usr/bin/time; Manifold needs node and bench/node_modules/manifold-3d (npm ci --prefix
bench) and is skipped with a note without them.  Standard library only.

Inputs: bench/gen3d.py writes each case once into BUILD_DIR/bench-cache/ as two OFF files (the
same doubles for every program) and later runs reuse them; a case is generated into a temporary
directory renamed into place, so an interrupted run leaves no half case, and it is made again
when gen3d.py or its source mesh changed (the file "key" holds their hash).
  part a  gen3d.py mesh tests/data/mesh/real/MESH.off SCENE for every mesh there but cow (its
          surface passes through itself: every program refuses it) and SCENE rot (the mesh and
          its turned, moved copy), box (a box through it) and shell (its copy scaled by 0.8
          inside it); ops union, intersection, difference.
  part b  gen3d.py refine tests/data/mesh/real/fertility.off N rot: the mesh refined to exactly
          N triangles per solid, with its turned copy, for N in --sizes (default 10000 to
          2000000); ops union and intersection.  Before a size is first used, both solids are
          checked with cgal_bool --op none (closed, not self-intersecting); the outcome is kept
          in the case's "checked" stamp, so the check runs once.  A failed check is reported
          loudly and the size is skipped.  cellar runs on T and 2 T threads (--threads T,
          default 1); Manifold runs a second time without --warm, for its peak RSS and its
          whole-process wall time (with --warm its first result stays alive during the second
          op: 13% more memory at 640000, and the op would be counted twice).

Programs (one at a time, each on the same two OFF files, each under /usr/bin/time and timeout):
  cellar    BUILD_DIR/cellar --threads T --quiet solids A.off B.off --op OP
            --options '{"fields":["stats","membership","result"]}'; its figure is stats.ms.total (from the parsed
            solids to the Boolean result: not reading the files nor writing the JSON) and its
            volume result.volume;
  Manifold  node bench/manifold_bool.mjs --warm --op OP A.off B.off; its figure is ms_warm (the
            op and its evaluation run a second time in the process, past WASM tier-up);
            beside it ms_build, the construction of its two input Manifolds (warm): its check,
            half-edges and collider, which cellar's figure counts (its check and input
            stages) and Manifold's op does not; xMe compares the two end to end;
  CGAL      cgal_bool --op OP A.off B.off (Epeck, PMP corefinement); its figure is "ms" (the
            Boolean only, after reading, checking and triangulating) and "area" is the area of
            the result's boundary.
A run whose process takes under 2 s is repeated (--repeat times in all, default 5) and the run
with the smallest figure kept (the machine is noisy; as bench/lib.sh does); the runs of cellar
and Manifold's warm op for one row take turns, so that both meet the same moments of the
machine, and are repeated while a run takes under 60 s (--repeat-under), so that the large
sizes' figures are not single samples; every column of a
row comes from the runs of this invocation, never from a cache.  Volumes are compared with
CGAL's: rel = |v - CGAL's| / |CGAL's|; agree "yes" within 1e-9 relative, "snap" within
precision * area (cellar's grid step, stats.precision, times the area of CGAL's result: how
far snapping every vertex to the grid may move the volume), else "NO".  A run that fails or
times out shows "failed" / "timeout" and the others still run.

Exit status: 0, or 1 when cellar or CGAL failed or timed out, cellar's volume disagrees with
CGAL's ("NO"), a case could not be generated or a refined mesh failed its CGAL check.
Manifold's failures and disagreements are reported but do not change it (it is optional), and
neither do the verdict lines (performance goals, not correctness).
"""
import argparse
import hashlib
import json
import mmap
import os
import re
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
REAL = os.path.join(ROOT, "tests", "data", "mesh", "real")
GEN = os.path.join(HERE, "gen3d.py")
OFFIO = os.path.join(HERE, "..", "tests", "offio.py")  # gen3d.py's OFF reader
MF = os.path.join(HERE, "manifold_bool.mjs")
TIME = "/usr/bin/time"
OPTS = '{"fields":["stats","membership","result"]}'
SCENES = ("rot", "box", "shell")
OPS_A = ("union", "intersection", "difference")
OPS_B = ("union", "intersection")
SIZES = (10000, 40000, 160000, 640000, 1000000, 2000000)
REFINED = "fertility"      # the mesh of part b
BIG = 160000               # part b's memory and thread verdicts hold from this size up
SKIPPED = {"cow": "its surface passes through itself: every program refuses it"}

status = 0                 # the exit status: set to 1 by fail()


def note(msg):
    """A message on stderr, prefixed like the other drivers' ("mesh3: ...")."""
    sys.stderr.write("mesh3: %s\n" % msg)
    sys.stderr.flush()


def fail(msg):
    """A message on stderr that also makes the exit status 1."""
    global status
    status = 1
    note(msg)


def out(line=""):
    """A line of the report on stdout, flushed at once (the runs take long)."""
    sys.stdout.write(line + "\n")
    sys.stdout.flush()


class BadOutput(Exception):
    """A program exited 0 but its output lacks what is read from it."""


# ---------------------------------------------------------------------------------------------
# Running the programs

class Run:
    """What is kept of one program on one case: state "ok", "failed", "timeout" or "skipped";
    fig, the figure compared (ms, in-program); wall, the whole process's seconds; mib, its peak
    RSS; data, what the parser returned (volume, and for cellar the stats)."""

    def __init__(self, state, fig=None, wall=None, mib=None, data=None):
        self.state, self.fig, self.wall, self.mib, self.data = state, fig, wall, mib, data or {}

    def ok(self):
        return self.state == "ok"

    def get(self, key):
        return self.data.get(key) if self.ok() else None


def run_once(cmd, path, limit):
    """Runs cmd once with stdout to path and stderr to path.err, under /usr/bin/time -f %M and
    timeout(1); returns (rc, wall seconds, peak RSS MiB or None).  rc is 124 on a timeout."""
    tfile = path + ".time"
    full = [TIME, "-f", "%M", "-o", tfile, "timeout", "-k", "10", str(limit)] + cmd
    t0 = time.monotonic()
    with open(path, "wb") as fo, open(path + ".err", "wb") as fe:
        p = subprocess.Popen(full, stdin=subprocess.DEVNULL, stdout=fo, stderr=fe,
                             start_new_session=True)
        try:
            rc = p.wait(timeout=limit + 60)        # timeout(1) should have ended it before
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)         # our own process group only
            p.wait()
            rc = 124
        except BaseException:                        # Ctrl-C: stop what we started
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()
            raise
    wall = time.monotonic() - t0
    mib = None
    try:
        with open(tfile) as f:
            lines = [ln for ln in f.read().split("\n") if ln.strip()]
        mib = int(lines[-1]) / 1024.0              # %M is in KiB; the last line (after any
    except (OSError, ValueError, IndexError):       # "Command exited with ..." note)
        pass
    return rc, wall, mib


def best_of(name, cmd, parse, workdir, repeat, limit):
    """Runs cmd (repeat times in all while a process takes under 2 s, as bench/lib.sh) and
    returns the Run with the smallest figure; parse(stdout path) gives (figure, data) or raises
    BadOutput.  A failure or a timeout ends the repeats and is reported on stderr."""
    return best_of_each([(name, cmd, parse)], workdir, repeat, limit)[0]


def best_of_each(progs, workdir, repeat, limit, under=2.0):
    """best_of for each (name, cmd, parse) of progs, their runs taken in turn (the first
    program, the second, ..., then again), so that the programs compared in a row meet the
    same moments of a noisy machine.  A program stops repeating after a run of `under` seconds
    or more, a failure or a timeout; the others go on.  Returns their Runs in order."""
    path = os.path.join(workdir, "out")
    best = [None] * len(progs)
    done = [False] * len(progs)
    for _ in range(max(1, repeat)):
        for i, (name, cmd, parse) in enumerate(progs):
            if done[i]:
                continue
            rc, wall, mib = run_once(cmd, path, limit)
            if rc == 124 or wall >= limit:
                note("%s timed out after %d s" % (name, limit))
                best[i], done[i] = Run("timeout"), True
                continue
            try:
                if rc != 0:
                    raise BadOutput(exit_text(rc))
                fig, data = parse(path)
            except (BadOutput, OSError, ValueError, KeyError, TypeError) as e:
                with open(path + ".err", "rb") as f:
                    err = f.read(600).decode("utf-8", "replace")
                note("%s failed (%s):\n%s" % (name, e, err.rstrip()))
                best[i], done[i] = Run("failed"), True
                continue
            fig = wall * 1000 if fig is None else fig  # no figure of its own: the wall time
            if best[i] is None or fig < best[i].fig:
                best[i] = Run("ok", fig, wall, mib, data)
            if wall >= under:
                done[i] = True
    for suffix in ("", ".err", ".time"):            # cellar's output can be hundreds of MB
        try:
            os.unlink(path + suffix)
        except OSError:
            pass
    return best


def exit_text(rc):
    """A process's status as text: "exit 1"; for 128 + a signal's number (timeout(1)'s status
    when its child died of that signal) with the signal's name: "exit 139: SIGSEGV"."""
    if rc > 128:
        try:
            return "exit %d: %s" % (rc, signal.Signals(rc - 128).name)
        except ValueError:
            pass
    return "exit %d" % rc


NUMBER = re.compile(rb"\s*(-?[0-9][0-9.eE+-]*)")


def parse_cellar(path):
    """cellar's output: (stats.ms.total, {"volume", "stats"}).  The output can be hundreds of MB
    (the result's faces come before its volume), so it is mapped, not loaded: "stats" (after
    "result") is decoded from its key on, and the volume is the number after the last
    "volume": of the result object (its last key)."""
    with open(path, "rb") as f:
        if os.fstat(f.fileno()).st_size == 0:
            raise BadOutput("no output")
        with mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as m:
            s = m.rfind(b'"stats":')
            r = m.find(b'"result":')
            if s < 0 or r < 0:
                raise BadOutput('no "stats" or no "result" in the output')
            tail = m[s + len(b'"stats":'):].decode()
            i = len(tail) - len(tail.lstrip())
            stats, _ = json.JSONDecoder().raw_decode(tail, i)
            v = m.rfind(b'"volume":', r, s if s > r else len(m))
            if v < 0:
                raise BadOutput('no "volume" in the result')
            g = NUMBER.match(m[v + len(b'"volume":'):v + 64])
            if not g:
                raise BadOutput("result.volume is not a number")
            volume = float(g.group(1))
    try:
        total = float(stats["ms"]["total"])
    except (KeyError, TypeError, ValueError):
        raise BadOutput("no stats.ms.total")
    return total, {"volume": volume, "stats": stats}


def json_line(path):
    """The last non-empty line of a program's output, as JSON (CGAL's and Manifold's)."""
    with open(path, "rb") as f:
        lines = [ln for ln in f.read().decode().split("\n") if ln.strip()]
    if not lines:
        raise BadOutput("no output")
    try:
        return json.loads(lines[-1])
    except ValueError:
        raise BadOutput("output is not JSON: %s" % lines[-1][:200])


def parse_cgal(path):
    """cgal_bool's line: (ms, {"volume", "area"})."""
    d = json_line(path)
    if "ms" not in d or "volume" not in d:
        raise BadOutput("no ms or volume")
    return float(d["ms"]), {"volume": float(d["volume"]), "area": float(d.get("area", 0))}


def parse_mf(path):
    """manifold_bool.mjs --warm's line: (ms_warm, {"volume", "ms_cold", "ms_build"})."""
    d = json_line(path)
    if "ms_warm" not in d or "volume" not in d or "ms_build" not in d:
        raise BadOutput("no ms_warm, ms_build or volume")
    return float(d["ms_warm"]), {"volume": float(d["volume"]), "ms_cold": float(d["ms"]),
                                 "ms_build": float(d["ms_build"])}


def parse_wall(path):
    """A run whose figure is the process's wall time (best_of takes it for a None figure)."""
    json_line(path)
    return None, {}


class Programs:
    """The three programs and the run settings: builds their command lines and runs them."""

    def __init__(self, build, args, workdir):
        self.cellar = os.path.join(build, "cellar")
        self.cgal = os.path.join(build, "tests", "ref", "cgal_bool")
        self.repeat, self.limit, self.workdir = args.repeat, args.timeout, workdir
        self.repeat_under = args.repeat_under
        self.use_cgal = not args.no_cgal
        self.mf_why = manifold_missing()
        self.cellar_id = self.binary_id()

    def binary_id(self):
        """build/cellar's (mtime, size, inode): another build may replace it during a run."""
        try:
            st = os.stat(self.cellar)
            return (st.st_mtime_ns, st.st_size, st.st_ino)
        except OSError:
            return None

    def rebuilt(self):
        """Prints a line into the table (and a note) when build/cellar changed since the last
        call (called after a row's runs, before the row is printed)."""
        now = self.binary_id()
        if now != self.cellar_id:
            self.cellar_id = now
            out("  (%s was rebuilt at %s: the row below may mix two binaries, the rows after"
                " it use the new one)" % (self.cellar, time.strftime(
                    "%H:%M:%SZ", time.gmtime(now[0] / 1e9)) if now else "?"))
            note("%s was rebuilt during the run" % self.cellar)

    def cellar_prog(self, label, files, op, threads):
        return ("cellar --threads %d (%s)" % (threads, label),
                [self.cellar, "--threads", str(threads), "--quiet", "solids"] + files +
                ["--op", op, "--options", OPTS], parse_cellar)

    def mf_prog(self, label, files, op, warm):
        """Manifold with --warm (figure ms_warm) or, warm=False, once per process (only its
        wall time and peak RSS are used)."""
        return ("manifold%s (%s)" % ("" if warm else " (once)", label),
                ["node", MF] + (["--warm"] if warm else []) + ["--op", op] + files,
                parse_mf if warm else parse_wall)

    def run_with_mf(self, label, files, op, threads):
        """cellar on each of threads and Manifold (warm), their runs in turn (best_of_each):
        the Runs of cellar in the order of threads, then Manifold's."""
        progs = [self.cellar_prog(label, files, op, t) for t in threads]
        if not self.mf_why:
            progs.append(self.mf_prog(label, files, op, True))
        runs = best_of_each(progs, self.workdir, self.repeat, self.limit, self.repeat_under)
        return runs if not self.mf_why else runs + [Run("skipped")]

    def run_cgal(self, label, files, op):
        if not self.use_cgal:
            return Run("skipped")
        return best_of("cgal_bool (%s)" % label, [self.cgal, "--op", op] + files, parse_cgal,
                       self.workdir, self.repeat, self.limit)

    def run_mf_once(self, label, files, op):
        """Manifold once per process, for its wall time and peak RSS."""
        if self.mf_why:
            return Run("skipped")
        return best_of(*self.mf_prog(label, files, op, False), self.workdir, self.repeat,
                       self.limit)


def manifold_missing():
    """Why Manifold cannot run (a note), or None: node and manifold-3d must be there, and
    manifold_bool.mjs without files exits 1 (its usage) rather than 2 (no module)."""
    if not shutil.which("node"):
        return "node is not installed"
    if not os.path.isdir(os.path.join(HERE, "node_modules", "manifold-3d")):
        return "bench/node_modules/manifold-3d is missing (npm ci --prefix bench)"
    rc = subprocess.run(["node", MF], stdout=subprocess.DEVNULL,
                        stderr=subprocess.DEVNULL).returncode
    return None if rc == 1 else "node cannot load manifold-3d"


def manifold_version():
    """manifold-3d's version from its package.json, or "?"."""
    try:
        with open(os.path.join(HERE, "node_modules", "manifold-3d", "package.json")) as f:
            return json.load(f).get("version", "?")
    except (OSError, ValueError):
        return "?"


# ---------------------------------------------------------------------------------------------
# The input cache

def file_hash(*paths):
    """The SHA-256 of the files' bytes, one after the other (the cache key of a case)."""
    h = hashlib.sha256()
    for p in paths:
        with open(p, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
    return h.hexdigest()


def replace_dir(tmp, final):
    """Moves the finished directory tmp to final (an older final is moved aside first, then
    removed), so that final is either absent or complete."""
    old = None
    if os.path.exists(final):
        old = "%s.old.%d" % (final, os.getpid())
        os.rename(final, old)
    os.rename(tmp, final)
    if old:
        shutil.rmtree(old, ignore_errors=True)


def case_files(cache, name, gen_args, source):
    """The two OFF files of a case in cache/name, generated by gen3d.py gen_args unless there
    with the same key (gen3d.py's, its reader's and source's hash); None (and status 1) when
    gen3d fails."""
    final = os.path.join(cache, name)
    files = [os.path.join(final, "s0000.off"), os.path.join(final, "s0001.off")]
    key = file_hash(GEN, OFFIO, source) + " " + " ".join(gen_args)
    try:
        with open(os.path.join(final, "key")) as f:
            if f.read().strip() == key and all(os.path.isfile(p) for p in files):
                return files
    except OSError:
        pass
    os.makedirs(cache, exist_ok=True)
    tmp = tempfile.mkdtemp(prefix=".tmp.%s." % name, dir=cache)
    os.chmod(tmp, 0o755)
    note("generating %s (gen3d.py %s)" % (name, " ".join(gen_args)))
    t0 = time.monotonic()
    p = subprocess.run([sys.executable, GEN] + gen_args + ["--off", tmp],
                       stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    if p.returncode != 0 or not all(os.path.isfile(os.path.join(tmp, os.path.basename(q)))
                                    for q in files):
        shutil.rmtree(tmp, ignore_errors=True)
        fail("gen3d.py %s failed:\n%s" % (" ".join(gen_args),
                                          p.stderr.decode("utf-8", "replace").rstrip()))
        return None
    with open(os.path.join(tmp, "key"), "w") as f:
        f.write(key + "\n")
    replace_dir(tmp, final)
    note("generated %s in %.1f s" % (name, time.monotonic() - t0))
    return files


def checked(progs, files):
    """Whether cgal_bool --op none accepts both solids (closed, not self-intersecting, bounding
    a volume); the answer is kept in the case's "checked" stamp (written under a temporary name,
    then renamed) and read from it later.  A rejection is reported loudly (status 1); a check
    that could not run (CGAL missing, crashed, timed out) too, and is not recorded."""
    d = os.path.dirname(files[0])
    stamp = os.path.join(d, "checked")
    rec = None
    try:
        with open(stamp) as f:
            rec = json.load(f)
    except (OSError, ValueError):
        pass
    if rec is None:
        if not progs.use_cgal:
            note("%s: not checked with CGAL (--no-cgal): used unchecked" % os.path.basename(d))
            return True
        note("checking %s with cgal_bool --op none" % os.path.basename(d))
        try:
            p = subprocess.run([progs.cgal, "--op", "none"] + files, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, timeout=progs.limit)
        except subprocess.TimeoutExpired:
            fail("cgal_bool --op none %s timed out: size skipped" % d)
            return False
        if p.returncode not in (0, 1):
            fail("cgal_bool --op none %s failed (exit %d): size skipped\n%s" %
                 (d, p.returncode, p.stderr.decode("utf-8", "replace").rstrip()))
            return False
        rec = {"ok": p.returncode == 0, "cgal": p.stdout.decode().strip(),
               "message": p.stderr.decode("utf-8", "replace").strip()[:2000],
               "date": time.strftime("%Y-%m-%dT%H:%MZ", time.gmtime())}
        with open(stamp + ".tmp", "w") as f:
            json.dump(rec, f)
            f.write("\n")
        os.rename(stamp + ".tmp", stamp)
    if not rec["ok"]:
        bar = "!" * 78
        fail("%s\nINVALID INPUT: %s does not pass cgal_bool --op none (checked %s):\n%s\n"
             "(remove %s to check again)\n%s" % (bar, d, rec.get("date", "?"),
                                                 rec.get("message", ""), stamp, bar))
        return False
    return True


# ---------------------------------------------------------------------------------------------
# Figures and formatting

def compare(v, ref, prec, area):
    """(rel, agree) of volume v against CGAL's ref: rel = |v - ref| / |ref|; agree "yes"
    within 1e-9 relative, "snap" within prec * area, else "NO"; ("-", "-") without both."""
    if v is None or ref is None:
        return "-", "-"
    d = abs(v - ref)
    rel = d / abs(ref) if ref != 0 else d
    if d <= 1e-9 * abs(ref):
        agree = "yes"
    elif d <= (prec or 0) * (area or 0):
        agree = "snap"
    else:
        agree = "NO"
    return "%.1e" % rel, agree


def ms(run):
    """A run's figure in ms for the table, or its state (failed, timeout, -)."""
    if run.ok():
        return "%.1f" % run.fig
    return "-" if run.state == "skipped" else run.state


def ratio(num, den):
    """num / den (two runs' figures), or None."""
    if num.ok() and den.ok() and den.fig > 0:
        return num.fig / den.fig
    return None


def ratio_e2e(mf, cel):
    """Manifold's construction of its inputs plus its op over cellar's figure (which counts
    cellar's check and input stages), or None."""
    if mf.ok() and cel.ok() and cel.fig > 0 and mf.get("ms_build") is not None:
        return (mf.get("ms_build") + mf.fig) / cel.fig
    return None


def fmt(x, spec="%.2f"):
    """x formatted, or "-" for None."""
    return "-" if x is None else spec % x


def mib(run):
    return fmt(run.mib, "%.0f") if run.ok() else "-"


def table_row(widths, cells):
    """One line of a table: cells right-aligned to widths, except the first ones given as
    negative widths (left-aligned)."""
    return " ".join(("%-*s" % (-w, c)) if w < 0 else ("%*s" % (w, c))
                    for w, c in zip(widths, cells))


def volume_columns(cel, mf, cg):
    """(cellar rel, agree, Manifold rel, agree) against CGAL's volume; a cellar "NO" sets the
    exit status (Manifold's is reported only)."""
    prec = (cel.get("stats") or {}).get("precision")
    ref, area = cg.get("volume"), cg.get("area")
    orel, oag = compare(cel.get("volume"), ref, prec, area)
    mrel, mag = compare(mf.get("volume"), ref, prec, area)
    if oag == "NO":
        fail("cellar's volume %r disagrees with CGAL's %r" % (cel.get("volume"), ref))
    return orel, oag, mrel, mag


def header_common(progs, threads_note):
    """The lines every part starts with: the programs and what their figures are."""
    out("  cellar   = %s %s --quiet solids A.off B.off --op OP" % (progs.cellar, threads_note))
    out("             (fields: stats, membership, result); ms = stats.ms.total: from the parsed solids to the")
    out("             Boolean result (not reading the files, not writing the JSON);")
    if progs.mf_why:
        out("  Manifold = not run: %s; its columns show -;" % progs.mf_why)
    else:
        out("  Manifold = node bench/manifold_bool.mjs --warm (manifold-3d %s, WASM, double"
            % manifold_version())
        out("             coordinates); ms = ms_warm: the op and its evaluation run a second")
        out("             time in the process;")
    if progs.use_cgal:
        out("  CGAL     = %s --op OP (Epeck, corefinement); ms = the" % progs.cgal)
        out("             Boolean only (after reading, checking and triangulating).")
    else:
        out("  CGAL     = not run (--no-cgal): no volume check; its columns show -.")
    out("  A process under 2 s runs %d time(s), the smallest ms kept (cellar's runs and"
        % progs.repeat)
    out("  Manifold's take turns, so that both meet the same moments of the machine, and repeat")
    out("  while a run takes under %g s); failed /" % progs.repeat_under)
    out("  timeout: the run failed or took over %d s.  rel = |volume - CGAL's| / CGAL's;"
        % progs.limit)
    out("  agr(ee): yes within 1e-9 relative, snap within cellar's precision * the area of")
    out("  CGAL's result, else NO.")


# ---------------------------------------------------------------------------------------------
# Part a: the real meshes

def part_a(progs, cache, meshes, threads):
    """Every mesh x scene x op: one row of ms, ratios and volumes; then, per scene, the median
    and minimum of Manifold/cellar and the verdict lines."""
    out("Part a: Booleans of two real meshes (%s, %s CPUs)" %
        (time.strftime("%Y-%m-%dT%H:%MZ", time.gmtime()), os.cpu_count() or "?"))
    out("  Inputs: gen3d.py mesh tests/data/mesh/real/MESH.off SCENE: rot (the mesh and its")
    out("  turned, moved copy), box (a box through it), shell (its copy scaled by 0.8 inside")
    out("  it); one OFF file per solid, cached in %s." % cache)
    header_common(progs, "--threads %d" % threads)
    out("  xM = Manifold ms / cellar ms, xC = CGAL ms / cellar ms (above 1: cellar is faster);")
    out("  xMe = (Manifold's construction of its two inputs + its op) / cellar ms: end to end")
    out("  from the meshes in memory, since cellar's figure counts its check and input stages")
    out("  and Manifold's op does not (ms_build of manifold_bool.mjs, warm).")
    for m, why in SKIPPED.items():
        out("  %s is left out: %s." % (m, why))
    W = (-16, -5, -12, 10, 10, 10, 6, 6, 6, 8, 4, 8, 4)
    out(table_row(W, ("mesh", "scene", "op", "cellar ms", "mf ms", "CGAL ms", "xM", "xC",
                      "xMe", "rel", "agr", "mf rel", "agr")))
    ratios = {s: [] for s in SCENES}            # per scene: xM of each row (None: no figure)
    ratios_e = {s: [] for s in SCENES}          # and xMe
    for mesh in meshes:
        src = os.path.join(REAL, mesh + ".off")
        for scene in SCENES:
            files = case_files(cache, "%s.%s" % (mesh, scene), ["mesh", src, scene], src)
            for op in OPS_A:
                label = "%s %s %s" % (mesh, scene, op)
                if files is None:
                    out(table_row(W, (mesh, scene, op, "no input")))
                    ratios[scene].append(None)
                    continue
                cel, mf = progs.run_with_mf(label, files, op, [threads])
                cg = progs.run_cgal(label, files, op)
                progs.rebuilt()
                bad = ["%s %s" % (who, run.state) for run, who in ((cel, "cellar"), (cg, "CGAL"))
                       if run.state in ("failed", "timeout")]
                if bad:
                    fail("%s: %s" % (label, ", ".join(bad)))
                xm, xc, xe = ratio(mf, cel), ratio(cg, cel), ratio_e2e(mf, cel)
                ratios[scene].append(xm)
                ratios_e[scene].append(xe)
                out(table_row(W, (mesh, scene, op, ms(cel), ms(mf), ms(cg), fmt(xm), fmt(xc),
                                  fmt(xe)) + volume_columns(cel, mf, cg)))
    out()
    out("Manifold ms / cellar ms per scene (all meshes and ops):")
    if progs.mf_why:
        out("  no figures: Manifold was not run (%s)" % progs.mf_why)
        return
    for scene in SCENES:
        xs = [x for x in ratios[scene] if x is not None]
        missing = len(ratios[scene]) - len(xs)
        if not ratios[scene]:
            continue
        if not xs:
            out("  %-5s no figures (%d rows failed)" % (scene, missing))
            continue
        med, low = statistics.median(xs), min(xs)
        gap = " (%d rows without a figure count as below)" % missing if missing else ""
        out("  %-5s median %.2f, minimum %.2f over %d rows%s" % (scene, med, low, len(xs), gap))
        out("  %-5s verdict: median >= 1.5: %s; every row >= 1: %s" %
            (scene, "yes" if med >= 1.5 else "no",
             "yes" if low >= 1 and not missing else "no"))
        xe = [x for x in ratios_e[scene] if x is not None]
        if xe:
            out("  %-5s end to end (xMe): median %.2f, minimum %.2f over %d rows" %
                (scene, statistics.median(xe), min(xe), len(xe)))


# ---------------------------------------------------------------------------------------------
# Part b: one mesh refined to millions of triangles

def part_b(progs, cache, sizes, threads):
    """Every size x op: cellar on threads and 2 x threads, Manifold, CGAL: ms, speed-ups,
    peak RSS, whole-process wall times, volumes; then the stage times and the verdicts."""
    t2 = 2 * threads
    src = os.path.join(REAL, REFINED + ".off")
    out("Part b: Booleans of %s.off refined to N triangles per solid with its turned copy"
        % REFINED)
    out("  (%s, %s CPUs).  Inputs: gen3d.py refine tests/data/mesh/real/%s.off N rot"
        % (time.strftime("%Y-%m-%dT%H:%MZ", time.gmtime()), os.cpu_count() or "?", REFINED))
    out("  (longest-edge splits, then Loop rounds), checked once with cgal_bool --op none")
    out("  (closed, not self-intersecting); cached in %s." % cache)
    header_common(progs, "--threads %d and %d" % (threads, t2))
    out("  c%d, c%d = cellar ms on %d and %d threads; x%d = c%d / c%d (the speed-up);"
        % (threads, t2, threads, t2, t2, threads, t2))
    out("  xM = Manifold ms / c%d, xC = CGAL ms / c%d (above 1: cellar is faster);"
        % (threads, threads))
    out("  mf bld = Manifold's construction of its two inputs (warm), xMe = (mf bld + mf ms) /")
    out("  c%d: end to end from the meshes in memory (cellar's figure counts its check and" % threads)
    out("  input stages, Manifold's op does not);")
    out("  MiB = peak RSS of the process (/usr/bin/time %M), Manifold's from a run without")
    out("  --warm (with it, its first result stays alive: 1.34 GB instead of 1.18 at 640000);")
    out("  wall c, wall mf = seconds of the whole process, reading and writing included: the")
    out("  c%d run (it writes the result as JSON) and Manifold's run without --warm (it writes"
        % threads)
    out("  one line).")
    W = (-8, -12, 9, 9, 5, 9, 9, 9, 6, 6, 6, 6, 6, 6, 6, 7, 7, 8, 4, 8, 4)
    out(table_row(W, ("N", "op", "c%d ms" % threads, "c%d ms" % t2, "x%d" % t2, "mf ms",
                      "mf bld", "CGAL ms", "xM", "xC", "xMe", "MiB c%d" % threads, "c%d" % t2,
                      "mf", "CGAL",
                      "wall c", "wall mf", "rel", "agr", "mf rel", "agr")))
    rows = []
    for n in sizes:
        name = "%s.%d.rot" % (REFINED, n)
        files = case_files(cache, name, ["refine", src, str(n), "rot"], src)
        ok = files is not None and checked(progs, files)
        for op in OPS_B:
            if not ok:
                out(table_row(W, (str(n), op, "no input" if files is None else
                                  "INVALID INPUT (CGAL check)")))
                rows.append((n, op, None))
                continue
            label = "%s %s" % (name, op)
            c1, c2, mf = progs.run_with_mf(label, files, op, [threads, t2])
            mf1 = progs.run_mf_once(label, files, op)
            cg = progs.run_cgal(label, files, op)
            progs.rebuilt()
            bad = ["%s %s" % (who, run.state) for run, who in
                   ((c1, "cellar --threads %d" % threads), (c2, "cellar --threads %d" % t2),
                    (cg, "CGAL")) if run.state in ("failed", "timeout")]
            if bad:
                fail("%s: %s" % (label, ", ".join(bad)))
            if c1.ok() and c2.ok() and c1.get("volume") != c2.get("volume"):
                note("%s: cellar's volume on %d threads %r differs from %d threads' %r" %
                     (label, t2, c2.get("volume"), threads, c1.get("volume")))
            row = {"c1": c1, "c2": c2, "mf": mf, "mf1": mf1, "cg": cg,
                   "x2": ratio(c1, c2), "xm": ratio(mf, c1), "xc": ratio(cg, c1),
                   "xe": ratio_e2e(mf, c1)}
            rows.append((n, op, row))
            out(table_row(W, (str(n), op, ms(c1), ms(c2), fmt(row["x2"]), ms(mf),
                              fmt(mf.get("ms_build"), "%.1f"), ms(cg), fmt(row["xm"]),
                              fmt(row["xc"]), fmt(row["xe"]), mib(c1), mib(c2), mib(mf1),
                              mib(cg), fmt(c1.wall if c1.ok() else None, "%.1f"),
                              fmt(mf1.wall if mf1.ok() else None, "%.1f")) +
                          volume_columns(c1, mf, cg)))
    stage_table(rows, threads)
    verdicts_b(rows, progs)


def stage_table(rows, threads):
    """cellar's stage times (stats.ms of the c1 runs above) and counts, to see where the
    time goes."""
    keys = ("check", "snap", "pairs", "cuts", "faces", "cells", "boolean", "total")
    out()
    out("cellar on %d thread(s), stats.ms by stage (the same runs as above), and its counts:"
        % threads)
    W = (-8, -12) + (8,) * len(keys) + (9, 9, 8)
    out(table_row(W, ("N", "op") + keys + ("in faces", "pairs", "cuts")))
    for n, op, row in rows:
        if row is None or not row["c1"].ok():
            continue
        st = row["c1"].get("stats")
        t = st.get("ms", {})
        out(table_row(W, (str(n), op) + tuple(fmt(t.get(k), "%.0f") for k in keys) +
                      tuple(str(st.get(k, "-")) for k in ("input_faces", "pairs_tested",
                                                          "cuts"))))


def verdicts_b(rows, progs):
    """The three verdict lines of part b (goals of the 3D core rewrite, not the exit status)."""
    out()
    out("Verdict (a row without a figure counts as not meeting a goal):")
    big = [r for r in rows if r[0] >= BIG]

    def line(text, subset, test, need_mf):
        if not subset:
            out("  %s: - (no such size run)" % text)
            return
        if need_mf and progs.mf_why:
            out("  %s: - (Manifold not run)" % text)
            return
        bad = [(n, op) for n, op, row in subset if row is None or not test(row)]
        out("  %s: %s%s" % (text, "no" if bad else "yes",
                            "" if not bad else " (not at %s)" %
                            ", ".join("%d %s" % b for b in bad)))

    line("Manifold ms / cellar ms >= 1.5 at every size", rows,
         lambda r: r["xm"] is not None and r["xm"] >= 1.5, True)
    line("end to end, (Manifold's construction + op) / cellar ms >= 1.5 at every size", rows,
         lambda r: r["xe"] is not None and r["xe"] >= 1.5, True)
    line("cellar peak RSS (both thread counts) <= Manifold's from %d up" % BIG, big,
         lambda r: r["c1"].ok() and r["c2"].ok() and r["mf1"].ok() and
         max(r["c1"].mib, r["c2"].mib) <= r["mf1"].mib, True)
    line("cellar's 2-thread speed-up >= 1.6 from %d up" % BIG, big,
         lambda r: r["x2"] is not None and r["x2"] >= 1.6, False)


# ---------------------------------------------------------------------------------------------

def int_list(text):
    """The argparse type of --sizes: "10000,40000" -> [10000, 40000]."""
    try:
        xs = [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError("not a list of integers: %s" % text)
    if not xs or any(x <= 0 for x in xs):
        raise argparse.ArgumentTypeError("not a list of positive integers: %s" % text)
    return xs


def main():
    ap = argparse.ArgumentParser(
        prog="mesh3.py", description="cellar, Manifold and CGAL on Booleans of real meshes"
        " (part a) and of a mesh refined to N triangles (part b); see the file's header.")
    ap.add_argument("build", metavar="BUILD_DIR")
    ap.add_argument("--part", choices=("a", "b", "all"), default="all")
    ap.add_argument("--sizes", type=int_list, default=list(SIZES),
                    help="part b's triangles per solid (default %s)" %
                    ",".join(map(str, SIZES)))
    ap.add_argument("--meshes", help="part a's meshes of tests/data/mesh/real (names without"
                    " .off, comma-separated; default all but cow)")
    ap.add_argument("--threads", type=int, default=1,
                    help="cellar's threads (part a; part b runs this and twice this)")
    ap.add_argument("--repeat", type=int, default=5,
                    help="runs of a process under 2 s (the smallest figure kept)")
    ap.add_argument("--repeat-under", type=float, default=60,
                    help="cellar's and Manifold's runs of a row are repeated while a run takes "
                    "under this many seconds (default 60; CGAL's and the others: 2)")
    ap.add_argument("--timeout", type=int, default=900, help="seconds a run may take")
    ap.add_argument("--no-cgal", action="store_true",
                    help="do not run CGAL (no volume check, no input check)")
    args = ap.parse_args()
    if args.threads < 1 or args.repeat < 1 or args.timeout < 1 or not args.repeat_under > 0:
        ap.error("--threads, --repeat and --timeout must be at least 1, --repeat-under above 0")

    all_meshes = sorted(f[:-4] for f in os.listdir(REAL) if f.endswith(".off"))
    meshes = args.meshes.split(",") if args.meshes else all_meshes
    for m in meshes:
        if m not in all_meshes:
            ap.error("no mesh %s.off in %s" % (m, REAL))
    meshes = [m for m in meshes if m not in SKIPPED]

    cache = os.path.join(args.build, "bench-cache")
    progs_need = [os.path.join(args.build, "cellar"), TIME]
    if not args.no_cgal:
        progs_need.append(os.path.join(args.build, "tests", "ref", "cgal_bool"))
    for p in progs_need:
        if not os.access(p, os.X_OK):
            note("%s is missing (make bench builds it)" % p)
            return 1
    if not shutil.which("timeout"):
        note("timeout (coreutils) is missing")
        return 1

    workdir = tempfile.mkdtemp(prefix="cellar-mesh3.")
    try:
        progs = Programs(args.build, args, workdir)
        if progs.mf_why:
            note("Manifold is skipped: %s" % progs.mf_why)
        if args.part in ("a", "all"):
            part_a(progs, cache, meshes, args.threads)
        if args.part == "all":
            out()
        if args.part in ("b", "all"):
            part_b(progs, cache, args.sizes, args.threads)
    except KeyboardInterrupt:
        note("interrupted")
        return 130
    finally:
        shutil.rmtree(workdir, ignore_errors=True)
    return status


if __name__ == "__main__":
    sys.exit(main())
