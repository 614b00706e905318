#!/bin/sh
# bench/cluster.sh BUILD_DIR — cellard on PostgreSQL with 1, 2 and 3 daemons behind nginx,
# beside one daemon on SQLite, in one run (wrk from Debian's packages, on loopback):
#   - GET /v1/results/{hash} of a small cached result;
#   - POST /v1/jobs of a small uncached job (different every request) with Prefer: wait=5;
# requests per second, p50 and p99; then the time from SIGKILL of the daemon running a job to
# that job done by another (with the default 30 s lease, and with --lease-seconds 5).
# Starts a private PostgreSQL (initdb in a temporary directory, as the postgres user when run
# as root), nginx with deploy/nginx.conf (as tests/test_cluster.c does), and the daemons.
# DURATION (seconds a wrk run, default 10), CONNECTIONS (default 32) tune it.
set -eu
B=${1:-build}
case $B in /*) ;; *) B="$(pwd)/$B" ;; esac
D=${DURATION:-10}
C=${CONNECTIONS:-32}
for c in wrk nginx psql curl; do
    command -v $c >/dev/null || { echo "bench/cluster.sh: $c is not installed (apt-get install wrk nginx-light postgresql)" >&2; exit 1; }
done
PGBIN=$(ls -d /usr/lib/postgresql/*/bin | tail -n 1)
tmp=$(mktemp -d /tmp/cellar-bench-cluster-XXXXXX)
AS=""
if [ "$(id -u)" = 0 ]; then chown postgres "$tmp"; AS="runuser -u postgres --"; fi
pids=""
cleanup() {
    for p in $pids; do kill "$p" 2>/dev/null || true; done
    for p in $pids; do wait "$p" 2>/dev/null || true; done
    [ -f "$tmp/nginx.pid" ] && nginx -c "$tmp/etc/nginx.conf" -p "$tmp" -s stop 2>/dev/null || true
    $AS "$PGBIN/pg_ctl" -D "$tmp/pg" -m immediate stop >/dev/null 2>&1 || true
    rm -rf "$tmp"
}
trap cleanup EXIT
trap 'exit 130' INT TERM
freeport() { python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }

pgport=$(freeport)
$AS "$PGBIN/initdb" -D "$tmp/pg" --auth=trust -U postgres --no-sync >/dev/null
$AS "$PGBIN/pg_ctl" -D "$tmp/pg" -l "$tmp/pg.log" -w -o "-k $tmp -p $pgport -h 127.0.0.1 -c max_connections=300" start >/dev/null

# start_daemon NAME DB: a daemon on a free port; its port in $port
start_daemon() {
    port=$(freeport)
    "$B/cellard" --listen 127.0.0.1:$port --db "$2" --name "$1" --log-level warn --max-per-ip 0 \
        --queue 100000 2>>"$tmp/$1.log" &
    pids="$pids $!"
    for i in $(seq 100); do curl -fs "http://127.0.0.1:$port/healthz" >/dev/null 2>&1 && return 0; sleep 0.1; done
    echo "bench/cluster.sh: daemon $1 did not start" >&2; cat "$tmp/$1.log" >&2; exit 1
}
stop_daemons() {
    for p in $pids; do kill "$p" 2>/dev/null || true; done
    for p in $pids; do wait "$p" 2>/dev/null || true; done
    pids=""
    [ -f "$tmp/nginx.pid" ] && nginx -c "$tmp/etc/nginx.conf" -p "$tmp" -s stop 2>/dev/null || true
    sleep 0.5
}
# nginx in front of the ports given, from deploy/nginx.conf; its port in $nport
start_nginx() {
    rm -rf "$tmp/etc" "$tmp/logs" "$tmp/modules"
    cp -a /etc/nginx "$tmp/etc"; mkdir -p "$tmp/logs"; ln -s /usr/lib/nginx/modules "$tmp/modules"
    sed -i "s#/etc/nginx#$tmp/etc#g; s#^pid .*#pid $tmp/nginx.pid;#; s#/var/log/nginx#$tmp/logs#g; s#worker_processes .*#worker_processes 1;#" "$tmp/etc/nginx.conf"
    nport=$(freeport)
    servers=""
    for p in "$@"; do servers="$servers    server 127.0.0.1:$p max_fails=1 fail_timeout=5s;\n"; done
    awk -v s="$servers" '/^upstream cellard \{/ { print; printf "%s", s; skip = 1; next }
        skip && /^ *server / { next } { skip = skip && !/^\}/; print }' deploy/nginx.conf |
        sed -e "s/listen 80 default_server/listen $nport default_server/" -e '/listen \[::\]/d' \
            -e 's/^\( *\)access_log .*//' > "$tmp/etc/sites-available/cellar"
    ln -sf ../sites-available/cellar "$tmp/etc/sites-enabled/cellar"
    rm -f "$tmp/etc/sites-enabled/default"
    sed -i "s#access_log .*#access_log off;#" "$tmp/etc/nginx.conf"
    nginx -c "$tmp/etc/nginx.conf" -p "$tmp"
}
# measure LABEL URL: one line of the table
measure() {
    url=$2
    hash=$(curl -fs -D - -o /dev/null -H 'Content-Type: application/json' -H 'Prefer: wait=5' \
        --data @tests/cases/orthogonal/request.json "$url/v1/jobs" | tr -d '\r' | sed -n 's/^ETag: "\(.*\)"/\1/p')
    g=$(wrk -t2 -c"$C" -d"${D}s" --latency -s bench/wrk_get.lua "$url/v1/results/$hash")
    p=$(wrk -t2 -c"$C" -d"${D}s" --latency -s bench/wrk_post.lua "$url")
    printf "%-28s %10s %8s %8s %10s %8s %8s %s\n" "$1" \
        "$(echo "$g" | sed -n 's/^Requests\/sec: *//p')" \
        "$(echo "$g" | sed -n 's/^p50 \([0-9.]*\) ms.*/\1/p')" "$(echo "$g" | sed -n 's/.*p99 \([0-9.]*\) ms/\1/p')" \
        "$(echo "$p" | sed -n 's/^Requests\/sec: *//p')" \
        "$(echo "$p" | sed -n 's/^p50 \([0-9.]*\) ms.*/\1/p')" "$(echo "$p" | sed -n 's/.*p99 \([0-9.]*\) ms/\1/p')" \
        "$(echo "$p" | sed -n 's/^non-200 responses: \([0-9]*\).*/\1/p')"
}

