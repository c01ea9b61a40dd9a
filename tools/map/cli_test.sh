#!/bin/sh
# CLI contract checks for fploc-map: errors name file:line and exit non-zero; validate emits the JSON keys.
set -u
MAP="$1"
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
printf 'x1,y1,x2,y2\n0,0,1,0\n0,0,zz,1\n' > "$T/bad.csv"
if "$MAP" build --plan "$T/bad.csv" --out "$T/x.fpmap" 2> "$T/err"; then fail "bad CSV accepted"; fi
grep -q "bad.csv:3:" "$T/err" || fail "error does not name bad.csv:3: $(cat "$T/err")"
printf '  0\nSECTION\n  2\nENTITIES\n  0\nLINE\n  8\nw\n 10\n0\n' > "$T/trunc.dxf"
if "$MAP" build --plan "$T/trunc.dxf" --out "$T/x.fpmap" 2> "$T/err"; then fail "truncated DXF accepted"; fi
grep -q "trunc.dxf:" "$T/err" || fail "error does not name trunc.dxf: $(cat "$T/err")"
printf '  0\nSECTION\n  2\nENTITIES\n  0\nLINE\n  8\nw\n 10\n0\n 20\nnan\n 11\n1\n 21\n1\n  0\nENDSEC\n  0\nEOF\n' > "$T/nan.dxf"
if "$MAP" build --plan "$T/nan.dxf" --out "$T/x.fpmap" 2> "$T/err"; then fail "NaN DXF accepted"; fi
grep -q "nan.dxf:11: LINE" "$T/err" || fail "NaN error does not name nan.dxf:11 (the group code) and the entity: $(cat "$T/err")"
cat > "$T/p.json" <<'J'
{"units":"m","elements":[{"type":"segment","a":[0,0],"b":[10,0],"layer":"walls"},{"type":"segment","a":[10,0],"b":[10,8],"layer":"walls"},
 {"type":"circle","c":[4,4],"r":0.3,"layer":"cols"},{"type":"arc","c":[2,6],"r":1,"start_deg":0,"end_deg":180,"layer":"walls"}]}
J
if "$MAP" build --plan "$T/p.json" --layers 'nothing*' --out "$T/x.fpmap" 2> "$T/err"; then fail "empty layer selection accepted"; fi
grep -q "no elements on layers" "$T/err" || fail "empty selection message: $(cat "$T/err")"
"$MAP" build --plan "$T/p.json" --mode exact --depth 8 --out "$T/p.fpmap" --json > "$T/build.json" 2>/dev/null || fail "build"
grep -q '"leaves"' "$T/build.json" || fail "build JSON"
"$MAP" validate --plan "$T/p.json" --samples 20000 --depths 4-6 --json > "$T/v.json" 2>/dev/null || fail "validate"
for k in elements rows depth leaf_length_m hit_first hit_first_or_second hit_exact ns_per_query bytes baselines brute_force_ns kdtree_ns kdtree_hit; do
  grep -q "\"$k\"" "$T/v.json" || fail "validate JSON lacks $k"
done
"$MAP" validate --plan "$T/p.json" --mode exact --samples 20000 --depths 5-7 --no-baselines --json > "$T/x.json" 2>/dev/null || fail "validate exact"
[ "$(grep -c '"hit_exact": 1.0,' "$T/x.json")" = 3 ] || fail "exact mode not exact: $(grep hit_exact "$T/x.json")"
"$MAP" render --plan "$T/p.json" --map "$T/p.fpmap" --out "$T/r.svg" 2>/dev/null || fail "render"
grep -q "<svg" "$T/r.svg" || fail "svg"
# The lines only (--fields none: no look-up fields built, no field rectangles); a plan-change drawing's layers in
# colour with a legend, and a scale bar (the trial found `map diff`'s DXF drawn all black over the fields).
cat > "$T/d.json" <<'J'
{"units":"m","elements":[{"type":"segment","a":[0,0],"b":[10,0],"layer":"FPLOC-PLAN"},{"type":"segment","a":[0,0],"b":[0,8],"layer":"FPLOC-MISSING"},
 {"type":"segment","a":[3,3],"b":[6,3],"layer":"FPLOC-NEW"}]}
