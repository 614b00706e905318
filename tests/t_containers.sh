#!/bin/sh
# t_containers.sh — the container deployment, built and run for real with podman (Debian's,
# rootful; scripts/podman-base.sh makes the base images out of Debian's archive):
#   1. the image from the repository's Dockerfile: cold and cached build times, size, its OCI
#      labels and HEALTHCHECK; a container of it: /healthz and /readyz, the README's job, the
#      image's own healthcheck, a non-root user, the database on the volume, CELLAR_* settings,
#      a read-only root filesystem (the volume and a tmpfs), and SIGTERM while a job runs (the
#      job resumes in a new container on the same volume: nothing lost);
#   2. deploy/compose.yaml (PostgreSQL, three cellard, nginx with deploy/nginx.conf), run with
#      podman-compose: 100 distinct jobs through nginx, each run exactly once and equal to
#      `cellar run`; a job through nginx's sub-path /cellar/, its links under it; one cellard
#      killed while it runs jobs (the others finish them once the lease runs out); the stack
#      stopped and started again on its volumes (results and finished jobs still there).
# Prints the figures (build times, size, time to healthy, stack up time).  Under make check
# (CELLAR_SANITIZED=1) only part 1's container checks run, on the image make test built.
# A missing podman is a failure; skipped only when CELLAR_SKIP_CONTAINERS=1 asks for it.
set -u
cd "$(dirname "$0")/.."
if [ "${CELLAR_SKIP_CONTAINERS:-0}" = 1 ]; then
    echo "skip containers: CELLAR_SKIP_CONTAINERS=1"
    echo "0 passed, 0 failed, 1 skipped"
    exit 0
fi
. tests/lib.sh
B=${CELLAR_BUILD:-build}
for c in podman podman-compose debootstrap runc curl; do
    command -v $c >/dev/null 2>&1 ||
        give_up "containers: $c is missing (make deps installs podman, podman-compose, runc, debootstrap; CELLAR_SKIP_CONTAINERS=1 skips)"
done
[ "$(id -u)" = 0 ] || give_up "containers: rootful podman needs root (CELLAR_SKIP_CONTAINERS=1 skips)"
export CONTAINERS_CONF="$(pwd)/build/containers/containers.conf"
scripts/podman-base.sh "$CONTAINERS_CONF" || give_up "containers: no base image (scripts/podman-base.sh)"
IMG=localhost/cellar:test
VERSION=$(sed -n 's/^#define API_VERSION "\(.*\)"/\1/p' api/api.h)
N=cellar-test-$$
now() { date +%s.%N; }
since() { echo "$(now) - $1" | bc | sed 's/^\./0./'; }
names=""
cleanup() {
    for c in $names; do podman rm -f -t 0 "$c" >/dev/null 2>&1; done
    podman volume rm -f "$N-data" "$N-ro" >/dev/null 2>&1
    [ -n "${compose_up:-}" ] && podman-compose -p "$N" -f deploy/compose.yaml down -v >/dev/null 2>&1
    podman network rm -f "${N}_default" >/dev/null 2>&1
    # the layers of replaced builds: unnamed, never used again, gigabytes after some runs
    podman image prune -f >/dev/null 2>&1
    rm -rf "$T"
}
trap cleanup EXIT INT TERM

# waits for a container's port 8080 to answer /healthz; its address in $addr
healthy() {
    addr=$(podman port "$1" 8080 2>/dev/null | head -n 1)
    for i in $(seq 200); do
        [ -n "$addr" ] && curl -fs "http://$addr/healthz" >/dev/null 2>&1 && return 0
        sleep 0.05
        addr=$(podman port "$1" 8080 2>/dev/null | head -n 1)
    done
    podman logs "$1" 2>&1 | tail -n 5
    return 1
}
run_ctr() { # NAME VOLUME [podman run flags...]: a container of the image, detached
    c=$1 v=$2
    shift 2
    names="$names $c"
    podman run -d --name "$c" --network slirp4netns:port_handler=slirp4netns \
        -p 127.0.0.1::8080 -v "$v:/data" -e CELLAR_MAX_PER_IP=0 "$@" "$IMG" >/dev/null 2>"$T/run.err"
}
post() { # ADDR FILE [PREFER]: POST a request; the body to $T/out, the status printed
    curl -s -o "$T/out" -w '%{http_code}' -H 'Content-Type: application/json' \
        ${3:+-H "Prefer: $3"} --data-binary @"$2" "http://$1/v1/jobs"
}
same_as_cli() { # FILE: $T/out equals `cellar run FILE` (stats' timings aside)
    "$B/cellar" run "$1" >"$T/cli" 2>/dev/null && python3 - "$T/out" "$T/cli" <<'EOF'
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
for x in (a, b):
    x.get("stats", {}).pop("ms", None)
sys.exit(0 if a == b else 1)
EOF
}

