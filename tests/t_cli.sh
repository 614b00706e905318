#!/bin/sh
# t_cli.sh — black-box tests of the command-line tool: exit statuses, stdin, gen, --help.
# Usage: CELLAR_BIN=build/cellar tests/t_cli.sh   (tests/run.sh sets CELLAR_BIN)
# Prints one line per check ("ok ..." / "FAIL ...") and a last line "N passed, N failed".
set -u
. "$(dirname "$0")/lib.sh"
BIN=${CELLAR_BIN:-build/cellar}
# a number from the "stats" object of a result file: stat FILE KEY
stat() { sed -n "s/.*\"stats\":{.*\"$2\":\([0-9][0-9]*\)[,}].*/\1/p" "$1"; }
has() { grep -q -- "$2" "$1"; }
lines_of() { wc -l <"$1" | tr -d ' '; }

[ -x "$BIN" ] || give_up "$BIN is not built"

SQUARE='[[[0,0],[1,0]],[[1,0],[1,1]],[[1,1],[0,1]],[[0,1],[0,0]]]'
printf '{"kind":"lines","lines":%s,"options":{"fields":["V","EV","FV","FE","holes","exterior"]}}\n' \
    "$SQUARE" >"$T/square.json"

# --help, --version, usage errors
check "--help exits 0 with usage on stdout" status 0 "$BIN" --help
check "--help text names run and gen" sh -c "grep -q 'usage: cellar' '$T/out' && grep -q 'gen lines N SCALING SEED' '$T/out'"
check "--help after a command still helps" status 0 "$BIN" run --help
check "--version exits 0" status 0 "$BIN" --version
check "--version prints the version" grep -q '^cellar [0-9]' "$T/out"
check "no command exits 2" status 2 "$BIN"
check "usage error explained on stderr" grep -q '^cellar: no command' "$T/err"
check "unknown command exits 2" status 2 "$BIN" frobnicate
check "unknown option exits 2" status 2 "$BIN" --frob run "$T/square.json"
check "run without a file exits 2" status 2 "$BIN" run
check "run with two files exits 2" status 2 "$BIN" run "$T/square.json" "$T/square.json"
check "--threads without a value exits 2" status 2 "$BIN" run "$T/square.json" --threads
check "--threads not a number exits 2" status 2 "$BIN" --threads many run "$T/square.json"
check "--options with run exits 2" status 2 "$BIN" run "$T/square.json" --options '{}'

# run: success, stdin, failures
check "run FILE exits 0" status 0 "$BIN" run "$T/square.json"
cp "$T/out" "$T/square.out"
check "run prints one line" test "$(lines_of "$T/square.out")" = 1
check "run prints the complex" grep -q '^{"dim":2,"V":\[\[0,0\],\[0,1\],\[1,0\],\[1,1\]\],"EV":\[\[0,1\],\[0,2\],\[1,3\],\[2,3\]\],"FV":\[\[' "$T/square.out"
check "run prints nothing on stderr" test ! -s "$T/err"
check "run - reads stdin" status 0 sh -c "'$BIN' run - <'$T/square.json'"
check "stdin and file give the same bytes" cmp -s "$T/out" "$T/square.out"
check "--threads before and after the command agree" sh -c \
    "'$BIN' --threads 1 run '$T/square.json' >'$T/a' && '$BIN' run '$T/square.json' --threads=3 >'$T/b' && cmp -s '$T/a' '$T/b'"
printf '{"kind":"lines","lines":[[[0,0],[1,0]],[[0,0],[1,2,3]]]}' >"$T/bad.json"
check "invalid request exits 1" status 1 "$BIN" run "$T/bad.json"
check "invalid request names the JSON path" grep -q '^cellar: lines\[1\]\[1\]: expected 2 finite numbers$' "$T/err"
check "invalid request prints nothing on stdout" test ! -s "$T/out"
check "malformed JSON on stdin exits 1" status 1 sh -c "printf '{\"kind\":' | '$BIN' run -"
check "malformed JSON message has line and column" grep -q 'malformed JSON at line 1, column' "$T/err"
check "empty stdin exits 1" status 1 sh -c "'$BIN' run - </dev/null"
check "unknown option in the request exits 1" status 1 sh -c \
    "echo '{\"kind\":\"lines\",\"lines\":[],\"options\":{\"colour\":1}}' | '$BIN' run -"
check "unknown option is named" grep -q '^cellar: options.colour: unknown option' "$T/err"
check "missing file exits 1" status 1 "$BIN" run "$T/no-such-file.json"