J
"$MAP" render --plan "$T/d.json" --fields none --out "$T/d.svg" 2> "$T/err" || fail "render --fields none: $(cat "$T/err")"
grep -q "building the look-up" "$T/err" && fail "--fields none built the fields"
grep -v 'fill="#ffffffd0"' "$T/d.svg" | grep -q "<rect" && fail "--fields none drew field rectangles"
grep -q 'stroke="#d62728"' "$T/d.svg" || fail "FPLOC-MISSING not drawn red"
grep -q 'stroke="#2ca02c"' "$T/d.svg" || fail "FPLOC-NEW not drawn green"
grep -q 'FPLOC-MISSING (1)' "$T/d.svg" || fail "no legend line for FPLOC-MISSING"
grep -q '>2 m</text>' "$T/d.svg" || fail "no 2 m scale bar (plan 10 m wide)"
grep -q "FPLOC-MOVED" "$T/d.svg" && fail "a legend line for a layer the drawing does not have"
"$MAP" render --plan "$T/d.json" --fields none --out "$T/d.png" 2> "$T/err" || fail "render png --fields none"
grep -q "scale bar (bottom left) 2 m" "$T/err" || fail "png scale bar not reported: $(cat "$T/err")"
# Plan coordinates (the pictures had a scale bar but nothing to read a start pose off): a grid every metre, its ticks
# and labels in margins below and left of the plan. PNG: the ticks under the plan are a metre apart, the FPLOC-MISSING
# wall x = 0 is over the tick labelled 0 and the FPLOC-NEW segment starts (x = 3) three ticks right of it. SVG: the
# grid's labels are at their plan coordinates ("3" at x = 3 below the plan, "8" at y = 8 left of it).
PYLIB="$(cd "$(dirname "$0")/../pylib" && pwd)"
python3 - "$T/d.svg" "$T/d.png" "$T/err" "$PYLIB" <<'PY' || fail "no plan coordinates on the picture"
import re, sys
sys.path.insert(0, sys.argv[4])
from png_read import read_png
svg, err = open(sys.argv[1]).read(), open(sys.argv[3]).read()
m = re.search(r"grid every (\S+) m, labelled left \((\d+) px\) and below \((\d+) px\)", err)
assert m, err
step, L, B = float(m.group(1)), int(m.group(2)), int(m.group(3))
band = int(re.search(r"legend above the plan \((\d+) px\)", err).group(1))
assert step == 1, step
w, h, px = read_png(sys.argv[2])
bottom = h - B  # the first row below the plan
ink = lambda c: max(c) < 90
ticks = [x for x in range(L, w) if ink(px(x, bottom + 1)) and not ink(px(x - 1, bottom + 1))]
gaps = [b - a for a, b in zip(ticks, ticks[1:])]
assert len(ticks) >= 8 and max(gaps) - min(gaps) <= 1, ("ticks", ticks)
def cols(rgb):
    return [x for x in range(L, w) for y in range(band, bottom) if px(x, y) == rgb]
red = cols((214, 39, 40)); green = cols((44, 160, 44))
wall = (min(red) + max(red)) / 2
zero = min(range(len(ticks)), key=lambda k: abs(ticks[k] - wall))
assert abs(ticks[zero] - wall) <= 2, ("the wall x = 0 is not over a tick", wall, ticks)
assert abs(ticks[zero + 3] - min(green) - 1.5) <= 3, ("the segment from x = 3 does not start 3 ticks right of x = 0", min(green), ticks)
# The labels under the plan: ink below the ticks of x = 0 and x = 3.
for k in (zero, zero + 3):
    assert sum(ink(px(x, y)) for x in range(ticks[k] - 8, ticks[k] + 8) for y in range(bottom + 3, h)) > 5, ("no label", k)
