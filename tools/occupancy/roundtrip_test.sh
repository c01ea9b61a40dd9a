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
# Framed on the trajectories alone (--crop-to tracks: the map's walls reach far beyond them), with a legend naming them
# in their colours (top left) and a scale bar in metres (bottom left). Tracks over 3 x 1 m, 1 m around them, 2 px per
# 5 cm cell: 200 x 120 px, the bar 1 m = 40 px (1, 2 or 5 x 10^k m, at most a third of the width).
printf '0 1.0 1.0 0 0 0 0 1\n1 4.0 2.0 0 0 0 0 1\n' > "$T/t.tum"
printf '0 1.2 1.2 0 0 0 0 1\n1 3.8 1.8 0 0 0 0 1\n' > "$T/e.tum"
"$OCC" "$T/m0.05/map.yaml" --png "$T/legend.png" --scale 2 --crop-margin 1 --crop-to tracks --tum "$T/t.tum" \
  --label reference --tum "$T/e.tum" --label fploc 2>/dev/null || fail "png --crop-to tracks --label"
if "$OCC" "$T/m0.05/map.yaml" --png "$T/n.png" --tum "$T/t.tum" --label a --label b 2> "$T/err"; then fail "2 labels for 1 track"; fi
# Trajectories wholly off the map frame nothing: an error, not a 20-px strip at the edge (or the whole grid).
printf '0 1000.0 1000.0 0 0 0 0 1\n1 1001.0 1000.0 0 0 0 0 1\n' > "$T/far.tum"
if "$OCC" "$T/m0.05/map.yaml" --png "$T/far.png" --crop-margin 1 --crop-to tracks --tum "$T/far.tum" 2> "$T/err"; then
  fail "tracks off the map framed"; fi
grep -q "none of the 2 trajectory points lies on the map" "$T/err" || fail "off-map tracks: $(cat "$T/err")"
if "$OCC" "$T/m0.05/map.yaml" --crop-to tracks --png "$T/n.png" 2> "$T/err"; then fail "--crop-to without --crop-margin"; fi
if "$OCC" "$T/m0.05/map.yaml" --tum "$T/t.tum" --label a 2> "$T/err"; then fail "--tum/--label without --png"; fi
grep -q "give --png" "$T/err" || fail "--label without --png: $(cat "$T/err")"
PYLIB="$(cd "$(dirname "$0")/../pylib" && pwd)"
python3 - "$T/legend.png" "$PYLIB" <<'PY' || fail "legend, scale bar or crop"
import sys
sys.path.insert(0, sys.argv[2])
from png_read import read_png
w, h, px = read_png(sys.argv[1])
print(f"legend png {w}x{h}")
assert abs(w - 200) <= 4 and abs(h - 120) <= 4, (w, h)
# Legend: a swatch per track in its colour (reference green, fploc blue), each followed by dark text on a light ground.
fs = max(12, min(28, min(w, h) // 30)); pad, lh, sw = fs // 2, fs * 3 // 2, 2 * fs
for t, col in enumerate(((0, 170, 0), (0, 60, 255))):
    y = pad + t * lh + lh // 2
    assert all(px(x, y) == col for x in range(pad, pad + sw)), (t, [px(x, y) for x in range(pad, pad + sw)])
    text = [(x, yy) for x in range(pad + sw + pad, w // 2) for yy in range(y - lh // 2, y + lh // 2) if max(px(x, yy)) < 80]
    assert len(text) > 20, (t, len(text))
# Scale bar: a black bar 1 m (40 px) long just above the bottom, its length printed above it.
bar = [x for x in range(w) if px(x, h - pad - 2) == (0, 0, 0)]
assert bar and bar[-1] - bar[0] + 1 == 40, bar
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
