#!/bin/sh
# t_schemas.sh — the JSON Schemas of schemas/ and the OpenAPI document against real documents:
# the schemas are valid; every case request and its `cellar run` result validate, and so do
# random requests with and without options, and solids requests with their 3D results; hand-made documents of every schema that must be
# accepted are, and hand-made INVALID documents are rejected at the expected JSON path (so the
# schemas can fail); the invalid requests are refused by `cellar run` too, so the request schema
# and the C validator agree.
# Usage: CELLAR_BIN=build/cellar tests/t_schemas.sh   (tests/run.sh sets CELLAR_BIN)
# Prints one line per check ("ok ..." / "FAIL ...") and a last line "N passed, N failed".
set -u
. "$(dirname "$0")/lib.sh"
BIN=${CELLAR_BIN:-build/cellar}
case $BIN in /*) ;; *) [ -e "$BIN" ] && BIN="$(pwd)/$BIN" ;; esac # before the cd below
cd "$(dirname "$0")/.."
PY=${PYTHON:-python3}
V="$PY tests/validate.py"
# tally WHAT: counts the "ok"/"FAIL" lines of validate.py's output in $T/out as checks
tally() {
    n=0
    while IFS= read -r line; do
        case $line in
        "ok "*) pass "$1: ${line#ok }"; n=$((n + 1)) ;;
        "FAIL "*) fail "$1: ${line#FAIL }"; n=$((n + 1)) ;;
        esac
    done <"$T/out"
    [ "$n" -gt 0 ] || fail "$1: validate.py printed no result ($(head -c 300 "$T/out"))"
}

$PY -c 'import jsonschema; jsonschema.Draft202012Validator' 2>/dev/null ||
    give_up "python3 with jsonschema (Draft202012Validator) is needed: apt-get install python3-jsonschema"
[ -x "$BIN" ] || give_up "$BIN is not built"

# --- the schemas themselves and the OpenAPI document
$V --check-all >"$T/out" 2>&1
rc=$?
tally "check-all"
check "check-all exits 0" test "$rc" -eq 0

# --- the case folders: requests and their results
mkdir "$T/cases"
for d in tests/cases/*/; do
    [ -f "$d/request.json" ] || continue
    name=$(basename "$d")
    "$BIN" run "$d/request.json" >"$T/cases/$name.result.json" 2>"$T/err" ||
        fail "cellar run tests/cases/$name: $(head -c 200 "$T/err")"