labels = re.search(r'<g class="grid-labels"[^>]*>(.*?)</g>', svg, re.S)
assert labels, "SVG: no grid labels"
assert re.search(r'<text x="3" y="[^"]*" text-anchor="middle">3</text>', labels.group(1)), labels.group(1)
y8 = re.search(r'<text x="[^"]*" y="([^"]*)" text-anchor="end">8</text>', labels.group(1))
assert y8 and abs(float(y8.group(1)) + 8) < 0.5, labels.group(1)
assert '<line x1="0" y1=' in re.search(r'<g class="grid"[^>]*>(.*?)</g>', svg, re.S).group(1), "SVG: no grid line x = 0"
print(f"coordinates: grid {step} m, ticks every {gaps[0]} px, wall x = 0 at column {wall}, the NEW segment from {min(green)}")
PY
# The legend sits in a band above the plan, not over its top-left walls (the trial: the SVG's legend box covered
# them). SVG: the white box ends above the plan's top (y 8, -8 in SVG's downward y) and the view starts above it;
# PNG: the band's height is said, the legend's swatch is in it, and the FPLOC-MISSING wall x = 0, y 0..8 is drawn
# pure red over its whole length (the translucent box paled its top).
PYLIB="$(cd "$(dirname "$0")/../pylib" && pwd)"
python3 - "$T/d.svg" "$T/d.png" "$T/err" "$PYLIB" <<'PY' || fail "the legend covers the plan"
import re, sys
sys.path.insert(0, sys.argv[4])
from png_read import read_png
svg, err = open(sys.argv[1]).read(), open(sys.argv[3]).read()
box = re.search(r'<rect x="[^"]*" y="([^"]*)" width="[^"]*" height="([^"]*)" fill="#ffffffd0"', svg)
assert box and float(box.group(1)) + float(box.group(2)) <= -8.0, ("SVG legend box", box and box.groups())
view_top = float(re.search(r'viewBox="[^ ]* ([^ ]*) ', svg).group(1))
assert view_top <= float(box.group(1)), ("SVG view top", view_top)
band = int(re.search(r"legend above the plan \((\d+) px\)", err).group(1))
w, h, px = read_png(sys.argv[2])
red = (214, 39, 40)
rows = [y for y in range(h) if any(px(x, y) == red for x in range(0, w // 8))]
assert any(y < band for y in rows), ("no legend swatch in the band", band)
line = [y for y in rows if y >= band]
top, bottom = min(line), max(line)
scale = (h - band) / 8.6  # px per metre: the plan is 8 m high plus 2 x 0.3 m of margin
assert top - band < 0.4 * scale and bottom - top > 7.5 * scale, ("the wall's extent", band, top, bottom, scale)
missing = [y for y in range(top, bottom + 1) if not any(px(x, y) == red for x in range(0, w // 8))]
assert not missing, ("the wall is not red at rows", missing[:5])
PY
if "$MAP" render --plan "$T/d.json" --fields some --out "$T/x.svg" 2> "$T/err"; then fail "--fields some accepted"; fi
grep -q "fields" "$T/err" || fail "--fields error does not name the option: $(cat "$T/err")"
"$MAP" export-pgm --plan "$T/p.json" --resolution 0.1 --out "$T/pgm" 2>/dev/null || fail "export-pgm"
head -c 2 "$T/pgm/map.pgm" | grep -q P5 || fail "pgm header"
grep -q "resolution: 0.1" "$T/pgm/map.yaml" || fail "yaml"
# Buildings: --floor picks the floor; an unknown floor names the known ones; a single plan has one floor.
B="$(cd "$(dirname "$0")/../.." && pwd)/data/buildings/two-floors.pbtxt"
"$MAP" render --plan "$B" --floor first --out "$T/first.svg" 2>/dev/null || fail "render a building floor"
grep -q "<svg" "$T/first.svg" || fail "building floor svg"
# A building floor's stairs, ramps and lifts (the connections from or to it) are drawn, each kind in its colour (a
# translucent area, its outline) with a legend line naming it and the other floor; connections elsewhere are not.
D="$(cd "$(dirname "$0")/../.." && pwd)/data/plans"
cat > "$T/b3.pbtxt" <<EOF
name: "three"
floor { name: "ground" plan { file: "$D/room.json" } elevation_m: 0 ceiling_height_m: 3 }
floor { name: "first" plan { file: "$D/corridor.json" } elevation_m: 3.3 ceiling_height_m: 2.8 }
floor { name: "second" plan { file: "$D/corridor.json" } elevation_m: 6.6 ceiling_height_m: 2.8 }
connection { name: "s1" kind: STAIRS from_floor: "ground" to_floor: "first"
             polygon { x: 0 y: 0 } polygon { x: 4 y: 0 } polygon { x: 4 y: 2 } polygon { x: 0 y: 2 } }
connection { name: "r1" kind: RAMP from_floor: "ground" to_floor: "first"
             polygon { x: 6 y: 4 } polygon { x: 9 y: 4 } polygon { x: 9 y: 6 } polygon { x: 6 y: 6 } }
connection { name: "l1" kind: LIFT from_floor: "first" to_floor: "second"
             polygon { x: 8 y: 10 } polygon { x: 10 y: 10 } polygon { x: 10 y: 12 } polygon { x: 8 y: 12 } }
EOF
PYLIB="$(cd "$(dirname "$0")/../pylib" && pwd)"
for fl in ground first second; do
  "$MAP" render --plan "$T/b3.pbtxt" --floor $fl --fields none --out "$T/$fl.svg" 2> "$T/err" || fail "render $fl: $(cat "$T/err")"
  "$MAP" render --plan "$T/b3.pbtxt" --floor $fl --fields none --width 800 --out "$T/$fl.png" 2>> "$T/err" || fail "render $fl png"
  case $fl in
    ground) want="STAIRS 's1' to first|RAMP 'r1' to first"; not="LIFT" ;;
    first) want="STAIRS 's1' to ground|RAMP 'r1' to ground|LIFT 'l1' to second"; not="-" ;;
    second) want="LIFT 'l1' to first"; not="STAIRS|RAMP" ;;
  esac
  python3 - "$T/$fl.svg" "$T/$fl.png" "$T/err" "$want" "$not" "$PYLIB" <<'PY' || fail "floor $fl: stairs, ramps, lifts"
import sys
sys.path.insert(0, sys.argv[6])
from png_read import read_png
svg, err = open(sys.argv[1]).read(), open(sys.argv[3]).read()
colour = {"STAIRS": (148, 103, 189, "#9467bd"), "RAMP": (140, 86, 75, "#8c564b"), "LIFT": (23, 190, 207, "#17becf")}
w, h, px = read_png(sys.argv[2])
count = {}
for y in range(h):
    for x in range(w):
        count[px(x, y)] = count.get(px(x, y), 0) + 1
for line in sys.argv[4].split("|"):
    kind = line.split()[0]
    r, g, b, hexc = colour[kind]
    assert f">{line}</text>" in svg, ("SVG legend", line)
    assert f'fill="{hexc}" fill-opacity="0.3"' in svg, ("SVG area", kind)
    assert err.count(line) == 2, ("summary line", line, err)
    area = tuple(int(0.7 * 255 + 0.3 * c) for c in (r, g, b))  # blended over the white ground
    assert count.get(area, 0) > 500, ("PNG area", kind, area, count.get(area, 0))
    assert count.get((r, g, b), 0) > 100, ("PNG outline and legend swatch", kind, count.get((r, g, b), 0))
for kind in sys.argv[5].split("|"):
    if kind in colour:
        assert kind not in svg and kind not in err and count.get(colour[kind][:3], 0) == 0, ("drawn on the wrong floor", kind)
PY
done
# Names from the building file are XML text in the SVG (a name with & or < made a file no SVG reader opens).
sed 's/name: "s1"/name: "A\&B <stairs>"/' "$T/b3.pbtxt" > "$T/b3x.pbtxt"
"$MAP" render --plan "$T/b3x.pbtxt" --floor ground --fields none --out "$T/gx.svg" 2> "$T/err" || fail "render a name with & and <"
python3 -c "import sys, xml.etree.ElementTree as E; t = E.parse(sys.argv[1]); assert any(\"'A&B <stairs>'\" in (x.text or '') for x in t.iter()), 'name'" "$T/gx.svg" \
  || fail "the SVG with a name holding & and < does not parse or lost the name"
"$MAP" build --plan "$B" --mode exact --out "$T/ground.fpmap" --json > "$T/b.json" 2>/dev/null || fail "build the first floor"
grep -q '"elements": 44' "$T/b.json" || fail "the default floor is the first (the room, 44 elements)"
if "$MAP" validate --plan "$B" --floor roof --no-baselines 2> "$T/err"; then fail "unknown floor accepted"; fi
grep -q "no floor 'roof' (floors: ground, first)" "$T/err" || fail "unknown floor message: $(cat "$T/err")"
if "$MAP" render --plan "$T/p.json" --floor first --out "$T/x.svg" 2> "$T/err"; then fail "floor of a single plan accepted"; fi
grep -q "a single plan has one floor" "$T/err" || fail "single plan floor message: $(cat "$T/err")"
# A number option that is nan or inf: one error naming it, exit 1, nothing written (--resolution inf wrote a 0 x 0
# map whose YAML its own reader rejects).
for bad in "export-pgm --resolution inf" "export-pgm --margin nan --resolution 0.1" "validate --root inf --no-baselines"; do
  set -- $bad
  out=""; [ "$1" = export-pgm ] && out="--out $T/n"
  if "$MAP" $bad --plan "$T/p.json" $out 2> "$T/err"; then fail "$bad accepted"; fi
  grep -q "^fploc map: error: $2 .*: not a finite number" "$T/err" || fail "$bad: $(cat "$T/err")"
  [ ! -e "$T/n" ] && [ ! -e "$T/n.svg" ] || fail "$bad: wrote output"
done
# A size that is not > 0: one error, nothing written (--width -5 wrote a 16 x 16 PNG).
for w in -5 0; do
  if "$MAP" render --plan "$T/p.json" --width $w --out "$T/w.png" 2> "$T/err"; then fail "--width $w accepted"; fi
  grep -q "^fploc map: error: --width must be > 0 (pixels / SVG user units), got $w" "$T/err" || fail "--width $w: $(cat "$T/err")"
  [ ! -e "$T/w.png" ] || fail "--width $w: wrote output"
done
echo "fploc-map CLI checks passed"