echo "cellard behind nginx: SQLite beside PostgreSQL ($(date -u +%Y-%m-%dT%H:%MZ), $(nproc) CPUs, wrk -c$C ${D}s)"
printf "%-28s %10s %8s %8s %10s %8s %8s %s\n" "setup" "GET req/s" "p50 ms" "p99 ms" "POST req/s" "p50 ms" "p99 ms" "POST non-200"
start_daemon s1 "$tmp/cellar.db"; s1=$port
measure "SQLite, 1 daemon (direct)" "http://127.0.0.1:$s1"
start_nginx $s1
measure "SQLite, 1 daemon (nginx)" "http://127.0.0.1:$nport"
stop_daemons
for n in 1 2 3; do
    db="postgresql://postgres@127.0.0.1:$pgport/c$n"
    psql -q "postgresql://postgres@127.0.0.1:$pgport/postgres" -c "CREATE DATABASE c$n"
    ports=""
    for i in $(seq $n); do start_daemon "p$n-$i" "$db"; ports="$ports $port"; done
    if [ "$n" = 1 ]; then measure "PostgreSQL, 1 daemon (direct)" "http://127.0.0.1:$port"; fi
    start_nginx $ports
    measure "PostgreSQL, $n daemon(s) (nginx)" "http://127.0.0.1:$nport"
    stop_daemons
done

# SIGKILL of the daemon running a job: how long until another has done it
for lease in 30 5; do
    db="postgresql://postgres@127.0.0.1:$pgport/k$lease"
    psql -q "postgresql://postgres@127.0.0.1:$pgport/postgres" -c "CREATE DATABASE k$lease"
    port=$(freeport)
    "$B/cellard" --listen 127.0.0.1:$port --db "$db" --name victim --log-level warn --workers 1 \
        --job-threads 1 --lease-seconds $lease 2>>"$tmp/victim.log" &
    victim=$!
    for i in $(seq 100); do curl -fs "http://127.0.0.1:$port/healthz" >/dev/null 2>&1 && break; sleep 0.1; done
    "$B/cellar" gen lines 8000 0.4 $lease --options '{"fields":["stats"]}' > "$tmp/slow.json"
    id=$(curl -fs -H 'Content-Type: application/json' --data @"$tmp/slow.json" "http://127.0.0.1:$port/v1/jobs" |
        sed -n 's/.*"id":"\([0-9a-f]*\)".*/\1/p')
    sleep 1
    start_daemon rescuer "$db"; rescuer=$port
    t0=$(date +%s.%N)
    kill -KILL $victim; wait $victim 2>/dev/null || true
    while :; do
        st=$(curl -fs "http://127.0.0.1:$rescuer/v1/jobs/$id" | sed -n 's/.*"state":"\([a-z]*\)".*/\1/p')
        [ "$st" = done ] && break
        sleep 0.1
    done
    t1=$(date +%s.%N)
    echo "SIGKILL of the daemon running a job (--lease-seconds $lease): done by another $(echo "$t1 - $t0" | bc) s later"
    stop_daemons
done
