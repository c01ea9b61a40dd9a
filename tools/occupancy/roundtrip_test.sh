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
  --label reference --tum "$T/e.tum" --label fploc 2> "$T/legend.err" || fail "png --crop-to tracks --label"
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
# Plan coordinates: a grid every 2 m (40 px per metre, labels 11 px: 1 m would put them closer than 5 of their
# size), labelled in margins left of and below the map; the tick of x = 4 and the tick of y = 2 meet at the end of
# the reference track, (4, 2), drawn where the map says it is (the pictures had a scale bar but no coordinates).
python3 - "$T/legend.png" "$PYLIB" "$T/legend.err" <<'PY' || fail "legend, scale bar, crop or coordinates"
import re, sys
sys.path.insert(0, sys.argv[2])
from png_read import read_png
W, H, px = read_png(sys.argv[1])
m = re.search(r"the map (\d+) x (\d+) px at (\d+), 0 showing x (\S+) \.\. (\S+), y (\S+) \.\. (\S+) m; grid every (\S+) m, "
              r"labelled left \((\d+) px\) and below \((\d+) px\)", open(sys.argv[3]).read())
assert m, open(sys.argv[3]).read()
w, h, L, ax0, ax1, ay0, ay1, step, L2, B = (float(v) for v in m.groups())
w, h, L, B = int(w), int(h), int(L), int(B)
print(f"legend png {W}x{H}: the map {w}x{h} at x {ax0} .. {ax1}, y {ay0} .. {ay1} m, margins {L} / {B} px, grid {step} m")
assert abs(w - 200) <= 4 and abs(h - 120) <= 4, (w, h)
assert (W, H) == (w + L, h + B) and L2 == L and L > 0 and B > 0, (W, H, w, h, L, B)
assert step == 2, step
# Legend: a swatch per track in its colour (reference green, fploc blue), each followed by dark text on a light ground.
fs = max(12, min(28, min(w, h) // 30)); pad, lh, sw = fs // 2, fs * 3 // 2, 2 * fs
for t, col in enumerate(((0, 170, 0), (0, 60, 255))):
    y = pad + t * lh + lh // 2
    assert all(px(L + x, y) == col for x in range(pad, pad + sw)), (t, [px(L + x, y) for x in range(pad, pad + sw)])
    text = [(x, yy) for x in range(L + pad + sw + pad, L + w // 2) for yy in range(y - lh // 2, y + lh // 2) if max(px(x, yy)) < 80]
    assert len(text) > 20, (t, len(text))
# Scale bar: a black bar 1 m (40 px) long just above the map's bottom, its length printed above it.
bar = [x for x in range(W) if px(x, h - pad - 2) == (0, 0, 0)]
assert bar and bar[-1] - bar[0] + 1 == 40, bar
# Ticks: dark marks just outside the map, below it at the columns of x = 2 and 4, left of it at the row of y = 2,
# each with its label's ink beside it.
ink = lambda c: max(c) < 90
col = {x: L + (x - ax0) / (ax1 - ax0) * w for x in (2.0, 4.0)}
row = {y: (ay1 - y) / (ay1 - ay0) * h for y in (2.0,)}
for x, c in col.items():
    assert any(ink(px(cc, h + 1)) for cc in range(int(c) - 1, int(c) + 2)), ("no tick below x", x, c)
    assert sum(ink(px(cc, yy)) for cc in range(int(c) - 8, int(c) + 8) for yy in range(h + 4, H)) > 5, ("no label for x", x)
for y, r in row.items():
    assert any(ink(px(L - 2, rr)) for rr in range(int(r) - 1, int(r) + 2)), ("no tick left of y", y, r)
    assert sum(ink(px(cc, rr)) for cc in range(0, L - 4) for rr in range(int(r) - 8, int(r) + 8)) > 5, ("no label for y", y)
# The reference track ends at (4, 2): green where the two ticks' lines meet.
green = [(cc, rr) for cc in range(int(col[4.0]) - 3, int(col[4.0]) + 4) for rr in range(int(row[2.0]) - 3, int(row[2.0]) + 4)
         if px(cc, rr) == (0, 170, 0)]
assert green, ("the track's end (4, 2) is not at the ticks of x = 4 and y = 2", col[4.0], row[2.0])
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
