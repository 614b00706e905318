# shellcheck shell=sh
# bench/lib.sh — what the benchmark drivers share; source it after setting:
#   BENCH_NAME  the prefix of their messages ("benchbool"), LIMIT (seconds a run may take),
#   REPEAT (how many times a run under 2 s is repeated), TIME (GNU /usr/bin/time).

# need PROG...: exits 1 naming the first PROG that is not an executable file.
need() {
    for p in "$@"; do
        if [ ! -x "$p" ]; then
            echo "$BENCH_NAME: $p is missing (make bench builds it)" >&2
            exit 1
        fi
    done
}

# timed NAME OUT CMD...: runs CMD with stdout to OUT under /usr/bin/time and the time limit;
# sets T_S (wall s, to the millisecond) and T_MIB (peak RSS, MiB), or T_S=failed / timeout and
# T_MIB=-.  A run under 2 s is repeated (REPEAT times in all) and the
# fastest kept: the machine is noisy, and the best of a few runs is the steadiest figure.
timed() {
    name=$1
    out=$2
    shift 2
    T_S='' T_MIB=-
    k=0
    while [ "$k" -lt "$REPEAT" ]; do
        k=$((k + 1))
        t0=$(date +%s%N)
        "$TIME" -f '%M' -o "$out.time" timeout "$LIMIT" "$@" >"$out" 2>"$out.err"
        rc=$?
        t1=$(date +%s%N)
        if [ "$rc" -eq 124 ]; then
            echo "$BENCH_NAME: $name timed out after $LIMIT s" >&2
            T_S=timeout T_MIB=-
            return 1
        fi
        if [ "$rc" -ne 0 ]; then
            echo "$BENCH_NAME: $name failed (exit $rc):" >&2
            head -c 600 "$out.err" >&2
            echo >&2
            T_S=failed T_MIB=-
            return 1
        fi
        s=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.3f", (b - a) / 1e9 }')
        if [ -z "$T_S" ] || awk -v a="$s" -v b="$T_S" 'BEGIN { exit !(a < b) }'; then
            T_S=$s
            T_MIB=$(tail -n 1 "$out.time" | awk '{ printf "%.1f", $1 / 1024 }')
        fi
        awk -v a="$s" 'BEGIN { exit !(a < 2) }' || break
    done
}

# num KEY FILE: the first number stored under "KEY" in FILE (empty if none).
num() {
    grep -o "\"$1\": *-\{0,1\}[0-9][0-9.eE+-]*" "$2" | head -n 1 | sed 's/.*: *//'
}

# speed C O: C / O to one decimal, or "-".
speed() {
    awk -v c="$1" -v o="$2" 'BEGIN {
        if (c !~ /^[0-9.]+$/ || o !~ /^[0-9.]+$/ || c + 0 <= 0 || o + 0 <= 0) print "-"
        else printf "%.2f", c / o }'
}