# ---- 1. the image ----
if [ "${CELLAR_SANITIZED:-0}" != 1 ]; then
    source=$(git remote get-url origin 2>/dev/null || echo "file://$(pwd)")
    # cold: this image and the cache entries only it kept are removed first (a --no-cache
    # build would leave no entries that the next build takes)
    podman rmi -f "$IMG" localhost/cellar:latest >/dev/null 2>&1
    podman image prune -f >/dev/null 2>&1
    # npm through a proxy that re-signs TLS (as on our machines): its CA as the build secret
    ca=${CELLAR_BUILD_CA:-${NODE_EXTRA_CA_CERTS:-}}
    secret=""
    [ -n "$ca" ] && [ -s "$ca" ] && secret="--secret id=ca,src=$ca"
    t0=$(now)
    # shellcheck disable=SC2086
    if podman build --format docker --network=host --pull=never $secret \
        --build-arg VERSION="$VERSION" --build-arg SOURCE="$source" -t "$IMG" . >"$T/build.log" 2>&1; then
        cold=$(since "$t0")
        n=$(grep -c '^--> Using cache' "$T/build.log")
        pass "the image builds from the Dockerfile (${cold} s; $n steps from an older build's cache)"
    else
        tail -n 30 "$T/build.log"
        give_up "containers: podman build failed"
    fi
    id1=$(podman image inspect "$IMG" --format '{{.Id}}')
    t0=$(now)
    # shellcheck disable=SC2086
    podman build --format docker --network=host --pull=never $secret --build-arg VERSION="$VERSION" \
        --build-arg SOURCE="$source" -t "$IMG" . >"$T/build2.log" 2>&1
    cached=$(since "$t0")
    steps=$(grep -c 'STEP [0-9]*/[0-9]*:' "$T/build2.log")
    froms=$(grep -c 'STEP [0-9]*/[0-9]*: FROM' "$T/build2.log")
    hits=$(grep -c '^--> Using cache' "$T/build2.log")
    id2=$(podman image inspect "$IMG" --format '{{.Id}}')
    same=""
    [ "$id1" = "$id2" ] && same=", the same image"
    check "a second build takes every step from the cache ($hits of $((steps - froms)), ${cached} s$same)" \
        [ "$steps" -gt 2 -a "$hits" -eq $((steps - froms)) ]
else
    podman image exists "$IMG" || give_up "containers: no image $IMG (make test builds it)"
fi
size=$(podman image inspect "$IMG" --format '{{.Size}}')
check "its OCI labels say version $VERSION, source and licence" sh -c \
    "podman image inspect '$IMG' --format '{{index .Labels \"org.opencontainers.image.version\"}} {{index .Labels \"org.opencontainers.image.licenses\"}} {{index .Labels \"org.opencontainers.image.source\"}}' | grep -q '^$VERSION MIT .'"
check "it has a HEALTHCHECK (cellard --healthcheck)" sh -c \
    "podman image inspect '$IMG' --format '{{.Config.Healthcheck.Test}}' | grep -q 'cellard --healthcheck'"
check "its runtime holds no compiler and no curl" sh -c \
    "! podman run --rm --entrypoint sh '$IMG' -c 'command -v gcc || command -v curl' >/dev/null 2>&1"

