#!/bin/sh
# Installs what the browser test (tests/t_page.sh) needs: Debian's chromium and Node.js (npm
# too, where the node in place came without it), then playwright-core from npm at the version
# tests/browser/package-lock.json pins, into tests/browser/node_modules.  Playwright never
# downloads a browser: the test drives /usr/bin/chromium.
# CELLAR_SKIP_BROWSER=1 installs nothing (and t_page.sh then reports itself skipped).
set -eu
cd "$(dirname "$0")/.."
[ "${CELLAR_SKIP_BROWSER:-0}" = 1 ] && exit 0
pkgs="chromium"
command -v node >/dev/null 2>&1 || pkgs="$pkgs nodejs"
command -v npm >/dev/null 2>&1 || pkgs="$pkgs npm"
scripts/deps.sh $pkgs
lock=tests/browser/package-lock.json
stamp=tests/browser/node_modules/.cellar-lock
if [ -f "$stamp" ] && cmp -s "$lock" "$stamp"; then exit 0; fi
echo "deps: npm ci in tests/browser (playwright-core)" >&2
npm ci --prefix tests/browser --no-audit --no-fund --loglevel=error >/dev/null
cp "$lock" "$stamp"
