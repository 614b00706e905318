#!/bin/sh
# Runs every tests/cases/*/request.json through the CLI and checks each "key": integer of
# expect.json against the result's stats.  Prints "ok"/"FAIL" per case and a summary line.
set -u
BIN=${CELLAR_BIN:-build/cellar}
cd "$(dirname "$0")/.."
P=0; F=0
for d in tests/cases/*/; do
    name=$(basename "$d")
    [ -f "$d/request.json" ] || continue
    out=$("$BIN" run "$d/request.json" 2>&1)
    rc=$?
    stats=$(printf '%s' "$out" | sed -n 's/.*"stats":{\(.*\)/\1/p')
    fail=""
    [ $rc -eq 0 ] || fail="exit $rc: $out"
    for kv in $(tr -d '{} \n' < "$d/expect.json" | tr ',' ' '); do
        key=${kv%%:*}; val=${kv#*:}
        got=$(printf '%s' "$stats" | grep -o "$key:[0-9]*" | head -n 1 | cut -d: -f2)
        [ "$got" = "$val" ] || fail="$fail $key=$got (want $val)"
    done
    if [ -z "$fail" ]; then echo "ok case $name"; P=$((P + 1)); else echo "FAIL case $name:$fail"; F=$((F + 1)); fi
done
echo "$P passed, $F failed"
[ "$F" -eq 0 ]
