#!/bin/sh
# Installs the Debian packages given as arguments when any of them is missing.
# Runs `apt-get update` only when something has to be installed.  nodejs and npm count as
# there when `node` and `npm` are (a NodeSource nodejs brings its own npm and conflicts with
# Debian's npm package).
set -eu
missing=""
for p in "$@"; do
    case $p in
    nodejs) command -v node >/dev/null 2>&1 && continue ;;
    npm) command -v npm >/dev/null 2>&1 && continue ;;
    esac
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing="$missing $p"
done
[ -z "$missing" ] && exit 0
echo "deps: installing$missing" >&2
SUDO=""
[ "$(id -u)" = 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q >/dev/null
$SUDO apt-get install -y -q --no-install-recommends $missing >/dev/null
