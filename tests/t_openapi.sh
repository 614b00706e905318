#!/bin/sh
# t_openapi.sh — schemas/openapi.json passes a real OpenAPI linter: Redocly CLI (from npm, at
# the version tests/lint/package-lock.json pins; `make deps` installs it), its recommended rules,
# no error allowed.  Its warnings are printed, not counted.  A missing linter is a failure.
set -u
cd "$(dirname "$0")/.."
. tests/lib.sh
cli=tests/lint/node_modules/.bin/redocly
[ -x "$cli" ] || give_up "openapi lint: $cli is missing (make deps installs it: scripts/npm-deps.sh tests/lint)"
export REDOCLY_TELEMETRY=off REDOCLY_SUPPRESS_UPDATE_NOTICE=true NO_COLOR=1
"$cli" lint schemas/openapi.json --format=summary >"$T/out" 2>&1
rc=$?
sed -n '/^error\|^warning/p' "$T/out"
errors=$(sed -n 's/^error .*: \([0-9]*\)$/\1/p' "$T/out" | awk '{s += $1} END {print s + 0}')
if [ $rc -eq 0 ] && [ "$errors" = 0 ]; then
    pass "openapi.json: Redocly's recommended rules, no error"
else
    tail -n 20 "$T/out"
    fail "openapi.json: Redocly lint exited $rc with $errors errors"
fi
finish