# gen lines
check "gen lines exits 0" status 0 "$BIN" gen lines 200 0.3 7
cp "$T/out" "$T/g7a"
"$BIN" gen lines 200 0.3 7 >"$T/g7b"
"$BIN" gen lines 200 0.3 8 >"$T/g8"
check "gen: same seed, same bytes" cmp -s "$T/g7a" "$T/g7b"
check "gen: other seed, other bytes" sh -c "! cmp -s '$T/g7a' '$T/g8'"
check "gen: one line" test "$(lines_of "$T/g7a")" = 1
check "gen: 200 segments" test "$(grep -o '\[\[' "$T/g7a" | wc -l | tr -d ' ')" = 200
check "gen: no negative coordinate" sh -c "! grep -q '[[,]-' '$T/g7a'"
check "gen: translated to x = 0 and y = 0" sh -c "grep -q '\[0,' '$T/g7a' && grep -q ',0\]' '$T/g7a'"
# the generator is ours and portable: these bytes are the same on every machine
check "gen: known bytes for seed 42" test "$("$BIN" gen lines 3 0.3 42)" = \
    '{"kind":"lines","lines":[[[0.29909645858954803,0.437203664596629],[0.4779505905800252,0.6009174729954447]],[[0.07285510944602591,0.07999774025207201],[0.08548985038438017,0]],[[0.02696230578508607,0.517257852451174],[0,0.6841645313429738]]]}'
check "gen lines | run exits 0" status 0 sh -c "'$BIN' run '$T/g7a'"
check "run counts the 200 input segments" test "$(stat "$T/out" input_segments)" = 200
check "gen lines 0 is an empty request" test "$("$BIN" gen lines 0 0.3 1)" = '{"kind":"lines","lines":[]}'
check "gen lines with bad N exits 2" status 2 "$BIN" gen lines ten 0.3 1
check "gen lines with negative scaling exits 2" status 2 "$BIN" gen lines 10 -0.3 1
check "gen lines with a missing seed exits 2" status 2 "$BIN" gen lines 10 0.3
check "gen with an unknown generator exits 2" status 2 "$BIN" gen circles 3

# gen grid
check "gen grid 4 exits 0" status 0 "$BIN" gen grid 4
cp "$T/out" "$T/grid4"
check "gen grid 4 has 8 segments" test "$(grep -o '\[\[' "$T/grid4" | wc -l | tr -d ' ')" = 8
check "gen grid 4 starts with (0,0)-(3,0)" grep -q '^{"kind":"lines","lines":\[\[\[0,0\],\[3,0\]\],\[\[0,1\],\[3,1\]\]' "$T/grid4"
check "gen grid 4 | run - exits 0" status 0 sh -c "'$BIN' gen grid 4 | '$BIN' run -"
check "gen grid 4 gives 9 faces" test "$(stat "$T/out" F)" = 9
check "gen grid 4 gives 16 vertices, 24 edges" test "$(stat "$T/out" V),$(stat "$T/out" E)" = "16,24"
check "gen grid 4: 9 rows in FE" test "$(sed 's/.*"FE":\[\(.*\)\],"holes".*/\1/' "$T/out" | grep -o '\[' | wc -l | tr -d ' ')" = 9
check "gen --options becomes the request's options" status 0 "$BIN" gen grid 3 --options '{"fields":["stats"], "precision": 0.1}'
check "gen --options is kept compact and exact" grep -q '"options":{"fields":\["stats"\],"precision":0.1}}$' "$T/out"
check "gen --options request runs" status 0 sh -c "'$BIN' gen grid 3 --options '{\"fields\":[\"stats\"]}' | '$BIN' run -"
check "fields subset gives only stats" sh -c "grep -q '^{\"dim\":2,\"stats\":{' '$T/out' && ! grep -q '\"FV\"' '$T/out'"
check "gen grid 3 gives 4 faces" test "$(stat "$T/out" F)" = 4
check "gen --options rejects an unknown option (exit 2)" status 2 "$BIN" gen grid 3 --options '{"bogus":true}'
check "gen --options error names the option" grep -q 'options.bogus: unknown option' "$T/err"
check "gen --options rejects a non-object (exit 2)" status 2 "$BIN" gen grid 3 --options '[1]'

