#!/bin/sh
# fploc eval's command line: numbers that are not whole finite numbers are one error naming the option and
# the value, exit 2 ("--delta 1x" was read as 1; "--offset nan" associated nothing and blamed --max-dt).
set -e
EVAL="$1"
ROOT="$2"  # the source tree (data/buildings)
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
printf '0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n2 2 0 0 0 0 0 1\n' > "$T/gt.tum"
printf '0 0 0.1 0 0 0 0 1\n1 1 0.1 0 0 0 0 1\n2 2 0.1 0 0 0 0 1\n' > "$T/est.tum"
"$EVAL" --gt "$T/gt.tum" --est "$T/est.tum" --json > "$T/ok.json" 2>/dev/null || fail "good input"
grep -q "\"ate_rmse_m\":0.1," "$T/ok.json" || fail "no ate in $(cat "$T/ok.json")"
# The horizontal ATE beside the 3D one (what a floor plan constrains): est2 is off by 5 cm in y and 10-20 cm in z.
printf '0 0 0 0 0 0 0 1\n1 1 0.05 0.1 0 0 0 1\n2 2 0 0.2 0 0 0 1\n' > "$T/est2.tum"
"$EVAL" --gt "$T/gt.tum" --est "$T/est2.tum" --json > "$T/xy.json" 2> "$T/xy.err" || fail "good input (xy)"
python3 - "$T/xy.json" "$T/ok.json" <<'PY' || fail "horizontal ATE: $(cat "$T/xy.json")"
import json, math, sys
a, b = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
assert abs(a["ate_xy_rmse_m"] - math.sqrt(0.05 ** 2 / 3)) < 1e-9, a
assert abs(a["ate_xy_max_m"] - 0.05) < 1e-9 and abs(a["ate_max_m"] - 0.2) < 1e-9, a
assert abs(b["ate_xy_rmse_m"] - 0.1) < 1e-9 and b["ate_rmse_m"] == 0.1, b
PY
grep -q "(horizontal: rmse 0.0288675 m, max 0.05 m)" "$T/xy.err" || fail "horizontal ATE text: $(cat "$T/xy.err")"
for bad in "--delta 1x" "--offset nan" "--max-dt inf" "--false-ok-m -nan" "--offset 0.5s"; do
  set -- $bad
  rc=0
  "$EVAL" --gt "$T/gt.tum" --est "$T/est.tum" $bad > "$T/out" 2> "$T/err" || rc=$?
  [ "$rc" = 2 ] || fail "$bad: exit $rc, expected 2"
  grep -qx "fploc eval: $1 $2: not a number" "$T/err" || { cat "$T/err"; fail "$bad: error text"; }
  [ "$(grep -c . "$T/err")" = 1 ] || { cat "$T/err"; fail "$bad: more than one line"; }
done
# Numbers out of range, a wrong unit, a missing file option: the problem named first (then the usage), exit 2.
check() {  # check "ARGS" "EXPECTED FIRST LINE"
  rc=0
  "$EVAL" $1 > "$T/out" 2> "$T/err" || rc=$?
  [ "$rc" = 2 ] || fail "$1: exit $rc, expected 2"
  [ "$(head -1 "$T/err")" = "$2" ] || { cat "$T/err"; fail "$1: first line"; }
}
check "--gt $T/gt.tum --est $T/est.tum --max-dt -1" "fploc eval: --max-dt -1: the association window must be >= 0 [s]"
check "--gt $T/gt.tum --est $T/est.tum --delta 0" "fploc eval: --delta 0: the RPE delta must be > 0"
check "--gt $T/gt.tum --est $T/est.tum --delta-unit x" "fploc eval: --delta-unit x: s (seconds) or f (frames)"
check "--gt $T/gt.tum" "fploc eval: --est EST.tum is missing"
# --plot writes SVG: another extension (direct.png got SVG bytes) is refused, naming the option; nothing written.
check "--gt $T/gt.tum --est $T/est.tum --plot $T/direct.png" "fploc eval: --plot $T/direct.png: the plot is written as SVG only; give a file name ending in .svg"
[ ! -e "$T/direct.png" ] || fail "--plot direct.png: written"
"$EVAL" --gt "$T/gt.tum" --est "$T/est.tum" --plot "$T/p.SVG" 2>/dev/null || fail "--plot p.SVG"
grep -q "<svg" "$T/p.SVG" || fail "--plot p.SVG: no SVG"
# --floor (a building's floor, as in map and sim): the legend names the floor drawn (the first by default); an
# unknown floor is one error listing the building's floors; a different floor draws a different plan.
B="$ROOT/data/buildings/demo-building.pbtxt"
"$EVAL" --gt "$T/gt.tum" --est "$T/est.tum" --plot "$T/b0.svg" --plan "$B" 2>/dev/null || fail "--plan building"
grep -q "floor plan: floor 'ground'" "$T/b0.svg" || fail "--plan building: the legend does not name floor ground"
"$EVAL" --gt "$T/gt.tum" --est "$T/est.tum" --plot "$T/b1.svg" --plan "$B" --floor first 2>/dev/null || fail "--floor first"
grep -q "floor plan: floor 'first'" "$T/b1.svg" || fail "--floor first: the legend does not name floor first"
cmp -s "$T/b0.svg" "$T/b1.svg" && fail "--floor first drew the same as the default floor"
rc=0
"$EVAL" --gt "$T/gt.tum" --est "$T/est.tum" --plot "$T/b2.svg" --plan "$B" --floor attic > /dev/null 2> "$T/err" || rc=$?
[ "$rc" = 1 ] || fail "--floor attic: exit $rc, expected 1"
grep -q "no floor 'attic' (floors: ground, first)" "$T/err" || { cat "$T/err"; fail "--floor attic: error text"; }
check "--gt $T/gt.tum --est $T/est.tum --floor first" "fploc eval: --floor needs --plan (a building .pbtxt or .ifc)"
# --hat: a three-cornered hat can estimate a negative variance (here est and THIRD carry the same error with opposite
# signs, gt none: gt's variance comes out negative). That is no noise level: the text says "not resolvable", the JSON
# keeps the signed value and says gt.xy_resolvable false (it printed "gt -0.0027 m" as a noise level).
awk 'BEGIN { srand(7); for (i = 0; i < 200; ++i) { nx = 0.02 * (rand() - 0.5); ny = 0.02 * (rand() - 0.5); t = 0.1 * i;
  printf "%.3f %.6f 0 0 0 0 0 1\n", t, t > "'"$T/hgt.tum"'";
  printf "%.3f %.6f %.6f 0 0 0 0 1\n", t, t + nx, ny > "'"$T/hest.tum"'";
  printf "%.3f %.6f %.6f 0 0 0 0 1\n", t, t - nx, -ny > "'"$T/hthird.tum"'" } }'
