#!/bin/sh
# Runs every test program of a build directory and every shell test (tests/t_*.sh), adds up
# their "N passed, N failed[, N skipped]" lines and prints the total as the last line (and
# each test's wall time after its output, to keep the suite's time in view). Every failing
# check (its "FAIL" line and the lines before it, which say why) and every failing program
# are repeated just above the total, so that the end of a long log names what failed.
# Every test runs from the repository's top (its data is tests/data).
# Usage: tests/run.sh BUILD_DIR [NAME ...]   (BUILD_DIR relative to the repository's top, or
# absolute; NAMEs, e.g. test_exact3d t_real3d, run only those: make stress)
set -u
cd "$(dirname "$0")/.."
B=${1:-build}
[ $# -gt 0 ] && shift
ONLY=" $* "
export CELLAR_BIN="$B/cellar" CELLAR_BUILD="$B"
P=0; F=0; S=0
log=$(mktemp)
fails=$(mktemp)
for t in "$B"/tests/test_* tests/t_*.sh; do
    [ -x "$t" ] || continue
    n=$(basename "$t" .sh)
    [ "$ONLY" = "  " ] || case $ONLY in *" $n "*) ;; *) continue ;; esac
    echo "== $t"
    t0=$(date +%s)
    "$t" >"$log" 2>&1
    rc=$?
    cat "$log"
    echo "   ($n: $(($(date +%s) - t0)) s)"
    grep -B 4 -E '^FAIL' "$log" | head -n 40 | sed "s|^|$n: |" >>"$fails"
    last=$(grep -E '^[0-9]+ passed, [0-9]+ failed' "$log" | tail -n 1)
    if [ -z "$last" ]; then
        echo "FAIL $t: exited $rc without a summary line" | tee -a "$fails"
        tail -n 5 "$log" | sed "s|^|$n: |" >>"$fails"
        F=$((F + 1))
        continue
    fi
    p=${last%% passed*}; f=${last#*, }; f=${f%% failed*}
    P=$((P + p)); F=$((F + f))
    case $last in *skipped*) s=${last##*, }; S=$((S + ${s%% skipped*})) ;; esac
    if [ "$rc" -ne 0 ] && [ "$f" -eq 0 ]; then
        echo "FAIL $t: exited $rc" | tee -a "$fails"
        F=$((F + 1))
    fi
done
if [ -s "$fails" ]; then
    echo "== what failed"
    cat "$fails"
fi
rm -f "$log" "$fails"
echo "$P passed, $F failed, $S skipped"
[ "$F" -eq 0 ]
