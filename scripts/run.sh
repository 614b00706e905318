#!/bin/sh
# `make run`: starts the service when it is built (build/cellard, the daemon issue);
# until then, runs the command-line tool on the seeds' orthogonal example and prints its faces.
set -eu
B=${1:-build}
if [ -x "$B/cellard" ]; then
    exec "$B/cellard" "$@"
fi
echo "cellard (the HTTP daemon) is not built yet; running the CLI on tests/cases/orthogonal:" >&2
"$B/cellar" run tests/cases/orthogonal/request.json
