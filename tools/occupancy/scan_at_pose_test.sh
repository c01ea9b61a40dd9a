#!/bin/sh
# fploc occupancy --png --pose X,Y,YAW --scan LOG: one scan of a log drawn at a candidate start pose. On Radish intel
# (its map from the first half, the log from scan 455), the first scan at its reference pose puts most returns within
# 0.1 m of a wall, the same scan 1 m and 20 degrees off few; the picture grows to hold the returns; bad input is refused.
set -e
OCC="$1"
IMPORT="$2"
LOG="$FPLOC_SHARED_DIR/data/recordings/radish/intel-corrected.log.gz"
if [ ! -f "$LOG" ]; then echo "SKIP: $LOG absent (shared data)"; exit 0; fi
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; cat "$T/err" 2>/dev/null; exit 1; }
"$IMPORT" "$LOG" --out "$T/rest.lcm" --tum "$T/ref.tum" --map "$T/map" --begin 0.5 --map-begin 0 --map-end 0.5 \
  --end 0.52 > /dev/null 2>&1
set -- $(python3 -c "import math, sys; l=[v for v in open(sys.argv[1]) if v[0]!='#'][0].split(); print(l[1], l[2], 2 * math.atan2(float(l[6]), float(l[7])))" "$T/ref.tum")
X=$1 Y=$2 YAW=$3
"$OCC" "$T/map/map.yaml" --png "$T/at.png" --pose "$X,$Y,$YAW" --scan "$T/rest.lcm" --json > "$T/at.json" 2> "$T/err" || fail "right pose"
grep -q "scan 0 of LASER_SCAN at 0.000 s" "$T/err" || fail "scan not named"
grep -q -- "--set grid2d.initial_pose.x=" "$T/err" || fail "no --set line"
python3 - "$T" "$X" "$Y" "$YAW" <<'PY'
import json, math, sys
d = sys.argv[1]
j = json.load(open(f"{d}/at.json"))["scan"]
print("right pose:", j["text"])
assert j["returns"] > 50 and j["near_walls_share"] > 0.8, j
PY
X2=$(python3 -c "print($X + 1)")
YAW2=$(python3 -c "print($YAW + 0.35)")
"$OCC" "$T/map/map.yaml" --png "$T/off.png" --pose "$X2,$Y,$YAW2" --scan "$T/rest.lcm" --json > "$T/off.json" 2> "$T/err" || fail "off pose"
python3 - "$T" <<'PY'
import json, sys
j = json.load(open(f"{sys.argv[1]}/off.json"))["scan"]
print("1 m, 20 deg off:", j["text"])
assert j["near_walls_share"] < 0.5, j
PY
# A pose far outside the map: the picture grows to hold it and its returns (grey around the map).
"$OCC" "$T/map/map.yaml" --png "$T/far.png" --pose "-100,0,0" --scan "$T/rest.lcm" 2> "$T/err" || fail "far pose"
grep -q "showing x -10[0-9]" "$T/err" || fail "picture not grown to the pose"
# --at: a later scan; past the end: an error naming the last scan's time.
"$OCC" "$T/map/map.yaml" --png "$T/at2.png" --pose "$X,$Y,$YAW" --scan "$T/rest.lcm" --at 5 2> "$T/err" || fail "--at 5"
grep -q "scan [1-9][0-9]* of LASER_SCAN at [5-9]\." "$T/err" || fail "--at 5: not a scan at 5 s or later"
if "$OCC" "$T/map/map.yaml" --png "$T/x.png" --pose "$X,$Y,$YAW" --scan "$T/rest.lcm" --at 100000 2> "$T/err"; then fail "--at past the end accepted"; fi
grep -q "is after its last LASER_SCAN scan" "$T/err" || fail "--at past the end: no reason"
if "$OCC" "$T/map/map.yaml" --png "$T/x.png" --pose "$X,$Y" 2> "$T/err"; then fail "two numbers accepted"; fi
grep -q "expected X,Y,YAW" "$T/err" || fail "bad --pose: no reason"
if "$OCC" "$T/map/map.yaml" --png "$T/x.png" --pose "$X,$Y,$YAW" --scan "$T/rest.lcm" --scan-channel NOPE 2> "$T/err"; then fail "no such channel accepted"; fi
grep -q "no NOPE event (the log holds LASER_SCAN" "$T/err" || fail "missing channel: not named"
if "$OCC" "$T/map/map.yaml" --png "$T/x.png" --scan "$T/rest.lcm" 2> "$T/err"; then fail "--scan without --pose accepted"; fi
# A log whose first event's data length is damaged (0x7fffffff): one error naming the file and the event's byte
# offset (liblcm alone would allocate and read 2 GB), not a crash and not "no LASER_SCAN event".
python3 - "$T/rest.lcm" "$T/damaged.lcm" <<'PY'
import sys
b = bytearray(open(sys.argv[1], 'rb').read()[:4096])
b[24:28] = (0x7fffffff).to_bytes(4, 'big')
open(sys.argv[2], 'wb').write(b)
PY
if "$OCC" "$T/map/map.yaml" --png "$T/x.png" --pose "$X,$Y,$YAW" --scan "$T/damaged.lcm" 2> "$T/err"; then fail "a damaged log accepted"; fi
grep -q -- "--scan $T/damaged.lcm: event 1 at byte 0" "$T/err" || fail "damaged log: not named with the event's offset"
echo OK