podman volume create "$N-data" >/dev/null
t0=$(now)
run_ctr "$N-a" "$N-data" || { cat "$T/run.err"; give_up "containers: podman run failed"; }
if healthy "$N-a"; then
    up=$(since "$t0")
    pass "the container answers /healthz ($up s after podman run)"
else
    give_up "containers: the container never answered /healthz"
fi
check "/readyz" curl -fs "http://$addr/readyz" -o /dev/null
check "the image's own HEALTHCHECK passes" podman healthcheck run "$N-a"
s=$(post "$addr" examples/orthogonal.json wait=10)
check "the README's job: the result of cellar run" [ "$s" = 200 ]
check "  ... equal to the CLI's" same_as_cli examples/orthogonal.json
check "it runs as a user that is not root (uid 999)" sh -c "[ \"\$(podman exec $N-a id -u)\" = 999 ]"
check "the database is on the volume" podman exec "$N-a" test -s /data/cellar.db
podman stop -t 60 "$N-a" >/dev/null 2>&1
check "SIGTERM (podman stop) exits 0" sh -c "[ \"\$(podman inspect $N-a --format '{{.State.ExitCode}}')\" = 0 ]"

# CELLAR_* settings reach the daemon: a body larger than CELLAR_MAX_BODY is refused
run_ctr "$N-b" "$N-data" -e CELLAR_MAX_BODY=2048 -e CELLAR_MAX_INFLIGHT_BYTES=65536 &&
    healthy "$N-b" && {
    python3 -c 'import json; print(json.dumps({"kind": "lines", "lines": [[[i, 0], [i, 1]] for i in range(400)]}))' >"$T/big.json"
    s=$(post "$addr" "$T/big.json")
    check "CELLAR_MAX_BODY=2048: a larger body gets 413" [ "$s" = 413 ]
    s=$(post "$addr" examples/orthogonal.json)
    check "  ... and the results of the volume are still served" [ "$s" = 200 ]
    podman stop -t 30 "$N-b" >/dev/null 2>&1
} || fail "a container with CELLAR_MAX_BODY"

# a read-only root filesystem: the volume and a tmpfs are all it writes
podman volume create "$N-ro" >/dev/null
run_ctr "$N-c" "$N-ro" --read-only --tmpfs /tmp && healthy "$N-c" && {
    s=$(post "$addr" examples/polygons.json wait=10)
    check "with --read-only: a job runs and its result is stored" [ "$s" = 200 ]
    check "  ... equal to the CLI's" same_as_cli examples/polygons.json
    podman stop -t 30 "$N-c" >/dev/null 2>&1
} || fail "a container with --read-only"

# SIGTERM while a job runs: with a drain of 1 s the job goes back to the queue, and a new
# container on the same volume runs it
"$B/cellar" gen lines 9000 0.4 11 --options '{"fields":["stats"]}' >"$T/slow.json"
run_ctr "$N-d" "$N-data" -e CELLAR_DRAIN_TIMEOUT=1 -e CELLAR_JOB_THREADS=1 && healthy "$N-d" && {
    post "$addr" "$T/slow.json" >/dev/null
    id=$(sed -n 's/.*"id":"\([0-9a-f]*\)".*/\1/p' "$T/out")
    sleep 1
    st=$(curl -fs "http://$addr/v1/jobs/$id" | sed -n 's/.*"state":"\([a-z]*\)".*/\1/p')
    podman stop -t 30 "$N-d" >/dev/null 2>&1
    check "SIGTERM while a job runs (state: $st) exits 0" sh -c \
        "[ \"\$(podman inspect $N-d --format '{{.State.ExitCode}}')\" = 0 ]"
    run_ctr "$N-e" "$N-data" && healthy "$N-e"
    done_=""
    for i in $(seq 600); do
        done_=$(curl -fs "http://$addr/v1/jobs/$id" | sed -n 's/.*"state":"\([a-z]*\)".*/\1/p')
        [ "$done_" = done ] && break
        sleep 0.1
    done
    check "  ... the job is done in a new container on the same volume" sh -c "[ '$done_' = done ]"
    podman stop -t 30 "$N-e" >/dev/null 2>&1
} || fail "a container stopped while a job runs"