done
$V request tests/cases/*/request.json >"$T/out" 2>&1
tally "case request"
$V result "$T"/cases/*.result.json >"$T/out" 2>&1
tally "case result"
$V openapi:Result "$T"/cases/*.result.json >"$T/out" 2>&1
tally "case result (openapi.json)"

# --- random requests, with and without options
mkdir "$T/gen"
i=0
for seed in 1 2 3 4; do
    for opt in '' '{"operators":true,"keep_dangling":true}' \
        '{"operators":true,"keep_dangling":true,"exterior_last":true,"precision":0.02}' \
        '{"fields":["stats","holes","V","FV"]}' '{"fields":[]}'; do
        i=$((i + 1))
        if [ -n "$opt" ]; then
            "$BIN" gen lines $((40 * seed)) 0.3 "$seed" --options "$opt" >"$T/gen/g$i.request.json"
        else
            "$BIN" gen lines $((40 * seed)) 0.3 "$seed" >"$T/gen/g$i.request.json"
        fi
        "$BIN" run "$T/gen/g$i.request.json" >"$T/gen/g$i.result.json" 2>"$T/err" ||
            fail "cellar run gen lines $((40 * seed)) 0.3 $seed $opt: $(head -c 200 "$T/err")"
        echo "seed $seed ${opt:-no options}" >"$T/gen/g$i.what"
    done
done
$V request "$T"/gen/*.request.json >"$T/out" 2>&1
tally "gen request"
$V result "$T"/gen/*.result.json >"$T/out" 2>&1
tally "gen result"
check "operators present with options.operators" grep -q '"operators":{"d1":{"shape":\[' "$T/gen/g2.result.json"
check "fields [] gives {\"dim\":2}" test "$(cat "$T/gen/g5.result.json")" = '{"dim":2}'

# --- 3D: solids requests and their results (the results come from the 3D core, core/arr3.c)
CUBE_V='[[0,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1]]'
CUBE_FV='[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,7]]'
HALF_V='[[0.5,0.5,0.5],[1.5,0.5,0.5],[1.5,1.5,0.5],[0.5,1.5,0.5],[0.5,0.5,1.5],[1.5,0.5,1.5],[1.5,1.5,1.5],[0.5,1.5,1.5]]'
CUBE="{\"V\":$CUBE_V,\"FV\":$CUBE_FV}"
mkdir "$T/solids"
i=0
for req in "{\"kind\":\"solids\",\"solids\":[$CUBE]}" '{"kind":"solids","solids":[]}' \
    "{\"kind\":\"solids\",\"solids\":[$CUBE,{\"V\":$HALF_V,\"FV\":$CUBE_FV}],\"options\":{\"operators\":true}}" \
    "{\"kind\":\"solids\",\"solids\":[{\"V\":$CUBE_V,\"FV\":[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,7,4,0]]}]}" \
    '{"kind":"solids","faces":{"V":[[0,0,0],[4,0,0],[4,4,0],[0,4,0],[1,1,0],[1,3,0],[3,3,0],[3,1,0],[2,2,-1],[2,2,1],[2,5,1],[2,5,-1]],"FV":[[0,1,2,3],[8,9,10,11]],"holes":{"0":[[4,5,6,7]]}}}' \
    "{\"kind\":\"solids\",\"solids\":[$CUBE],\"options\":{\"fields\":[\"CF\",\"exterior\",\"FE\",\"EV\",\"V\",\"stats\"],\"precision\":0.001}}" \
    "{\"kind\":\"solids\",\"solids\":[$CUBE,{\"V\":$HALF_V,\"FV\":$CUBE_FV}],\"op\":[\"-\",0,1]}"; do
    i=$((i + 1))
    printf '%s\n' "$req" >"$T/solids/s$i.request.json"
    "$BIN" run "$T/solids/s$i.request.json" >"$T/solids/s$i.result.json" 2>"$T/err" ||
        fail "cellar run solids request $i: $(head -c 200 "$T/err")"
done
$V request "$T"/solids/*.request.json >"$T/out" 2>&1
tally "solids request"
$V result "$T"/solids/*.result.json >"$T/out" 2>&1
tally "solids result"
$V openapi:Result "$T"/solids/*.result.json >"$T/out" 2>&1
tally "solids result (openapi.json)"
check "3D operators d1, d2, d3 with options.operators" grep -q '"d3":{"shape":\[18,3\]' "$T/solids/s3.result.json"
check "a flipped face gives a warning" grep -q '"warnings":\["solids\[0\]: orientation inconsistent' "$T/solids/s4.result.json"
check "op: membership and result" grep -q '"membership":{"format":"csr".*"result":{"cells":\[' "$T/solids/s7.result.json"
check "fields V, EV, FE, CF, exterior, stats only" python3 -c 'import json, sys; sys.exit(list(json.load(open(sys.argv[1]))) != ["dim", "V", "EV", "FE", "CF", "exterior", "stats"])' "$T/solids/s6.result.json"

# --- 2D Booleans: polygons requests and their results (core/bool2.c)
SQ1='[[[0,0],[2,0],[2,2],[0,2]]]'
SQ2='[[[1,1],[3,1],[3,3],[1,3]]]'
RINGHOLE='[[[0,0],[10,0],[10,10],[0,10]],[[4,4],[7,4],[7,7],[4,7]]]'
mkdir "$T/polygons"
i=0
for req in "{\"kind\":\"polygons\",\"polygons\":[$SQ1,$SQ2],\"op\":\"union\"}" \
    "{\"kind\":\"polygons\",\"polygons\":[$SQ1,$SQ2],\"op\":\"difference\",\"options\":{\"operators\":true,\"exterior_last\":true}}" \
    "{\"kind\":\"polygons\",\"polygons\":[$RINGHOLE,$SQ1,$SQ2],\"op\":[\"-\",0,[\"+\",1,2]]}" \
    "{\"kind\":\"polygons\",\"polygons\":[$SQ1,$SQ1],\"op\":\"xor\",\"options\":{\"fields\":[\"V\",\"EV\",\"FV\",\"result\"]}}" \
    "{\"kind\":\"polygons\",\"polygons\":[\"POLYGON Z ((0 0 1, 2 0 1, 2 2 1, 0 0 1))\",\"SRID=4326;MULTIPOLYGON (((1 0, 3 0, 3 1, 1 0)), EMPTY)\",{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[1,0],[1,1],[0,0]]]}],\"op\":\"union\"}" \
    "{\"kind\":\"polygons\",\"polygons\":{\"type\":\"FeatureCollection\",\"features\":[{\"type\":\"Feature\",\"properties\":{\"id\":7},\"geometry\":{\"type\":\"MultiPolygon\",\"coordinates\":[[[[0,0],[2,0],[2,2],[0,0]]]]}},{\"type\":\"Feature\",\"geometry\":null}]},\"op\":\"intersection\"}" \
    "{\"kind\":\"polygons\",\"polygons\":[$RINGHOLE,$SQ1,$SQ2],\"op\":[\"-\",0,[\"+\",1,2]],\"options\":{\"fields\":[\"result\"]}}" \
    "{\"kind\":\"polygons\",\"polygons\":[$SQ1,$SQ2],\"op\":\"union\",\"options\":{\"fields\":[\"V\",\"membership\",\"result\",\"stats\"]}}"; do
    i=$((i + 1))
    printf '%s\n' "$req" >"$T/polygons/p$i.request.json"
    "$BIN" run "$T/polygons/p$i.request.json" >"$T/polygons/p$i.result.json" 2>"$T/err" ||
        fail "cellar run polygons request $i: $(head -c 200 "$T/err")"
done
$V request "$T"/polygons/*.request.json >"$T/out" 2>&1
tally "polygons request"
$V result "$T"/polygons/*.result.json >"$T/out" 2>&1
tally "polygons result"
$V openapi:Result "$T"/polygons/*.result.json >"$T/out" 2>&1
tally "polygons result (openapi.json)"
check "polygons: a square with a hole minus two squares has a hole" grep -q '"holes":{"0":\[\[' "$T/polygons/p3.result.json"
check "polygons: xor of a polygon with itself is empty" grep -q '"result":{"cells":\[\],"FV":\[\],"FE":\[\],"holes":{},"area":0}' "$T/polygons/p4.result.json"
check "polygons: fields [\"result\"] gives the result alone, with its own V" \
    grep -q '^{"dim":2,"result":{"V":\[\[' "$T/polygons/p7.result.json"
check "polygons: fields without EV and FV leave the result's FE and cells out" \
    sh -c "grep -q '\"membership\":' '$T/polygons/p8.result.json' && ! grep -q '\"cells\"\\|\"FE\"\\|\"EV\"' '$T/polygons/p8.result.json'"

# --- hand-made documents that must be accepted
H=0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef
J=0f1e2d3c4b5a69788796a5b4c3d2e1f0
T0='"2025-11-22T06:30:00.123Z"'
T1='"2025-11-22T06:30:01+01:00"'
PROB='{"type":"about:blank","title":"Unprocessable Content","status":422,"detail":"lines[17][1]: expected 2 finite numbers","instance":"/v1/jobs","path":"lines[17][1]"}'
JOB="\"id\":\"$J\",\"kind\":\"lines\",\"hash\":\"$H\",\"created\":$T0,\"attempts\":1,\"daemon\":\"a\""
SQUARE='"V":[[0,0],[0,1],[1,0],[1,1]],"EV":[[0,1],[0,2],[1,3],[2,3]],"FV":[[1,0,2,3]],"FE":[[-1,2,4,-3]],"holes":{},"exterior":[[0,1,3,2]]'
CSR1='{"shape":[2,1],"indptr":[0,1,2],"indices":[0,0],"data":[-1,1]}'
CSR0='{"shape":[1,0],"indptr":[0,0],"indices":[],"data":[]}'
CUBE3='"V":[[0,0,0],[0,0,1],[0,1,0],[0,1,1],[1,0,0],[1,0,1],[1,1,0],[1,1,1]],"EV":[[0,1],[0,2],[0,4],[1,3],[1,5],[2,3],[2,6],[3,7],[4,5],[4,6],[5,7],[6,7]],"FV":[[2,6,4,0],[3,1,5,7],[4,5,1,0],[5,4,6,7],[6,2,3,7],[1,3,2,0]],"FE":[[7,-10,-3,2],[-4,5,11,-8],[9,-5,-1,3],[-9,10,12,-11],[-7,6,8,-12],[4,-6,-2,1]],"holes":{},"CF":[[1,2,3,4,5,6]],"CV":[[0,1,2,3,4,5,6,7]],"exterior":[-6,-5,-4,-3,-2,-1]'
STATS3='{"input_solids":1,"input_faces":6,"planes":0,"coplanar_groups":0,"pairs_tested":0,"pairs_meeting":0,"faces_reached":0,"patches":1,"split_faces":0,"cuts":0,"points":0,"V":8,"E":12,"F":6,"C":1,"shells":2,"components":1,"precision":1.4901161193847656e-08,"ms":{"check":0.01,"snap":0.03,"pairs":0.01,"cuts":0.005,"faces":0.35,"cells":0.02,"boolean":0,"total":0.43},"volumes":[1],"warnings":["solids[0]: inward oriented (volume -1): every face flipped"]}'
STATS=$(sed -n 's/.*"stats":\({.*}\)}$/\1/p' "$T/cases/orthogonal.result.json")
check "a stats object to build documents from" test -n "$STATS"

mkdir "$T/good" "$T/bad"
good() { printf '%s\n' "$3" >"$T/good/$1.$2.json"; }
good job queued "{$JOB,\"state\":\"queued\",\"started\":null,\"finished\":null,\"progress\":{\"stage\":\"queued\",\"fraction\":0}}"
good job running "{$JOB,\"state\":\"running\",\"started\":$T0,\"finished\":null,\"progress\":{\"stage\":\"intersect\",\"fraction\":0.5}}"
good job done "{$JOB,\"state\":\"done\",\"started\":$T0,\"finished\":$T1,\"progress\":{\"stage\":\"done\",\"fraction\":1},\"result\":\"/v1/results/$H\"}"
good job done_from_cache "{$JOB,\"state\":\"done\",\"started\":null,\"finished\":$T0,\"progress\":{\"stage\":\"done\",\"fraction\":1},\"result\":\"/v1/results/$H\"}"
good job failed "{$JOB,\"state\":\"failed\",\"started\":$T0,\"finished\":$T1,\"progress\":{\"stage\":\"snap\",\"fraction\":0},\"error\":$PROB}"
good job canceled_queued "{$JOB,\"state\":\"canceled\",\"started\":null,\"finished\":$T1,\"progress\":{\"stage\":\"queued\",\"fraction\":0}}"
good job canceled_running "{$JOB,\"state\":\"canceled\",\"started\":$T0,\"finished\":$T1,\"progress\":{\"stage\":\"faces\",\"fraction\":0.9}}"
good problem with_path "$PROB"
good problem without_path '{"type":"about:blank","title":"Service Unavailable","status":503,"detail":"the queue is full","instance":"/v1/jobs"}'
good problem typed '{"type":"https://cellar.invalid/problems/limit","title":"Beyond a limit","status":422,"detail":"at most 20000000 segments","instance":"/v1/jobs","path":"lines"}'
good result dim_only '{"dim":2}'
good result square "{\"dim\":2,$SQUARE}"
good result stats_only "{\"dim\":2,\"stats\":$STATS}"
good result operators "{\"dim\":2,\"operators\":{\"d1\":$CSR1,\"d2\":$CSR0}}"
good result dim_only_3 '{"dim":3}'
good result cube3 "{\"dim\":3,$CUBE3,\"stats\":$STATS3}"
good result operators3 "{\"dim\":3,\"operators\":{\"d1\":$CSR1,\"d2\":$CSR0,\"d3\":{\"shape\":[0,0],\"indptr\":[0],\"indices\":[],\"data\":[]}}}"
good result lone_edge '{"dim":2,"V":[[0,0],[1,0]],"EV":[[0,1]],"FV":[[0,1]],"FE":[[]],"holes":{"0":[[0,1]]},"exterior":[[0,1]]}'
good request minimal '{"kind":"lines","lines":[]}'
good request all_options '{"kind":"lines","lines":[[[0,0],[1,1]],[[0,1],[1,0]]],"options":{"precision":0.5,"keep_dangling":true,"exterior_last":true,"operators":true,"fields":["V","EV","FV","FE","holes","exterior","stats","operators"]}}'
good request empty_options '{"kind":"lines","lines":[[[0,0],[1,1]]],"options":{}}'
good request solids_minimal "{\"kind\":\"solids\",\"solids\":[$CUBE]}"
good request solids_all_options "{\"kind\":\"solids\",\"solids\":[$CUBE,{\"V\":$HALF_V,\"FV\":$CUBE_FV}],\"options\":{\"precision\":0.001,\"operators\":true,\"fields\":[\"V\",\"EV\",\"FV\",\"FE\",\"holes\",\"CF\",\"CV\",\"exterior\",\"stats\",\"operators\",\"CF\"]}}"
good request faces_with_a_hole '{"kind":"solids","faces":{"V":[[0,0,0],[4,0,0],[4,4,0],[0,4,0],[1,1,0],[1,3,0],[3,3,0],[3,1,0]],"FV":[[0,1,2,3]],"holes":{"0":[[4,5,6,7]]}},"options":{"fields":[]}}'
good request polygons_tree '{"kind":"polygons","polygons":[[[[0,0],[1,0],[1,1]]],[[[0,0],[2,0],[0,2],[0,0]],[[0.1,0.1],[0.2,0.1],[0.1,0.2]]]],"op":["^",0,["&",1,0]],"options":{"precision":0.001}}'
good request repeated_fields '{"kind":"lines","lines":[[[-1e9,2.5e-3],[1E3,7]]],"options":{"fields":["V","V"]}}'
for s in job problem result request; do
    $V "$s" "$T"/good/$s.*.json >"$T/out" 2>&1
    tally "accepted"
done
for f in "$T"/good/request.*.json; do
    check "cellar run accepts $(basename "$f")" sh -c "'$BIN' run '$f' >/dev/null 2>&1"
done

# --- hand-made INVALID documents: each must be rejected at its JSON path
# bad SCHEMA NAME PATH JSON: PATH is where validate.py must report it ("(document)" for the
# root, "not JSON" for strict-JSON refusals)
bad() {
    printf '%s\n' "$4" >"$T/bad/$1.$2.json"
    printf '%s\n' "$3" >"$T/bad/$1.$2.want"
}
bad result string_in_V 'V[2][1]' "{\"dim\":2,\"V\":[[0,0],[0,1],[1,\"0\"],[1,1]]}"
bad result negative_edge_index 'EV[1][0]' '{"dim":2,"EV":[[0,1],[-1,2]]}'
bad result extra_key '(document)' "{\"dim\":2,$SQUARE,\"colour\":\"red\"}"
bad result no_dim '(document)' "{$SQUARE}"
bad result dim_4 'dim' '{"dim":4}'
bad result dim_2_with_CF '(document)' '{"dim":2,"CF":[[1]]}'
bad result vertex3_2_coords 'V[1]' '{"dim":3,"V":[[0,0,0],[0,0]]}'
bad result zero_in_CF 'CF[0][1]' '{"dim":3,"CF":[[1,0]]}'
bad result empty_CF_row 'CF[1]' '{"dim":3,"CF":[[1],[]]}'
bad result face3_2_vertices 'FV[0]' '{"dim":3,"FV":[[0,1]]}'
bad result exterior_fraction 'exterior[0]' '{"dim":3,"exterior":[1.5]}'
bad result exterior_cycles 'exterior[0]' '{"dim":3,"exterior":[[0,1,2]]}'
bad result operators3_no_d3 'operators' "{\"dim\":3,\"operators\":{\"d1\":$CSR1,\"d2\":$CSR0}}"
bad result extra_key_3 '(document)' "{\"dim\":3,$CUBE3,\"colour\":\"red\"}"
bad result stats3_no_volumes 'stats' "{\"dim\":3,\"stats\":$(printf '%s' "$STATS3" | sed 's/"volumes":\[1\],//')}"
bad result stats3_zero_volume 'stats.volumes[0]' "{\"dim\":3,\"stats\":$(printf '%s' "$STATS3" | sed 's/"volumes":\[1\]/"volumes":[0]/')}"
bad result stats3_2d_keys 'stats' "{\"dim\":3,\"stats\":$STATS}"
bad result stats3_ms_2d 'stats.ms' "{\"dim\":3,\"stats\":$(printf '%s' "$STATS3" | sed 's/"snap":/"buckets":/')}"
bad result vertex_3_coords 'V[0]' '{"dim":2,"V":[[0,0,0]]}'
bad result edge_3_vertices 'EV[0]' '{"dim":2,"EV":[[0,1,2]]}'
bad result fractional_index 'FV[0][1]' '{"dim":2,"FV":[[0,1.5,2]]}'
bad result zero_in_FE 'FE[0][2]' '{"dim":2,"FE":[[1,-2,0]]}'
bad result FE_not_integer 'FE[0][0]' '{"dim":2,"FE":[["1"]]}'
bad result one_vertex_cycle 'exterior[0]' '{"dim":2,"exterior":[[3]]}'
bad result holes_key_not_index 'holes' '{"dim":2,"holes":{"face1":[[0,1,2]]}}'
bad result holes_key_leading_zero 'holes' '{"dim":2,"holes":{"01":[[0,1,2]]}}'
bad result holes_not_object 'holes' '{"dim":2,"holes":[[[0,1,2]]]}'
bad result holes_empty_list 'holes.0' '{"dim":2,"holes":{"0":[]}}'
bad result stats_missing_key 'stats' "{\"dim\":2,\"stats\":$(printf '%s' "$STATS" | sed 's/"blocks":[0-9]*,//')}"
bad result stats_extra_key 'stats' "{\"dim\":2,\"stats\":$(printf '%s' "$STATS" | sed 's/^{/{"faces":1,/')}"
bad result stats_negative_count 'stats.V' "{\"dim\":2,\"stats\":$(printf '%s' "$STATS" | sed 's/"V":[0-9]*/"V":-1/')}"
bad result stats_ms_missing 'stats.ms' "{\"dim\":2,\"stats\":$(printf '%s' "$STATS" | sed 's/"total":[0-9.e-]*//; s/,}/}/')}"
bad result stats_zero_precision 'stats.precision' "{\"dim\":2,\"stats\":$(printf '%s' "$STATS" | sed 's/"precision":[0-9.e-]*/"precision":0/')}"
bad result operators_data_2 'operators.d1.data[1]' "{\"dim\":2,\"operators\":{\"d1\":{\"shape\":[2,1],\"indptr\":[0,1,2],\"indices\":[0,0],\"data\":[-1,2]},\"d2\":$CSR0}}"
bad result operators_no_d2 'operators' "{\"dim\":2,\"operators\":{\"d1\":$CSR1}}"
bad result operators_shape_1 'operators.d2.shape' "{\"dim\":2,\"operators\":{\"d1\":$CSR1,\"d2\":{\"shape\":[1],\"indptr\":[0],\"indices\":[],\"data\":[]}}}"
bad result NaN_coordinate 'not JSON' '{"dim":2,"V":[[0,NaN]]}'
bad job unknown_state 'state' "{$JOB,\"state\":\"paused\",\"started\":null,\"finished\":null,\"progress\":{\"stage\":\"queued\",\"fraction\":0}}"
bad job id_uppercase 'id' "{\"id\":\"0F1E2D3C4B5A69788796A5B4C3D2E1F0\",\"kind\":\"lines\",\"hash\":\"$H\",\"created\":$T0,\"state\":\"queued\",\"started\":null,\"finished\":null,\"progress\":{\"stage\":\"queued\",\"fraction\":0},\"attempts\":0,\"daemon\":null}"
bad job hash_short 'hash' "{\"id\":\"$J\",\"kind\":\"lines\",\"hash\":\"0123abc\",\"created\":$T0,\"state\":\"queued\",\"started\":null,\"finished\":null,\"progress\":{\"stage\":\"queued\",\"fraction\":0},\"attempts\":0,\"daemon\":null}"
bad job created_not_rfc3339 'created' "{\"id\":\"$J\",\"kind\":\"lines\",\"hash\":\"$H\",\"created\":\"22/11/2025 06:30\",\"state\":\"queued\",\"started\":null,\"finished\":null,\"progress\":{\"stage\":\"queued\",\"fraction\":0},\"attempts\":0,\"daemon\":null}"
bad job created_unix_seconds 'created' "{\"id\":\"$J\",\"kind\":\"lines\",\"hash\":\"$H\",\"created\":1763793000,\"state\":\"queued\",\"started\":null,\"finished\":null,\"progress\":{\"stage\":\"queued\",\"fraction\":0},\"attempts\":0,\"daemon\":null}"
bad job no_progress '(document)' "{$JOB,\"state\":\"queued\",\"started\":null,\"finished\":null}"
bad job fraction_above_1 'progress.fraction' "{$JOB,\"state\":\"running\",\"started\":$T0,\"finished\":null,\"progress\":{\"stage\":\"faces\",\"fraction\":1.5}}"
bad job failed_without_error '(document)' "{$JOB,\"state\":\"failed\",\"started\":$T0,\"finished\":$T1,\"progress\":{\"stage\":\"snap\",\"fraction\":0}}"
bad job done_without_result '(document)' "{$JOB,\"state\":\"done\",\"started\":$T0,\"finished\":$T1,\"progress\":{\"stage\":\"done\",\"fraction\":1}}"
bad job queued_with_result '(document)' "{$JOB,\"state\":\"queued\",\"started\":null,\"finished\":null,\"progress\":{\"stage\":\"queued\",\"fraction\":0},\"result\":\"/v1/results/$H\"}"
bad job attempts_negative 'attempts' "{\"id\":\"$J\",\"kind\":\"lines\",\"hash\":\"$H\",\"created\":$T0,\"attempts\":-1,\"daemon\":null,\"state\":\"queued\",\"started\":null,\"finished\":null,\"progress\":{\"stage\":\"queued\",\"fraction\":0}}"
bad job daemon_number 'daemon' "{\"id\":\"$J\",\"kind\":\"lines\",\"hash\":\"$H\",\"created\":$T0,\"attempts\":1,\"daemon\":7,\"state\":\"queued\",\"started\":null,\"finished\":null,\"progress\":{\"stage\":\"queued\",\"fraction\":0}}"
bad job result_wrong_path 'result' "{$JOB,\"state\":\"done\",\"started\":$T0,\"finished\":$T1,\"progress\":{\"stage\":\"done\",\"fraction\":1},\"result\":\"/results/$H\"}"
bad job running_finished 'finished' "{$JOB,\"state\":\"running\",\"started\":$T0,\"finished\":$T1,\"progress\":{\"stage\":\"faces\",\"fraction\":0.5}}"
bad job queued_started 'started' "{$JOB,\"state\":\"queued\",\"started\":$T0,\"finished\":null,\"progress\":{\"stage\":\"queued\",\"fraction\":0}}"
bad job error_without_status 'error' "{$JOB,\"state\":\"failed\",\"started\":$T0,\"finished\":$T1,\"progress\":{\"stage\":\"snap\",\"fraction\":0},\"error\":{\"type\":\"about:blank\",\"title\":\"x\",\"detail\":\"x\",\"instance\":\"/v1/jobs\"}}"
bad job extra_key '(document)' "{$JOB,\"state\":\"queued\",\"started\":null,\"finished\":null,\"progress\":{\"stage\":\"queued\",\"fraction\":0},\"priority\":1}"
bad problem no_status '(document)' '{"type":"about:blank","title":"Not Found","detail":"no such job","instance":"/v1/jobs/x"}'
bad problem status_200 'status' '{"type":"about:blank","title":"OK","status":200,"detail":"fine","instance":"/v1/jobs"}'
bad problem status_string 'status' '{"type":"about:blank","title":"Not Found","status":"404","detail":"no such job","instance":"/v1/jobs/x"}'
bad problem extra_key '(document)' '{"type":"about:blank","title":"Not Found","status":404,"detail":"no such job","instance":"/v1/jobs/x","message":"no such job"}'
bad problem path_not_string 'path' '{"type":"about:blank","title":"Unprocessable Content","status":422,"detail":"x","instance":"/v1/jobs","path":["lines",17]}'
bad request unknown_option 'options' '{"kind":"lines","lines":[],"options":{"colour":1}}'
bad request unknown_key '(document)' '{"kind":"lines","lines":[],"name":"plan"}'
bad request unknown_kind 'kind' '{"kind":"mesh","lines":[]}'
bad request no_kind '(document)' '{"lines":[[[0,0],[1,1]]]}'
bad request no_lines '(document)' '{"kind":"lines"}'
bad request lines_not_array 'lines' '{"kind":"lines","lines":{"0":[[0,0],[1,1]]}}'
bad request point_3_numbers 'lines[1][1]' '{"kind":"lines","lines":[[[0,0],[1,0]],[[0,0],[1,2,3]]]}'
bad request point_1_number 'lines[0][0]' '{"kind":"lines","lines":[[[0],[1,0]]]}'
bad request segment_3_points 'lines[0]' '{"kind":"lines","lines":[[[0,0],[1,0],[2,0]]]}'
bad request coordinate_string 'lines[0][1][0]' '{"kind":"lines","lines":[[[0,0],["1",0]]]}'
bad request coordinate_null 'lines[0][1][1]' '{"kind":"lines","lines":[[[0,0],[1,null]]]}'
bad request coordinate_NaN 'not JSON' '{"kind":"lines","lines":[[[0,0],[1,NaN]]]}'
bad request precision_0 'options.precision' '{"kind":"lines","lines":[],"options":{"precision":0}}'
bad request precision_negative 'options.precision' '{"kind":"lines","lines":[],"options":{"precision":-0.001}}'
bad request precision_string 'options.precision' '{"kind":"lines","lines":[],"options":{"precision":"0.001"}}'
bad request keep_dangling_string 'options.keep_dangling' '{"kind":"lines","lines":[],"options":{"keep_dangling":"yes"}}'
bad request operators_number 'options.operators' '{"kind":"lines","lines":[],"options":{"operators":1}}'
bad request exterior_last_null 'options.exterior_last' '{"kind":"lines","lines":[],"options":{"exterior_last":null}}'
bad request fields_unknown_name 'options.fields[1]' '{"kind":"lines","lines":[],"options":{"fields":["V","faces"]}}'
bad request fields_string 'options.fields' '{"kind":"lines","lines":[],"options":{"fields":"V"}}'
bad request options_array 'options' '{"kind":"lines","lines":[],"options":[]}'
bad request solids_and_faces '(document)' "{\"kind\":\"solids\",\"solids\":[$CUBE],\"faces\":$CUBE}"
bad request solids_nor_faces '(document)' '{"kind":"solids"}'
bad request solids_not_array 'solids' "{\"kind\":\"solids\",\"solids\":$CUBE}"
bad request solid_vertex_2_numbers 'solids[0].V[1]' '{"kind":"solids","solids":[{"V":[[0,0,0],[1,0]],"FV":[[0,1,1]]}]}'
bad request solid_face_2_vertices 'solids[0].FV[1]' '{"kind":"solids","solids":[{"V":[[0,0,0],[1,0,0]],"FV":[[0,1,1],[0,1]]}]}'
bad request solid_negative_index 'solids[0].FV[0][1]' '{"kind":"solids","solids":[{"V":[[0,0,0],[1,0,0]],"FV":[[0,-1,1]]}]}'
bad request solid_extra_key 'solids[0]' '{"kind":"solids","solids":[{"V":[],"FV":[[0,1,2]],"name":"a"}]}'
bad request solid_no_faces 'solids[0].FV' '{"kind":"solids","solids":[{"V":[[0,0,0]],"FV":[]}]}'
bad request faces_holes_key 'faces.holes' '{"kind":"solids","faces":{"V":[[0,0,0],[1,0,0],[1,1,0]],"FV":[[0,1,2]],"holes":{"x":[[0,1,2]]}}}'
bad request faces_empty_hole_list 'faces.holes.0' '{"kind":"solids","faces":{"V":[[0,0,0],[1,0,0],[1,1,0]],"FV":[[0,1,2]],"holes":{"0":[]}}}'
bad request solids_lines_key '(document)' "{\"kind\":\"solids\",\"faces\":$CUBE,\"lines\":[]}"
bad request solids_option_2d 'options' "{\"kind\":\"solids\",\"solids\":[$CUBE],\"options\":{\"keep_dangling\":true}}"
bad request solids_precision_0 'options.precision' "{\"kind\":\"solids\",\"solids\":[$CUBE],\"options\":{\"precision\":0}}"
bad request solids_field_unknown 'options.fields[1]' "{\"kind\":\"solids\",\"solids\":[$CUBE],\"options\":{\"fields\":[\"CF\",\"C\"]}}"
bad request polygons_no_op '(document)' '{"kind":"polygons","polygons":[[[[0,0],[1,0],[1,1]]]]}'
bad request polygons_ring_2_points 'polygons[0][1]' '{"kind":"polygons","polygons":[[[[0,0],[1,0],[1,1]],[[0,0],[1,0]]]],"op":"union"}'
bad request polygons_point_3_numbers 'polygons[0][0][2]' '{"kind":"polygons","polygons":[[[[0,0],[1,0],[1,1,1]]]],"op":"union"}'
bad request polygons_empty 'polygons' '{"kind":"polygons","polygons":[],"op":"union"}'
bad request polygons_no_rings 'polygons[0]' '{"kind":"polygons","polygons":[[]],"op":"union"}'
bad request polygons_op_name 'op' '{"kind":"polygons","polygons":[[[[0,0],[1,0],[1,1]]]],"op":"merge"}'
bad request polygons_op_operator 'op[0]' '{"kind":"polygons","polygons":[[[[0,0],[1,0],[1,1]]]],"op":["*",0,0]}'
bad request polygons_op_negative 'op[2]' '{"kind":"polygons","polygons":[[[[0,0],[1,0],[1,1]]]],"op":["+",0,-1]}'
bad request polygons_option_3d 'options.fields[0]' '{"kind":"polygons","polygons":[[[[0,0],[1,0],[1,1]]]],"op":"union","options":{"fields":["CF"]}}'
bad request duplicate_key 'not JSON' '{"kind":"lines","lines":[],"lines":[[[0,0],[1,1]]]}'
for s in result job problem request; do
    $V "$s" "$T"/bad/$s.*.json >"$T/out" 2>&1
    for f in "$T"/bad/$s.*.json; do
        name=$(basename "$f" .json)
        want=$(cat "$T/bad/$name.want")
        line=$(grep -F " $f: " "$T/out" | head -n 1)
        if grep -q -F -x "ok $s $f" "$T/out"; then
            fail "rejects $name: it was accepted"
        elif [ -z "$line" ]; then
            fail "rejects $name: no verdict ($(head -c 200 "$T/out"))"
        else
            got=${line#FAIL "$s" "$f": }
            got=${got%%: *}
            if [ "$got" = "$want" ]; then pass "rejects $name at $want"; else fail "rejects $name at $want: $line"; fi
        fi
    done
done
for f in "$T"/bad/request.*.json; do
    check "cellar run refuses $(basename "$f" .json) too" sh -c "'$BIN' run '$f' >/dev/null 2>&1; test \$? -eq 1"
done

# --- validate.py itself
"$BIN" run tests/cases/orthogonal/request.json | $V result - >"$T/out" 2>&1
check "validate.py - reads stdin" grep -q -x 'ok result -' "$T/out"
printf '{"dim":2,"V":[[0,"a"]]}' | $V result - >"$T/out" 2>&1
check "validate.py - on an invalid document exits 1" test $? -eq 1
$V result "$T/cases/orthogonal.result.json" "$T/bad/result.string_in_V.json" "$T/cases/empty.result.json" >"$T/out" 2>&1
rc=$?
check "validate.py: one invalid file of three exits 1" test "$rc" -eq 1
check "validate.py: one line per file" test "$(wc -l <"$T/out" | tr -d ' ')" = 3
check "validate.py: the valid files still pass" test "$(grep -c '^ok result ' "$T/out")" = 2
printf '{"dim":' >"$T/truncated.json"
$V result "$T/truncated.json" >"$T/out" 2>&1
check "validate.py: malformed JSON exits 1" test $? -eq 1
check "validate.py: malformed JSON says so" grep -q "^FAIL result $T/truncated.json: not JSON" "$T/out"
$V result "$T/no-such-file.json" >"$T/out" 2>&1
check "validate.py: a missing file exits 1" test $? -eq 1
$V nosuchschema "$T/truncated.json" >"$T/out" 2>&1
check "validate.py: an unknown schema exits 2" test $? -eq 2
$V >"$T/out" 2>&1
check "validate.py without arguments exits 2" test $? -eq 2

echo "$P passed, $F failed"
[ "$F" -eq 0 ]
