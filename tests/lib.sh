# lib.sh — what the shell tests (tests/t_*.sh) share; source it right after `set -u`:
#   T         a temporary directory, removed at exit
#   P, F      the counts of passed and failed checks
#   pass NAME / fail NAME       record a check ("ok NAME" / "FAIL NAME")
#   check NAME CMD...           runs CMD; passes when it succeeds
#   status WANT CMD...          runs CMD (stdout to $T/out, stderr to $T/err); true when it
#                               exits WANT, else prints what it got
#   finish                      prints "N passed, N failed" and exits non-zero on a failure
#   give_up WHY                 a test that cannot run: one failure, WHY, and exit
#   need_python IMPORTS PKGS    sets PY to a python3 that runs "import IMPORTS": $PYTHON or
#                               the one on PATH, else Debian's /usr/bin/python3; gives up
#                               naming the Debian packages PKGS when none does
#   tally_file FILE             counts a checker's "ok ..." / "FAIL ..." lines in FILE as checks
#                               of this test (its summary line dropped, other lines shown)
#   run_py PY SCRIPT ARGS...    runs a Python test that prints its checks and a summary line
#                               last (tests/tally.py), passes its lines on and exits with it;
#                               a crash leaves no summary: one failure, with its stderr's end
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT INT TERM
P=0
F=0

pass() { P=$((P + 1)); echo "ok $1"; }
fail() { F=$((F + 1)); echo "FAIL $1"; }
check() {
    name=$1
    shift
    if "$@"; then pass "$name"; else fail "$name"; fi
}
status() {
    want=$1
    shift
    "$@" >"$T/out" 2>"$T/err"
    got=$?
    [ "$got" -eq "$want" ] || { echo "  exit $got, want $want: $*"; head -c 300 "$T/err"; return 1; }
}
finish() {
    echo "$P passed, $F failed"
    [ "$F" -eq 0 ]
    exit $?
}
give_up() {
    echo "FAIL $1"
    echo "0 passed, 1 failed"
    exit 1
}
need_python() {
    PY=${PYTHON:-python3}
    $PY -c "import $1" 2>/dev/null || PY=/usr/bin/python3
    $PY -c "import $1" 2>/dev/null ||
        give_up "python3 that imports $1 is needed: apt-get install $2 (make deps)"
}
tally_file() {
    while IFS= read -r line; do
        case $line in
        "ok "*) pass "${line#ok }" ;;
        "FAIL "*) fail "${line#FAIL }" ;;
        [0-9]*" passed, "*" failed"*) ;;
        *) echo "  $line" ;;
        esac
    done <"$1"
}
run_py() {
    py=$1
    shift
    "$py" "$@" >"$T/py.out" 2>"$T/py.err"
    rc=$?
    grep -v -E '^[0-9]+ passed, [0-9]+ failed' "$T/py.out"
    last=$(grep -E '^[0-9]+ passed, [0-9]+ failed' "$T/py.out" | tail -n 1)
    if [ -z "$last" ]; then
        tail -n 5 "$T/py.err"
        give_up "$1 exited $rc without a summary line"
    fi
    echo "$last"
    [ "$rc" -eq 0 ]
    exit $?
}