if [ "${CELLAR_SANITIZED:-0}" = 1 ]; then
    echo "containers: CELLAR_SANITIZED=1: the compose stack is left to make test"
    finish
fi

# ---- 2. the compose stack ----
export CELLAR_HTTP_PORT=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
export CELLAR_LEASE_SECONDS=5
podman tag "$IMG" localhost/cellar:latest # the stack's cellard image: built above (its cache)
t0=$(now)
# (the cellard services' image is the one built and tagged above: only postgres and nginx here)
if ! podman-compose -p "$N" -f deploy/compose.yaml build postgres nginx >"$T/cbuild.log" 2>&1; then
    tail -n 30 "$T/cbuild.log"
    give_up "containers: podman-compose build failed"
fi
cbuild=$(since "$t0")
t0=$(now)
compose_up=1
podman-compose -p "$N" -f deploy/compose.yaml up -d >"$T/cup.log" 2>&1
url=http://127.0.0.1:$CELLAR_HTTP_PORT
ready=""
for i in $(seq 600); do
    if curl -fs "$url/readyz" >/dev/null 2>&1; then ready=1; break; fi
    sleep 0.1
done
stackup=$(since "$t0")
check "the compose stack answers through nginx (up in $stackup s)" sh -c "[ -n '$ready' ]"
[ -n "$ready" ] || { tail -n 20 "$T/cup.log"; podman-compose -p "$N" -f deploy/compose.yaml logs 2>&1 | tail -n 40; finish; }
psql_() { podman exec "${N}_postgres_1" psql -U cellar -d cellar -Atc "$1"; }

# 100 distinct jobs through nginx, each run exactly once, each equal to the CLI's
ids=""
bad=0
for i in $(seq 100); do
    printf '{"kind":"lines","lines":[[[0,0],[%d,0]],[[%d,0],[%d,%d]],[[%d,%d],[0,0]]],"options":{"fields":["V","EV","FV","FE"]}}' \
        $i $i $i $i $i $i >"$T/j$i.json"
    s=$(post 127.0.0.1:$CELLAR_HTTP_PORT "$T/j$i.json")
    case $s in 200 | 202) ids="$ids $(sed -n 's/.*"id":"\([0-9a-f]*\)".*/\1/p' "$T/out")" ;; *) bad=$((bad + 1)) ;; esac
done
notdone=0
for id in $ids; do
    for k in $(seq 300); do
        curl -fs "$url/v1/jobs/$id" | grep -q '"state":"done"' && break
        sleep 0.1
    done
    curl -fs "$url/v1/jobs/$id" | grep -q '"state":"done"' || notdone=$((notdone + 1))
done
same=0
for i in $(seq 100); do
    post 127.0.0.1:$CELLAR_HTTP_PORT "$T/j$i.json" wait=5 >/dev/null && same_as_cli "$T/j$i.json" && same=$((same + 1))
done
once=$(psql_ "SELECT count(*) FROM jobs WHERE state = 2 AND attempts = 1")
total=$(psql_ "SELECT count(*) FROM jobs")
daemons=$(psql_ "SELECT count(DISTINCT owner) FROM jobs")
echo "  (100 jobs through nginx: $total in the database, $once run exactly once, by $daemons daemons)"
check "100 jobs through nginx: each run exactly once, equal to cellar run" sh -c \
    "[ $bad = 0 ] && [ $notdone = 0 ] && [ $same = 100 ] && [ '$once' = 100 ] && [ '$total' = 100 ]"
check "  ... shared by the three daemons" sh -c "[ '$daemons' = 3 ]"

# the service on a sub-path through nginx (deploy/nginx.conf's /cellar/, X-Forwarded-Prefix):
# the page, and a job whose Location and result link are under /cellar/ and lead, through
# nginx, to its result
check "GET /cellar/ through nginx: the page" sh -c "curl -fs '$url/cellar/' | grep -q '<title>cellar'"
check "  ... GET /cellar redirects to it (relative: the published port kept)" sh -c \
    "[ \"\$(curl -s -o /dev/null -w '%{http_code} %{redirect_url}' '$url/cellar')\" = '301 $url/cellar/' ]"
