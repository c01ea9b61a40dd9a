#!/bin/sh
# fploc map export-pgm PLAN -> fploc occupancy (vectorise) --compare PLAN: both directions within one cell.
set -e
MAP="$1"; OCC="$2"; PLAN="$3"
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
for RES in 0.05 0.02; do
  "$MAP" export-pgm --plan "$PLAN" --resolution $RES --out "$T/m$RES" 2>/dev/null || fail "export-pgm $RES"
  "$OCC" "$T/m$RES/map.yaml" --compare "$PLAN" --json > "$T/r.json" 2>/dev/null || fail "occupancy $RES"
  python3 - "$T/r.json" "$RES" <<'PY' || fail "round trip at $RES m"
import json, sys
j = json.load(open(sys.argv[1])); r = float(sys.argv[2])
print(f"res {r}: segments {j['segments']} plan->map max {j['plan_to_map_max_m']:.4f} map->plan max {j['map_to_plan_max_m']:.4f} chain max {j['max_error_m']:.4f}")
assert j['plan_to_map_max_m'] <= r, j
assert j['map_to_plan_max_m'] <= r, j
assert j['max_error_m'] <= 0.5 * r + 1e-9, j
PY
done
# The picture: the whole grid, and cropped to the occupied cells and a trajectory 0.5 m around them (the room plan
# exported with a margin around it: the crop is smaller in both directions and frames the walls).
printf '0 1.0 1.0 0 0 0 0 1\n1 2.0 1.5 0 0 0 0 1\n' > "$T/t.tum"
"$OCC" "$T/m0.05/map.yaml" --png "$T/full.png" --tum "$T/t.tum" 2>/dev/null || fail "png"
"$OCC" "$T/m0.05/map.yaml" --png "$T/crop.png" --tum "$T/t.tum" --crop-margin 0.5 2>/dev/null || fail "png --crop-margin"
python3 - "$T/full.png" "$T/crop.png" <<'PY' || fail "crop"
import struct, sys
def size(p):
    d = open(p, "rb").read(24)
    assert d[:8] == b"\x89PNG\r\n\x1a\n", p
    return struct.unpack(">II", d[16:24])
(fw, fh), (cw, ch) = size(sys.argv[1]), size(sys.argv[2])
print(f"png {fw}x{fh}, cropped {cw}x{ch}")
assert 0 < cw <= fw and 0 < ch <= fh and (cw, ch) != (fw, fh), (fw, fh, cw, ch)
PY
# A corrupt YAML: one clear error naming file and field, exit 1.
printf 'image: map.pgm\nresolution: -1\norigin: [0, 0, 0]\n' > "$T/bad.yaml"
if "$OCC" "$T/bad.yaml" 2> "$T/err"; then fail "bad yaml accepted"; fi
grep -q "bad.yaml: resolution: must be > 0" "$T/err" || { cat "$T/err"; fail "error text"; }
# Bad numbers on the command line: one error naming the option, exit 1, nothing written (a NaN tolerance gave a
# plan of a few long segments 1.6 m off the walls; a NaN crop margin "cannot create std::vector larger than max_size()").
for bad in "--tolerance nan" "--tolerance -1" "--tolerance inf" "--crop-margin nan --png $T/n.png" "--crop-margin inf --png $T/n.png"; do
  set -- $bad
  if "$OCC" "$T/m0.05/map.yaml" $bad --out "$T/n.json" 2> "$T/err"; then fail "$bad accepted"; fi
  grep -q "^fploc occupancy: $1 " "$T/err" || { cat "$T/err"; fail "$bad: error does not name $1"; }
  [ "$(grep -c . "$T/err")" = 1 ] || { cat "$T/err"; fail "$bad: more than one line"; }
  [ ! -e "$T/n.json" ] && [ ! -e "$T/n.png" ] || fail "$bad: wrote output"
done
echo OK
