#!/bin/sh
# bench/http.sh BUILD_DIR — throughput and latency of cellard on loopback, measured with wrk
# (Debian's wrk): GET /v1/results/{hash} of a small cached result, and POST /v1/jobs of a
# small uncached job with Prefer: wait=5.  Starts its own daemon on a free port with a
# temporary database.  DURATION (seconds, default 10) and CONNECTIONS (default 32) tune it.
set -eu
B=${1:-build}
D=${DURATION:-10}
C=${CONNECTIONS:-32}
command -v wrk >/dev/null || { echo "bench/http.sh: wrk is not installed (apt-get install wrk)" >&2; exit 1; }
tmp=$(mktemp -d)
trap 'kill "$pid" 2>/dev/null; wait "$pid" 2>/dev/null; rm -rf "$tmp"' EXIT
port=$(( 20000 + $$ % 20000 ))
"$B/cellard" --listen 127.0.0.1:$port --db "$tmp/cellar.db" --log-level warn --max-per-ip 0 \
    2>"$tmp/log" &
pid=$!
for i in $(seq 50); do curl -fs "http://127.0.0.1:$port/healthz" >/dev/null 2>&1 && break; sleep 0.1; done
url=http://127.0.0.1:$port
hash=$(curl -fs -D - -o /dev/null -H 'Content-Type: application/json' -H 'Prefer: wait=5' \
    --data @tests/cases/orthogonal/request.json "$url/v1/jobs" | tr -d '\r' | sed -n 's/^ETag: "\(.*\)"/\1/p')
echo "== GET /v1/results/{hash} (cached, $(curl -fs "$url/v1/results/$hash" | wc -c) bytes), $C connections, ${D}s"
wrk -t2 -c"$C" -d"${D}s" --latency -s bench/wrk_get.lua "$url/v1/results/$hash" | grep -E "Requests/sec|non-|p50|Latency "
echo "== POST /v1/jobs (uncached small job, Prefer: wait=5), $C connections, ${D}s"
wrk -t2 -c"$C" -d"${D}s" --latency -s bench/wrk_post.lua "$url" | grep -E "Requests/sec|non-|p50|Latency "