"$B/cellar" gen lines 1500 0.4 77 --options '{"fields":["V","EV","FV","FE"]}' >"$T/p.json"
s=$(curl -s -o "$T/out" -D "$T/hdr" -w '%{http_code}' -H 'Content-Type: application/json' \
    --data-binary @"$T/p.json" "$url/cellar/v1/jobs")
loc=$(sed -n 's/^[Ll]ocation: *\([^[:space:]]*\).*/\1/p' "$T/hdr")
check "a job posted to /cellar/v1/jobs through nginx: 202, its Location under /cellar/ ($loc)" \
    sh -c "[ '$s' = 202 ] && case '$loc' in /cellar/v1/jobs/*) true ;; *) false ;; esac"
res=""
for k in $(seq 300); do
    [ -n "$loc" ] || break
    res=$(curl -fs "$url$loc" | sed -n 's/.*"result":"\([^"]*\)".*/\1/p')
    [ -n "$res" ] && break
    sleep 0.1
done
check "  ... its Location followed through nginx: done, its result link under /cellar/ ($res)" \
    sh -c "case '$res' in /cellar/v1/results/*) true ;; *) false ;; esac"
rm -f "$T/out"
[ -n "$res" ] && curl -fs -o "$T/out" "$url$res"
check "  ... the result link followed through nginx: the result of cellar run" same_as_cli "$T/p.json"

# one cellard killed while it runs jobs: the others finish them once the lease runs out
for k in 1 2 3 4; do
    "$B/cellar" gen lines 7000 0.4 $((20 + k)) --options '{"fields":["stats"]}' >"$T/s$k.json"
    post 127.0.0.1:$CELLAR_HTTP_PORT "$T/s$k.json" >/dev/null
    eval "sid$k=\$(sed -n 's/.*\"id\":\"\\([0-9a-f]*\\)\".*/\\1/p' '$T/out')"
done
victim=""
for i in $(seq 100); do
    victim=$(psql_ "SELECT owner FROM jobs WHERE state = 1 LIMIT 1")
    [ -n "$victim" ] && break
    sleep 0.1
done
running=$(psql_ "SELECT count(*) FROM jobs WHERE state = 1 AND owner = '$victim'")
t0=$(now)
podman kill "${N}_${victim}_1" >/dev/null 2>&1
all=1
for k in 1 2 3 4; do
    eval "id=\$sid$k"
    for i in $(seq 600); do
        curl -fs "$url/v1/jobs/$id" | grep -q '"state":"done"' && break
        sleep 0.1
    done
    curl -fs "$url/v1/jobs/$id" | grep -q '"state":"done"' || all=0
done
killed=$(since "$t0")
again=$(psql_ "SELECT count(*) FROM jobs WHERE attempts = 2 AND state = 2")
echo "  (podman kill of $victim running $running job(s): all done $killed s later, $again started twice, lease 5 s)"
check "a cellard killed while it runs jobs: the others finish them" sh -c \
    "[ -n '$victim' ] && [ $all = 1 ] && [ '$again' -ge 1 ]"

# the stack stopped and started again on its volumes
first=$(echo $ids | cut -d' ' -f1)
podman-compose -p "$N" -f deploy/compose.yaml down >/dev/null 2>&1
podman-compose -p "$N" -f deploy/compose.yaml up -d >/dev/null 2>&1
ready=""
for i in $(seq 600); do
    if curl -fs "$url/readyz" >/dev/null 2>&1; then ready=1; break; fi
    sleep 0.1
done
check "after down and up: a finished job is still there" sh -c \
    "[ -n '$ready' ] && curl -fs '$url/v1/jobs/$first' | grep -q '\"state\":\"done\"'"
s=$(post 127.0.0.1:$CELLAR_HTTP_PORT "$T/j1.json")
check "  ... and a result is served from the cache" sh -c "[ '$s' = 200 ] && grep -q '\"dim\"' '$T/out'"

echo "  (image: cold build ${cold:-?} s, cached build ${cached:-?} s, $((size / 1000000)) MB; healthy ${up:-?} s after podman run;"
echo "   compose: images built in $cbuild s, stack up in $stackup s)"
finish
