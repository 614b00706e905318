#!/bin/sh
# web-build.sh OUTDIR — builds the page (web/) into OUTDIR with web/build.mjs, after `npm ci`
# in web/ when web/node_modules is missing or older than web/package-lock.json (three.js and
# esbuild at the versions the lockfile pins).  Needs node and npm (Debian: nodejs npm; `make
# deps` installs them).
set -eu
cd "$(dirname "$0")/.."
out=$1
for c in node npm; do
    command -v $c >/dev/null 2>&1 || {
        echo "web-build: $c is missing: the page is bundled at build time (apt-get install nodejs npm, or make deps)" >&2
        exit 1
    }
done
lock=web/package-lock.json
stamp=web/node_modules/.cellar-lock
if ! [ -f "$stamp" ] || ! cmp -s "$lock" "$stamp"; then
    echo "web-build: npm ci in web/ (three, esbuild)" >&2
    npm ci --prefix web --no-audit --no-fund --loglevel=error >/dev/null
    cp "$lock" "$stamp"
fi
mkdir -p "$out"
exec node web/build.mjs "$out"
