#!/bin/sh
# t_svg.sh — black-box tests of `cellar svg`: the flags become the request's options, stdin,
# exit statuses and messages on malformed and hostile drawings, results valid against the schema.
# Usage: CELLAR_BIN=build/cellar tests/t_svg.sh   (tests/run.sh sets CELLAR_BIN)
# Prints one line per check ("ok ..." / "FAIL ...") and a last line "N passed, N failed".
set -u
. "$(dirname "$0")/lib.sh"
BIN=${CELLAR_BIN:-build/cellar}
case $BIN in /*) ;; *) [ -e "$BIN" ] && BIN="$(pwd)/$BIN" ;; esac # before the cd below
cd "$(dirname "$0")/.."
D=tests/data/svg
PY=${PYTHON:-python3}
# a number of the result in $T/out: json EXPR (python, the result is r)
json() { $PY -c "import json,sys; r=json.load(open('$T/out')); print($1)"; }
errhas() { grep -q -- "$1" "$T/err"; }

{ [ -x "$BIN" ] && [ -d "$D" ]; } || give_up "$BIN is not built or $D is missing"

# --- help and usage
check "--help names svg and its flags" sh -c "'$BIN' --help | grep -q 'cellar svg DRAWING.svg \[--normalize\]'"
check "svg without a file exits 2" status 2 "$BIN" svg
check "svg with two files exits 2" status 2 "$BIN" svg "$D/box.svg" "$D/box.svg"
check "--normalize with run exits 2" status 2 "$BIN" run tests/cases/orthogonal/request.json --normalize
check "... and says the flag is for svg" errhas '^cellar: --normalize is for the svg command'
check "--precision 0 exits 2" status 2 "$BIN" svg "$D/box.svg" --precision 0
check "--flatten-tolerance x exits 2" status 2 "$BIN" svg "$D/box.svg" --flatten-tolerance=x
check "--precision without a value exits 2" status 2 "$BIN" svg "$D/box.svg" --precision

# --- drawings in, complexes out
check "svg shells.svg exits 0" status 0 "$BIN" svg "$D/shells.svg"
cp "$T/out" "$T/shells.out"
check "one line of output, nothing on stderr" sh -c "test \"\$(wc -l <'$T/out' | tr -d ' ')\" = 1 && test ! -s '$T/err'"
check "shells: 8 faces, 32 segments from 8 elements" test "$(json 'r["stats"]["F"], r["stats"]["svg"]["segments"], r["stats"]["svg"]["elements"]')" = "8 32 8"
check "the result is valid against result.schema.json" sh -c "$PY tests/validate.py result '$T/out' >/dev/null"
# the same bytes, timings aside (no stats)
NOSTATS='{"fields":["V","EV","FV","FE","holes","exterior"]}'
"$BIN" svg "$D/shells.svg" --options "$NOSTATS" >"$T/shells.nostats"
check "svg - reads stdin, same bytes" sh -c "'$BIN' svg - --options '$NOSTATS' <'$D/shells.svg' | cmp -s - '$T/shells.nostats'"
check "the same as cellar run of the request" sh -c \
    "$PY -c 'import json,sys; print(json.dumps({\"kind\":\"svg\",\"svg\":open(sys.argv[1]).read(),\"options\":json.loads(sys.argv[2])}))' '$D/shells.svg' '$NOSTATS' >'$T/req.json' &&
     '$BIN' run '$T/req.json' | cmp -s - '$T/shells.nostats' && $PY tests/validate.py request '$T/req.json' >/dev/null"
check "--normalize exits 0" status 0 "$BIN" svg "$D/shells.svg" --normalize
check "--normalize: V in the unit square, the longer side 1" test "$(json 'float(min(min(v) for v in r["V"])), float(max(max(v) for v in r["V"]))')" = "0.0 1.0"
check "--normalize: the transform flips y" test "$(json 'r["stats"]["svg"]["transform"][0] == -r["stats"]["svg"]["transform"][3] > 0')" = True
status 0 "$BIN" svg "$D/box.svg" --y-up --options '{"fields":["stats"]}'
check "--y-up: transform [1,0,0,-1,0,0]" test "$(json 'r["stats"]["svg"]["transform"]')" = '[1, 0, 0, -1, 0, 0]'
status 0 "$BIN" svg "$D/box.svg" --rect-diagonal
check "--rect-diagonal: one segment, no face" test "$(json 'r["stats"]["svg"]["segments"], r["stats"]["F"]')" = '1 0'
status 0 "$BIN" svg "$D/box.svg" --precision 0.5
check "--precision 0.5 is the grid step" test "$(json 'r["stats"]["precision"]')" = 0.5
status 0 "$BIN" svg "$D/box.svg" --rect-diagonal --keep-dangling
check "--keep-dangling keeps the diagonal" test "$(json 'len(r["EV"])')" = 1
"$BIN" svg "$D/curved.svg" --flatten-tolerance 10 >"$T/coarse" 2>"$T/err"
"$BIN" svg "$D/curved.svg" --flatten-tolerance=0.01 >"$T/fine" 2>"$T/err"
check "--flatten-tolerance: finer tolerance, more segments" $PY -c "
import json
c = json.load(open('$T/coarse'))['stats']['svg']['segments']
f = json.load(open('$T/fine'))['stats']['svg']['segments']
assert 0 < c < f, (c, f)"
status 0 "$BIN" svg "$D/box.svg" --options '{"fields":["stats"],"operators":true}'
check "--options gives the other options" test "$(json 'sorted(r)')" = "['dim', 'operators', 'stats']"
check "--options that is not an object exits 2" status 2 "$BIN" svg "$D/box.svg" --options '[1]'
check "an unknown option in --options exits 1" status 1 "$BIN" svg "$D/box.svg" --options '{"colour":1}'
check "... and is named" errhas '^cellar: options.colour: unknown option'
printf '<svg xmlns="http://www.w3.org/2000/svg"><line x1="NaN" x2="1"/><rect width="2" height="1"/></svg>' >"$T/warn.svg"
check "an unreadable element is a warning, not an error" status 0 "$BIN" svg "$T/warn.svg"
check "... counted and described" test "$(json 'r["stats"]["svg"]["skipped"], r["stats"]["svg"]["warnings"][0]')" = \
    '1 line 1: <line>: x1="NaN" is not a finite number or length; skipped'

# --- malformed and hostile drawings: exit 1, the message on stderr, nothing on stdout
printf '<svg xmlns="http://www.w3.org/2000/svg">\n<g>\n  <line/>\n</svg>\n' >"$T/unclosed.svg"
check "unclosed tag exits 1" status 1 "$BIN" svg "$T/unclosed.svg"
check "... with line and column" errhas '^cellar: svg: line 4, column 7: Opening and ending tag mismatch'
check "... and nothing on stdout" test ! -s "$T/out"
check "malformed on stdin exits 1" status 1 sh -c "printf '<svg><g></svg>' | '$BIN' svg -"
check "empty drawing exits 1" status 1 sh -c "'$BIN' svg - </dev/null"
check "... Document is empty" errhas 'svg: line 1, column 1: Document is empty'
printf '<html/>' >"$T/html.svg"
check "non-SVG root exits 1" status 1 "$BIN" svg "$T/html.svg"
check "... named" errhas 'the root element is <html>, not <svg>'
{
    echo '<?xml version="1.0"?><!DOCTYPE svg [<!ENTITY a "aaaaaaaaaa">'
    prev=a
    for i in 1 2 3 4 5 6 7 8 9; do
        printf '<!ENTITY a%s "' "$i"
        for j in 1 2 3 4 5 6 7 8 9 10; do printf '&%s;' "$prev"; done
        printf '">\n'
        prev=a$i
    done
    echo ']><svg xmlns="http://www.w3.org/2000/svg"><path d="&a9;"/></svg>'
} >"$T/lol.svg"
check "billion laughs exits 1" status 1 "$BIN" svg "$T/lol.svg"
check "... refused as an entity problem" errhas 'entity'
$PY -c "print('<svg xmlns=\"http://www.w3.org/2000/svg\">' + '<g>' * 100000 + '</g>' * 100000 + '</svg>')" >"$T/deep.svg"
check "100000 nested groups exit 1" status 1 "$BIN" svg "$T/deep.svg"
check "... beyond max_depth" errhas 'nested deeper than 200 (limit max_depth)'
printf '<svg>\377\376</svg>' >"$T/latin1.svg"
check "a drawing that is not UTF-8 exits 1" status 1 "$BIN" svg "$T/latin1.svg"
check "... and says so" errhas 'not UTF-8'
check "a missing file exits 1" status 1 "$BIN" svg "$T/no-such.svg"

echo "$P passed, $F failed"
[ "$F" -eq 0 ]
