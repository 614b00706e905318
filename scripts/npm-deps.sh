#!/bin/sh
# scripts/npm-deps.sh DIR — the npm packages DIR/package-lock.json pins, into DIR/node_modules
# (npm ci), unless they are there already for this lockfile.  Node.js and npm come from
# Debian's packages (installed here when missing).
set -eu
cd "$(dirname "$0")/.."
dir=${1:?usage: scripts/npm-deps.sh DIR}
pkgs=""
command -v node >/dev/null 2>&1 || pkgs="$pkgs nodejs"
command -v npm >/dev/null 2>&1 || pkgs="$pkgs npm"
[ -z "$pkgs" ] || scripts/deps.sh $pkgs
lock=$dir/package-lock.json
stamp=$dir/node_modules/.cellar-lock
if [ -f "$stamp" ] && cmp -s "$lock" "$stamp"; then exit 0; fi
echo "deps: npm ci in $dir" >&2
npm ci --prefix "$dir" --no-audit --no-fund --loglevel=error >/dev/null
cp "$lock" "$stamp"
