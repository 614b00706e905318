#!/bin/sh
# t_fuzz.sh — the libFuzzer targets of tests/fuzz/ (json, svg, obj, off, stl, ply, 3mf, render,
# http): builds them if needed (make fuzz-build: clang, ASan + UBSan, into build/fuzz/), then
#   - runs every file of each checked-in corpus (tests/fuzz/corpus/NAME/) once: no crash;
#   - fuzzes each target CELLAR_FUZZ_SECONDS seconds (default 30) from that corpus (new inputs
#     go to a temporary directory: the corpus is only read).
# Under make check (CELLAR_SANITIZED=1) only the corpus runs, no timed run.  One check per
# target and per run; a finding names the input kept in build/fuzz/crashes/ and the log in
# build/fuzz/logs/.  clang and libclang-rt-14-dev come from `make deps`: a missing one is a
# failure; the test is skipped only when CELLAR_SKIP_FUZZ=1 asks for it.
# Usage: tests/t_fuzz.sh   (tests/run.sh runs it from the repository's top)
set -u
cd "$(dirname "$0")/.."
if [ "${CELLAR_SKIP_FUZZ:-0}" = 1 ]; then
    echo "skip fuzz: CELLAR_SKIP_FUZZ=1"
    echo "0 passed, 0 failed, 1 skipped"
    exit 0
fi
. tests/lib.sh
FB=build/fuzz
SECS=${CELLAR_FUZZ_SECONDS:-30}
case $SECS in '' | *[!0-9]*) give_up "fuzz: CELLAR_FUZZ_SECONDS=$SECS is not a number of seconds" ;; esac

command -v clang >/dev/null 2>&1 ||
    give_up "fuzz: clang is missing (make deps installs it; CELLAR_SKIP_FUZZ=1 skips)"
# a make of our own: none of the caller's make flags or variables (BUILD, SAN, ...)
if ! env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL make --no-print-directory -j2 fuzz-build \
    >"$T/build.log" 2>&1; then
    tail -n 30 "$T/build.log"
    give_up "fuzz: make fuzz-build failed (clang and libclang-rt-14-dev: make deps)"
fi
targets=$(for f in tests/fuzz/fuzz_*.c; do n=${f#tests/fuzz/fuzz_}; echo "${n%.c}"; done)

# tests/fuzz/run.sh prints "ok ..." / "FAIL ..." per target and detail lines: count its verdicts
tally() {
    while IFS= read -r line; do
        case $line in
        "ok "*) pass "${line#ok }" ;;
        "FAIL "*) fail "${line#FAIL }" ;;
        *) echo "$line" ;;
        esac
    done <"$1"
}

for t in $targets; do
    tests/fuzz/run.sh --build "$FB" --corpus "$t" >"$T/run" 2>&1
    tally "$T/run"
done
if [ "${CELLAR_SANITIZED:-0}" = 1 ]; then
    echo "fuzz: CELLAR_SANITIZED=1: the corpus runs only, no timed runs"
else
    for t in $targets; do
        tests/fuzz/run.sh --build "$FB" --seconds "$SECS" --work "$T/work" "$t" >"$T/run" 2>&1
        tally "$T/run"
    done
fi
finish
