#!/bin/sh
# The web page at / in a real browser: headless Chromium (Debian's /usr/bin/chromium) driven by
# playwright-core runs tests/page.js against a cellard of its own (a free port, a temporary
# --db, --workers 1 --job-threads 1 so that a long job stays long): every example of examples/
# renders as its result says (faces drawn, meshes, a Boolean's highlight), 2D hover, zoom,
# explode and numbers, 3D pick, show/hide, explode and numbers, GeoJSON, OFF and OBJ inputs,
# readable errors for bad inputs, a long job's progress and its Cancel, and the figures (page
# weight, time to the first picture for the five cubes and for 100 000 faces).  Screenshots go
# to tests/out/page/.  Needs /usr/bin/chromium, node and playwright-core in
# tests/browser/node_modules: `make deps` installs them (scripts/browser-deps.sh).  A missing
# piece is a failure; the test is skipped only when CELLAR_SKIP_BROWSER=1 asks for it.
set -u
cd "$(dirname "$0")/.."
B=${CELLAR_BUILD:-build}
if [ "${CELLAR_SKIP_BROWSER:-0}" = 1 ]; then
    echo "skip page: CELLAR_SKIP_BROWSER=1"
    echo "0 passed, 0 failed, 1 skipped"
    exit 0
fi
missing=""
[ -x /usr/bin/chromium ] || missing="$missing /usr/bin/chromium"
command -v node >/dev/null 2>&1 || missing="$missing node"
[ -d tests/browser/node_modules/playwright-core ] || missing="$missing playwright-core"
if [ -n "$missing" ]; then
    echo "FAIL page: missing$missing (make deps installs them; CELLAR_SKIP_BROWSER=1 skips)"
    echo "0 passed, 1 failed"
    exit 1
fi
tmp=$(mktemp -d)
"$B/cellard" --listen 127.0.0.1:0 --db "$tmp/c.db" --workers 1 --job-threads 1 2>"$tmp/log" &
pid=$!
trap 'kill $pid 2>/dev/null; wait $pid 2>/dev/null; rm -rf "$tmp"' EXIT
port=""
for i in $(seq 300); do  # the daemon logs the port it bound (30 s at most: sanitizer builds)
    port=$(sed -n 's/.*"msg":"listening".*"port":\([0-9]*\).*/\1/p' "$tmp/log" | head -n 1)
    [ -n "$port" ] && break
    sleep 0.1
done
if [ -z "$port" ]; then
    echo "FAIL page: cellard did not start"; cat "$tmp/log"; echo "0 passed, 1 failed"; exit 1
fi
# a job of many seconds on one thread (16 000 random segments, 3.2 million faces: 14 s here,
# so that it is still running when the test has seen its progress move and presses Cancel, also
# on a loaded machine; 12 000 took 7 s and was sometimes done first), and a result of 100 000
# faces (2 920 segments: 100 012 faces)
"$B/cellar" gen lines 16000 0.4 1 >"$tmp/long.json"
"$B/cellar" gen lines 2920 0.4 1 >"$tmp/big.json"
# this machine's pace now: the best of three runs of a reference job (400 long segments) over
# a quiet machine's 0.04 s; page.js stretches its waits by it (never below 1)
"$B/cellar" gen lines 400 1.0 77 >"$tmp/pace.json"
best=""
for i in 1 2 3; do
    t0=$(date +%s%N)
    "$B/cellar" --threads 1 --quiet run "$tmp/pace.json" >/dev/null
    t=$(( $(date +%s%N) - t0 ))
    if [ -z "$best" ] || [ "$t" -lt "$best" ]; then best=$t; fi
done
CELLAR_PACE=$(awk -v t="$best" 'BEGIN { p = t / 4e7; print (p > 1 ? p : 1) }')
export CELLAR_PACE
out=tests/out/page
rm -rf "$out" && mkdir -p "$out"
NODE_PATH=tests/browser/node_modules timeout 600 node tests/page.js "http://127.0.0.1:$port/" "$out" \
    "$tmp/long.json" "$tmp/big.json"
rc=$?
# a summary line even when node was killed
[ $rc -eq 124 ] && echo "FAIL page: tests/page.js timed out" && echo "0 passed, 1 failed"
exit $rc
