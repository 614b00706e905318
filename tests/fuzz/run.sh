#!/bin/sh
# run.sh — runs libFuzzer targets of tests/fuzz/ built by `make fuzz-build` (make fuzz and
# tests/t_fuzz.sh call it).
# Usage: tests/fuzz/run.sh [--build DIR] [--seconds N | --corpus] [--work DIR] NAME...
#   --build DIR   where the targets are (default build/fuzz); crashes go to DIR/crashes/, logs
#                 to DIR/logs/NAME.log
#   --seconds N   fuzz each target N seconds from its checked-in corpus tests/fuzz/corpus/NAME/,
#                 which is only read: new inputs go to WORK/NAME/ (default DIR/work/NAME/, kept
#                 from run to run); prints the executions (libFuzzer's final
#                 stat::number_of_executed_units)
#   --corpus      run each file of the checked-in corpus once instead (no fuzzing)
# Prints one line per target, "ok fuzz NAME: ..." or "FAIL fuzz NAME: ..." naming the input
# kept (a crash, leak, timeout or out-of-memory: DIR/crashes/NAME-KIND-SHA1), and exits 1 when
# any target failed.  Each target's flags (input size, dictionary) are here, in flags().
set -u
cd "$(dirname "$0")/../.."
B=build/fuzz
SECONDS_=600
MODE=time
WORK=""
while [ $# -gt 0 ]; do
    case $1 in
    --build) B=$2; shift 2 ;;
    --seconds) SECONDS_=$2; shift 2 ;;
    --corpus) MODE=corpus; shift ;;
    --work) WORK=$2; shift 2 ;;
    --*) echo "run.sh: unknown option $1" >&2; exit 2 ;;
    *) break ;;
    esac
done
[ $# -gt 0 ] || { echo "usage: tests/fuzz/run.sh [--build DIR] [--seconds N | --corpus] [--work DIR] NAME..." >&2; exit 2; }
[ -n "$WORK" ] || WORK=$B/work

# libFuzzer flags of a target: the largest input (the targets refuse larger ones anyway), a
# dictionary, and a timeout per input far above what an input takes (a hang is a finding)
flags() {
    case $1 in
    json) echo "-max_len=4096 -dict=tests/fuzz/json.dict" ;;
    render) echo "-max_len=16384 -dict=tests/fuzz/json.dict" ;;
    svg) echo "-max_len=16384 -dict=tests/fuzz/svg.dict" ;;
    obj | off | stl | ply) echo "-max_len=16384 -dict=tests/fuzz/mesh.dict" ;;
    3mf) echo "-max_len=16384" ;;
    http) echo "-max_len=4096 -dict=tests/fuzz/http.dict" ;;
    *) echo "" ;;
    esac
}
COMMON="-timeout=30 -rss_limit_mb=3072"

mkdir -p "$B/crashes" "$B/logs"
failed=0
tmp=""
trap 'rm -rf "$tmp"; exit 130' INT TERM
for name in "$@"; do
    bin=$B/fuzz_$name
    corpus=tests/fuzz/corpus/$name
    log=$B/logs/$name.log
    if [ ! -x "$bin" ] || [ ! -d "$corpus" ]; then
        echo "FAIL fuzz $name: no $bin or no $corpus (make fuzz-build)"
        failed=1
        continue
    fi
    t0=$(date +%s)
    # the target's temporary files (fuzz_http's database) in a directory of this run, removed
    # after it even when the target died
    tmp=$(mktemp -d "$B/tmp.XXXXXX") || exit 2
    if [ "$MODE" = corpus ]; then
        # shellcheck disable=SC2046
        TMPDIR=$tmp "$bin" $(flags "$name") $COMMON -artifact_prefix="$B/crashes/$name-" \
            "$corpus"/* >"$log" 2>&1
        rc=$?
    else
        mkdir -p "$WORK/$name"
        # shellcheck disable=SC2046
        TMPDIR=$tmp "$bin" $(flags "$name") $COMMON -max_total_time="$SECONDS_" \
            -print_final_stats=1 -artifact_prefix="$B/crashes/$name-" "$WORK/$name" "$corpus" \
            >"$log" 2>&1
        rc=$?
    fi
    rm -rf "$tmp"
    t=$(($(date +%s) - t0))
    artifact=$(sed -n 's/.*Test unit written to \(.*\)$/\1/p' "$log" | tail -n 1)
    if [ "$rc" -ne 0 ] && [ -z "$artifact" ] && [ "$MODE" = corpus ]; then
        # a corpus file failed: libFuzzer names it ("Running: FILE") but writes no copy
        input=$(sed -n 's/^Running: //p' "$log" | tail -n 1)
        if [ -f "$input" ]; then
            artifact=$B/crashes/$name-corpus-$(basename "$input")
            cp "$input" "$artifact"
        fi
    fi
    if [ "$rc" -ne 0 ] || [ -n "$artifact" ]; then
        failed=1
        # what was found: a check of the target (fuzz.h), a sanitizer's report, or libFuzzer's
        # own (deadly signal, timeout, out-of-memory, leak)
        kind=$(grep -q '^fuzz: .*check failed' "$log" && echo "a check failed")
        [ -n "$kind" ] || kind=$(sed -n 's/^SUMMARY: \([A-Za-z]*Sanitizer\): \([^ ]*\).*/\1: \2/p' "$log" | head -n 1)
        [ -n "$kind" ] || kind=$(sed -n 's/^==[0-9]*== *ERROR: libFuzzer: \(.*\)/\1/p' "$log" | head -n 1)
        echo "FAIL fuzz $name: ${kind:-exit $rc} after ${t}s; input: ${artifact:-none kept}; log: $log"
        # the messages, and the first frames of the first stack that are ours
        grep -E '^(SUMMARY|fuzz: |==[0-9]+== ?ERROR|[^ ].*runtime error)' "$log" | head -n 6 |
            sed 's/^/    /'
        grep -E '^ +#[0-9]+ ' "$log" | grep -v -e 'fuzzer::' -e '__sanitizer' -e 'libc\.so' \
            -e 'in abort ' -e 'in raise ' -e '__pthread_kill' -e ' in main ' -e '__libc_start' \
            -e ' in _start ' | head -n 8 | sed 's/^ */      /'
        continue
    fi
    if [ "$MODE" = corpus ]; then
        n=$(find "$corpus" -type f | wc -l | tr -d ' ')
        echo "ok fuzz $name: $n corpus inputs ran, no crash (${t}s)"
    else
        execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
        cov=$(grep -E '^#[0-9]+' "$log" | tail -n 1 | sed -n 's/.* cov: \([0-9]*\).*/\1/p')
        new=$(find "$WORK/$name" -type f | wc -l | tr -d ' ')
        echo "ok fuzz $name: ${execs:-?} executions in ${t}s, coverage ${cov:-?}, $new inputs in $WORK/$name"
    fi
done
exit $failed