# --format request: the request svg and solids would run, which run gives the same result for
printf '<svg xmlns="http://www.w3.org/2000/svg"><rect width="4" height="3"/><line x1="2" y1="-1" x2="2" y2="4"/></svg>' >"$T/d.svg"
check "svg --format request exits 0" status 0 "$BIN" svg "$T/d.svg" --y-up --format request
cp "$T/out" "$T/svgreq"
check "svg --format request prints the svg request with its options" grep -q '^{"kind":"svg","svg":"<svg .*","options":{"y_up":true}}$' "$T/svgreq"
check "... which run - computes as svg does" sh -c "'$BIN' run - <'$T/svgreq' | sed 's/\"ms\":{[^}]*}//' >'$T/a' && '$BIN' svg '$T/d.svg' --y-up | sed 's/\"ms\":{[^}]*}//' >'$T/b' && cmp -s '$T/a' '$T/b'"
check "... two faces" test "$(stat "$T/a" F)" = 2
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n' >"$T/t.obj"
check "solids --format request exits 0" status 0 "$BIN" solids "$T/t.obj" "$T/t.obj" --op union --format request
cp "$T/out" "$T/solreq"
check "solids --format request prints the solids request with the op" grep -q '^{"kind":"solids","solids":\[{"V":\[\[0,0,0\],.*"op":"union"}$' "$T/solreq"
check "... which run - computes as solids does" sh -c "'$BIN' run - <'$T/solreq' | sed 's/\"ms\":{[^}]*}//' >'$T/a' && '$BIN' solids '$T/t.obj' '$T/t.obj' --op union | sed 's/\"ms\":{[^}]*}//' >'$T/b' && cmp -s '$T/a' '$T/b'"
check "run --format request exits 2" status 2 "$BIN" run "$T/square.json" --format request
check "... and says it is for svg, solids and polygons" grep -q -- '--format request is for the svg, solids and polygons' "$T/err"

# A result of more than a megabyte (the unit of streaming) goes to stdout as it is made: whole,
# valid, with the area the GeoJSON path (which needs the whole result in memory) gives; a write
# error exits 1 and says why.
python3 -c 'import json
print(json.dumps({"kind": "polygons", "op": "union", "polygons":
    [[[[i, j], [i + 1.5, j], [i + 1.5, j + 1.5], [i, j + 1.5]]] for i in range(60) for j in range(60)]}))' >"$T/many.json"
check "a big result streams whole" sh -c "'$BIN' run '$T/many.json' >'$T/big.json' && test \$(wc -c <'$T/big.json') -gt 1100000"
check "... valid JSON, area 3660.25" python3 -c "import json,sys; r=json.load(open(sys.argv[1])); assert abs(r['result']['area'] - 3660.25) < 1e-9, r['result']['area']" "$T/big.json"
check "... which is the area the map gives" sh -c "'$BIN' run '$T/many.json' --format geojson | grep -q '\"area\":3660.25'"
if [ -w /dev/full ]; then
    check "a full disk exits 1" sh -c "! '$BIN' run '$T/many.json' >/dev/full 2>'$T/err'"
    check "... and says why" grep -q 'No space left' "$T/err"
fi

# Progress on stderr: --progress writes a line per stage and per tenth (for logs), in the
# documented order, ending at 100%, the result unchanged; a terminal gets a bar redrawn in place
# and cleared at the end; --quiet silences it.
check "--progress exits 0" sh -c "'$BIN' --progress run '$T/many.json' >'$T/p.json' 2>'$T/p.err'"
check "... the result unchanged" sh -c "'$BIN' run '$T/many.json' | sed 's/\"ms\":{[^}]*}//' >'$T/a' && sed 's/\"ms\":{[^}]*}//' '$T/p.json' | cmp -s - '$T/a'"
check "... a line per stage, in the documented order" sh -c "sed -n 's/^cellar: \([a-z]*\) .*% at .* s$/\1/p' '$T/p.err' | uniq | tr '\n' ' ' | grep -qx 'snap buckets intersect split biconnected faces membership select polygons output end '"
check "... ending at 100%" grep -q '^cellar: end *100.0% at' "$T/p.err"
check "... fractions that never go back" sh -c "sed -n 's/^cellar: [a-z]* *\([0-9.]*\)% .*/\1/p' '$T/p.err' | sort -n -c"
check "a terminal gets a bar" sh -c "script -qec \"'$BIN' run '$T/many.json' >/dev/null\" /dev/null >'$T/tty' && grep -q '\[###.*%' '$T/tty' && grep -q \"\$(printf '\r')\" '$T/tty'"
check "... cleared at the end" sh -c "tail -c 8 '$T/tty' | grep -q \"\$(printf '\033\\[K')\""
check "--quiet: no bar on a terminal" sh -c "script -qec \"'$BIN' --quiet run '$T/many.json' >/dev/null\" /dev/null >'$T/tty' && ! grep -q '%' '$T/tty'"
check "no bar when stderr is not a terminal" sh -c "'$BIN' run '$T/many.json' 2>'$T/e' >/dev/null && test ! -s '$T/e'"

echo "$P passed, $F failed"
[ "$F" -eq 0 ]