"$EVAL" --gt "$T/hgt.tum" --est "$T/hest.tum" --hat "$T/hthird.tum" --json > "$T/hat.json" 2> "$T/hat.err" || { cat "$T/hat.err"; fail "--hat"; }
grep -q "per-pose noise (if white) gt xy not resolvable (negative variance estimate) / " "$T/hat.err" || { cat "$T/hat.err"; fail "--hat: negative gt variance not said"; }
grep -q "gt -[0-9]" "$T/hat.err" && { cat "$T/hat.err"; fail "--hat: a negative noise level printed"; }
grep -q '"gt":{[^}]*"pose_sigma_xy_m":-[0-9][^}]*"xy_resolvable":false' "$T/hat.json" || { cat "$T/hat.json"; fail "--hat: JSON gt.xy_resolvable"; }
grep -q '"est":{[^}]*"xy_resolvable":true' "$T/hat.json" || { cat "$T/hat.json"; fail "--hat: JSON est.xy_resolvable"; }
# --hat with a NaN variance (a third trajectory with coordinates of 1e200: the differences' squares overflow) says
# "not computed (... NaN)" and why, never "negative" (it printed "xy not resolvable (negative variance estimate)" and
# the negative-variance warning); the JSON's sigma is null and xy_resolvable false.
awk 'BEGIN { for (i = 0; i < 50; ++i) printf "%.3f %g 0 0 0 0 0 1\n", 0.1 * i, (i % 2 ? 1e200 : -1e200) }' > "$T/hbig.tum"
"$EVAL" --gt "$T/hgt.tum" --est "$T/hest.tum" --hat "$T/hbig.tum" --json > "$T/hat.json" 2> "$T/hat.err" || { cat "$T/hat.err"; fail "--hat 1e200"; }
grep -q "per-pose noise (if white) gt xy not computed (the variance estimate is NaN) / " "$T/hat.err" || { cat "$T/hat.err"; fail "--hat: NaN variance not said"; }
grep -q "a variance estimate is NaN: " "$T/hat.err" || { cat "$T/hat.err"; fail "--hat: no NaN warning"; }
grep -qi "negative" "$T/hat.err" && { cat "$T/hat.err"; fail "--hat: a NaN variance called negative"; }
grep -q '"gt":{[^}]*"pose_sigma_xy_m":null[^}]*"xy_resolvable":false' "$T/hat.json" || { cat "$T/hat.json"; fail "--hat: JSON gt NaN"; }
# A constant difference (a stationary third trajectory against the straight constant-speed gt) is 0, not a
# rounding residue called a negative variance (-1.7e-9 m).
awk 'BEGIN { for (i = 0; i < 50; ++i) printf "%.3f 5 5 0 0 0 0 1\n", 0.1 * i }' > "$T/hstill.tum"
awk 'BEGIN { for (i = 0; i < 50; ++i) printf "%.3f %.6f 0.3 0 0 0 0 1\n", 0.1 * i, 0.1 * i + 0.3 }' > "$T/hoff.tum"
awk 'BEGIN { for (i = 0; i < 50; ++i) printf "%.3f %.6f 0 0 0 0 0 1\n", 0.1 * i, 0.1 * i }' > "$T/hline.tum"
"$EVAL" --gt "$T/hline.tum" --est "$T/hoff.tum" --hat "$T/hstill.tum" > /dev/null 2> "$T/hat.err" || { cat "$T/hat.err"; fail "--hat constant"; }
grep -q "per-pose noise (if white) gt 0 m / 0 deg, est 0 m / 0 deg, $T/hstill.tum 0 m / 0 deg" "$T/hat.err" || { cat "$T/hat.err"; fail "--hat: a constant difference is not 0"; }
echo OK
