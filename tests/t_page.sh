#!/bin/sh
# The web page at /, in a real browser: headless Chromium driven by playwright-core posts an
# SVG drawing and must show its complex as a picture with one filled path per face (the count
# the CLI gives for the same drawing).  Needs /usr/bin/chromium, node and playwright-core in
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
"$B/cellard" --listen 127.0.0.1:0 --db "$tmp/c.db" 2>"$tmp/log" &
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
P=0; F=0
drawing=tests/data/svg/holes.svg
want=$("$B/cellar" svg "$drawing" --y-up | sed -n 's/.*"F":\([0-9]*\).*/\1/p')
out=$(NODE_PATH=tests/browser/node_modules timeout 90 node tests/page.js "http://127.0.0.1:$port/" "$drawing" "$tmp/page.png" 2>&1)
echo "$out"
got=$(printf '%s\n' "$out" | sed -n 's/^face paths: //p')
if printf '%s\n' "$out" | grep -q "^status: 200 OK"; then echo "ok page: the drawing computes (200)"; P=$((P+1)); else echo "FAIL page: no 200 status line"; F=$((F+1)); fi
if [ -n "$want" ] && [ "$got" = "$want" ]; then echo "ok page: $got face paths drawn, as the CLI's F"; P=$((P+1)); else echo "FAIL page: $got face paths drawn, the CLI says F=$want"; F=$((F+1)); fi
echo "$P passed, $F failed"
[ "$F" -eq 0 ]
