#!/bin/sh
# bench/http_compare.sh OLD_CELLARD NEW_CELLARD — bench/http.sh's two wrk runs (cached GET of a
# small result, uncached small POST with Prefer: wait=5) against two builds of cellard in one
# run, alternating OLD, NEW, OLD, NEW so that the machine's noise falls on both alike.
# DURATION (seconds, default 10), CONNECTIONS (default 32), ROUNDS (default 2).
set -eu
OLD=$1 NEW=$2
D=${DURATION:-10}
C=${CONNECTIONS:-32}
ROUNDS=${ROUNDS:-2}
command -v wrk >/dev/null || { echo "bench/http_compare.sh: wrk is not installed (apt-get install wrk)" >&2; exit 1; }
tmp=$(mktemp -d)
pid=""
trap '[ -n "$pid" ] && kill "$pid" 2>/dev/null; rm -rf "$tmp"' EXIT
one() { # LABEL BINARY [FLAGS...]
    label=$1 bin=$2
    shift 2
    rm -f "$tmp"/c.db*
    port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
    "$bin" --listen 127.0.0.1:$port --db "$tmp/c.db" --log-level warn "$@" 2>"$tmp/log" &
    pid=$!
    for i in $(seq 50); do curl -fs "http://127.0.0.1:$port/healthz" >/dev/null 2>&1 && break; sleep 0.1; done
    url=http://127.0.0.1:$port
    hash=$(curl -fs -D - -o /dev/null -H 'Content-Type: application/json' -H 'Prefer: wait=5' \
        --data @tests/cases/orthogonal/request.json "$url/v1/jobs" | tr -d '\r' | sed -n 's/^ETag: "\(.*\)"/\1/p')
    g=$(wrk -t2 -c"$C" -d"${D}s" --latency -s bench/wrk_get.lua "$url/v1/results/$hash")
    p=$(wrk -t2 -c"$C" -d"${D}s" --latency -s bench/wrk_post.lua "$url")
    kill "$pid"; wait "$pid" 2>/dev/null || true; pid=""
    rps() { echo "$1" | sed -n 's/^Requests\/sec: *\([0-9.]*\).*/\1/p'; }
    pct() { echo "$1" | sed -n "s/^ *$2% *\([0-9.]*[a-z]*\).*/\1/p"; }
    bad() { echo "$1" | sed -n 's/^non-200 responses: \([0-9]* (of [0-9]*)\).*/\1/p' | head -n 1; }
    printf '%-4s  GET %9s req/s  p50 %8s  p99 %8s   POST %7s req/s  p50 %8s  p99 %8s  %s\n' "$label" \
        "$(rps "$g")" "$(pct "$g" 50)" "$(pct "$g" 99)" "$(rps "$p")" "$(pct "$p" 50)" "$(pct "$p" 99)" \
        "$(bad "$p" | sed 's/^/non-200 POSTs: /')"
}
echo "$C connections, ${D} s a run, 2 wrk threads, loopback; GET: a cached small result, POST: a small uncached job"
for r in $(seq "$ROUNDS"); do
    one old "$OLD"
    one new "$NEW" --max-per-ip 0
done
