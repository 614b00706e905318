#!/bin/sh
# t_objparts.sh — the page and the CLI read an OBJ file into the same solids (issue 26, item 4):
# for every OBJ file of tests/data, examples and the fuzz corpus, the page's reader
# (web/src/input.js readObj, run by node) and `cellar solids FILE --format request` give the
# same number of solids with the same numbers of faces and vertices, or both refuse the file.
# Needs node (make deps installs it, for the page); the test is skipped only when
# CELLAR_SKIP_BROWSER=1 asks for it.
set -u
cd "$(dirname "$0")/.." || exit 1
. tests/lib.sh
B=${CELLAR_BUILD:-build}
CELLAR=${CELLAR_BIN:-$B/cellar}
if [ "${CELLAR_SKIP_BROWSER:-0}" = 1 ]; then
    echo "skip objparts: CELLAR_SKIP_BROWSER=1"
    echo "0 passed, 0 failed, 1 skipped"
    exit 0
fi
command -v node >/dev/null 2>&1 || give_up "node is not installed (make deps installs it)"
[ -x "$CELLAR" ] || give_up "$CELLAR is not built"

# "solids faces vertices ..." for a file, or "refused"
page_parts() {
    node -e '
import("./web/src/input.js").then((m) => {
  const t = require("fs").readFileSync(process.argv[1], "utf8");
  let s;
  try { s = m.readObj(t, "f"); } catch (e) { console.log("refused"); return; }
  console.log([s.length].concat(s.map((x) => x.FV.length + ":" + x.V.length)).join(" "));
});' "$1"
}
cli_parts() {
    if ! "$CELLAR" solids "$1" --format request >"$T/req.json" 2>/dev/null; then
        echo refused
        return
    fi
    python3 -c '
import json, sys
s = json.load(open(sys.argv[1]))["solids"]
print(" ".join([str(len(s))] + ["%d:%d" % (len(x["FV"]), len(x["V"])) for x in s]))' "$T/req.json"
}

for f in tests/data/mesh/*.obj examples/*.obj tests/fuzz/corpus/obj/*.obj; do
    [ -f "$f" ] || continue
    p=$(page_parts "$f")
    c=$(cli_parts "$f")
    check "$f: the page and the CLI read the same solids (page: $p, CLI: $c)" test "$p" = "$c"
done
# a file of two objects, one of its objects with no face
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\no a\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\no empty\no b\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n' >"$T/two.obj"
p=$(page_parts "$T/two.obj")
c=$(cli_parts "$T/two.obj")
check "two objects (and one empty): page $p, CLI $c" test "$p" = "$c" -a "$p" = "2 4:4 4:4"
finish
