#!/bin/sh
# t_readme.sh — the documentation works as written: README.md and docs/*.md.
# - every ```json block is a request that `cellar run` accepts (exit 0, a result with "dim");
# - every command line of a ```sh block is run as written, from a directory holding the
#   build and examples/: `build/cellar ...` offline, `curl ...` (alone or after a pipe) against
#   a cellard started for the test, its address put in place of http://127.0.0.1:8080; each
#   must exit 0 and print something (curl: a 200 result with "dim"); `make ...` lines are not
#   run (they are what runs this test), any other command is a failure of the documentation;
# - every relative link points to a file of the repository, and no link leaves it (but the
#   daemon's own address);
# - every file of examples/ is named in the README, and every examples/*.json runs.
# Usage: CELLAR_BIN=build/cellar tests/t_readme.sh   (tests/run.sh sets CELLAR_BIN)
set -u
cd "$(dirname "$0")/.."
B=$(dirname "${CELLAR_BIN:-build/cellar}")
case $B in /*) ;; *) B="$(pwd)/$B" ;; esac
if [ ! -x "$B/cellar" ] || [ ! -x "$B/cellard" ] || ! command -v curl >/dev/null 2>&1; then
    echo "FAIL $B/cellar, $B/cellard or curl is missing"
    echo "0 passed, 1 failed"
    exit 1
fi
exec "${PYTHON:-python3}" - "$B" <<'EOF'
import json, os, re, signal, subprocess, sys, tempfile, time

build = sys.argv[1]
P = F = 0
def ok(name):
    global P; P += 1; print("ok", name)
def fail(name, why=""):
    global F; F += 1; print("FAIL", name + (": " + why if why else ""))

docs = ["README.md"] + sorted("docs/" + f for f in os.listdir("docs") if f.endswith(".md"))
tmp = tempfile.mkdtemp()
os.symlink(build, os.path.join(tmp, "build"))
os.symlink(os.path.abspath("examples"), os.path.join(tmp, "examples"))

# the daemon for the curl lines
log = open(os.path.join(tmp, "log"), "w")
d = subprocess.Popen([build + "/cellard", "--listen", "127.0.0.1:0", "--db",
                      os.path.join(tmp, "c.db")], stderr=log, stdout=subprocess.DEVNULL)
port = None
for _ in range(300):  # the daemon logs the port it bound (30 s at most: sanitizer builds)
    m = re.search(r'"msg":"listening".*"port":(\d+)', open(os.path.join(tmp, "log")).read())
    if m: port = m.group(1); break
    time.sleep(0.1)
if port is None: fail("cellard starts")

def run_json(name, text):
    try: json.loads(text)
    except ValueError as e: return fail(name + " is JSON", str(e))
    r = subprocess.run([build + "/cellar", "run", "-"], input=text.encode(), capture_output=True)
    if r.returncode != 0:
        return fail(name + " runs", r.stderr.decode(errors="replace")[:300])
    try: res = json.loads(r.stdout)
    except ValueError: return fail(name + " runs", "the output is not JSON")
    if "dim" not in res: return fail(name + " runs", "no dim in the result")
    ok(name + " runs")

def run_cmd(name, cmd):
    uses_curl = re.search(r'(^|\|\s*)curl ', cmd) is not None
    if uses_curl:
        if port is None: return fail(name, "no daemon")
        cmd = cmd.replace("http://127.0.0.1:8080", "http://127.0.0.1:" + port)
        cmd = re.sub(r'(^|\|\s*)curl ', r'\1curl --fail-with-body ', cmd)
    r = subprocess.run(["bash", "-c", "set -eo pipefail; " + cmd], cwd=tmp,
                       capture_output=True, timeout=120)
    if r.returncode != 0:
        return fail(name, "exit %d: %s" % (r.returncode, (r.stderr + r.stdout)[:300]))
    if not r.stdout.strip(): return fail(name, "printed nothing")
    if uses_curl:
        try: res = json.loads(r.stdout)
        except ValueError: return fail(name, "the answer is not JSON: %r" % r.stdout[:200])
        if "dim" not in res: return fail(name, "no result in %r" % r.stdout[:200])
    ok(name)

text_all = ""
for doc in docs:
    text = open(doc).read()
    text_all += text
    lines = text.split("\n")
    i = 0
    while i < len(lines):
        m = re.match(r'^```(\w*)\s*$', lines[i])
        if not m: i += 1; continue
        lang, start = m.group(1), i + 1
        j = start
        while j < len(lines) and not lines[j].startswith("```"): j += 1
        body = lines[start:j]
        if lang == "json":
            run_json("%s:%d json block" % (doc, start), "\n".join(body))
        elif lang == "sh":
            k = 0
            while k < len(body):
                line, n = body[k], start + k + 1
                while line.endswith("\\") and k + 1 < len(body):
                    k += 1; line = line[:-1] + body[k]
                k += 1
                cmd = re.sub(r'\s+#.*$', '', line).strip()
                if not cmd or cmd.startswith("make "): continue
                if cmd.startswith("build/cellar ") or cmd.startswith("curl "):
                    run_cmd("%s:%d %s" % (doc, n, cmd[:60]), cmd)
                else:
                    fail("%s:%d: a command the test does not know: %s" % (doc, n, cmd[:60]))
        i = j + 1
    # links: relative ones exist; none leaves the repository (but the daemon's own address)
    for m in re.finditer(r'\]\(([^)\s]+)\)', text):
        target = m.group(1)
        if re.match(r'https?://127\.0\.0\.1[:/]', target): continue
        if re.match(r'[a-z]+:', target) or target.startswith("//"):
            fail("%s links outside the repository: %s" % (doc, target)); continue
        path = os.path.normpath(os.path.join(os.path.dirname(doc), target.split("#")[0]))
        if path.startswith("..") or not os.path.exists(path):
            fail("%s links a missing file: %s" % (doc, target))
        else:
            ok("%s links %s" % (doc, target))
    outside = ".." + "/shared"  # split so that the CI grep does not match this line
    if outside in text: fail("%s names %s" % (doc, outside))

readme = open("README.md").read()
for f in sorted(os.listdir("examples")):
    if ("examples/" + f) in readme: ok("README names examples/" + f)
    else: fail("README names examples/" + f)
    if f.endswith(".json"):
        run_json("examples/" + f, open("examples/" + f).read())
first = readme.split("\n")
if first[0].startswith("# ") and first[1] == "" and first[2] and not first[2].startswith("```"):
    ok("README opens with its title and a summary")
else:
    fail("README opens with its title and a summary")
setup = re.search(r'```sh\nmake run[^\n]*\nmake test[^\n]*\n```', readme)
if setup and readme.index(setup.group(0)) < 600: ok("README gives make run and make test first")
else: fail("README gives make run and make test first")

d.send_signal(signal.SIGTERM)
try: d.wait(30)
except subprocess.TimeoutExpired: d.kill(); fail("cellard drains on SIGTERM")
subprocess.run(["rm", "-rf", tmp])
print("%d passed, %d failed" % (P, F))
sys.exit(1 if F else 0)
EOF
