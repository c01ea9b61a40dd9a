#!/usr/bin/env bash
# A robot rides a lift from the ground floor to the first floor of a two-floor building, live:
# fploc launch (tests/floors/lift.pbtxt: graphs/replay.pbtxt's pipeline with the building as every node's plan,
# and the dashboard) + lcm-logplayer, in a
# private network namespace (scripts/netns-run). The log is made by make_lift_log from two simulated
# runs (the demo room as the ground floor, the demo corridor as the first floor, moved so that the
# corridor run starts where the room run ends; a 3.3 m ride with the IMU's vertical motion between).
# Checked on the final poses (FPLOC_POSE as the graph's pose_logger wrote them, with their floors; an
# lcm-logger beside it lost some of the burst of final poses at the floor switch on a loaded machine):
#  - the pose's floor (pose_t.floor) is 'first' within 2 s of the lift's arrival,
#  - no pose on the wrong floor from 3 s after the arrival (and none on 'first' before the ride),
#  - horizontal ATE over the 10 s after the arrival <= 5 cm;
# and the matcher said why it switched (its stderr).
set -euo pipefail
BIN="${FPLOC_BUILD_DIR:?}/bin"
ROOT="${FPLOC_ROOT:?}"
T="$(mktemp -d /tmp/fploc-floor-lift-XXXXXX)"
[ -n "${FPLOC_KEEP:-}" ] && echo "keeping $T" || trap 'rm -rf "$T"' EXIT
URL='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304'

"$BIN/fploc-sim" --plan "$ROOT/data/plans/room.json" --scenario room-small-loop-fast --seed 5 --out "$T/a.lcm" --gt "$T/a.tum" 2> "$T/sim-a.log"
"$BIN/fploc-sim" --plan "$ROOT/data/plans/corridor.json" --scenario corridor-loop-fast --seed 6 --duration 16 --out "$T/b.lcm" --gt "$T/b.tum" 2> "$T/sim-b.log"
"$BIN/make_lift_log" --a "$T/a.lcm" --a-gt "$T/a.tum" --b "$T/b.lcm" --b-gt "$T/b.tum" --b-plan "$ROOT/data/plans/corridor.json" \
  --height 3.3 --b-plan-out "$T/first.json" --out "$T/lift.lcm" --gt "$T/gt.tum" --floors "$T/floors.txt"
read -r _ _ LX LY < <(grep '^# lift' "$T/floors.txt")
cp "$ROOT/data/plans/room.json" "$T/ground.json"
cat > "$T/building.pbtxt" <<PB
name: "lift-test"
floor { name: "ground" plan { file: "ground.json" } elevation_m: 0 ceiling_height_m: 3.0 }
floor { name: "first" plan { file: "first.json" } elevation_m: 3.3 ceiling_height_m: 3.0 }
connection { name: "lift" kind: LIFT from_floor: "ground" to_floor: "first"
  polygon { x: $(python3 -c "print($LX-1)") y: $(python3 -c "print($LY-1)") }
  polygon { x: $(python3 -c "print($LX+1)") y: $(python3 -c "print($LY-1)") }
  polygon { x: $(python3 -c "print($LX+1)") y: $(python3 -c "print($LY+1)") }
  polygon { x: $(python3 -c "print($LX-1)") y: $(python3 -c "print($LY+1)") } }
PB
read -r X Y YAW < <(python3 -c "
import math
t,x,y,z,qx,qy,qz,qw=map(float,open('$T/gt.tum').readline().split())
print(x,y,math.atan2(2*(qw*qz+qx*qy),1-2*(qy*qy+qz*qz)))")
SETS=(--set matcher.initial_pose.x="$X" --set matcher.initial_pose.y="$Y" --set matcher.initial_pose.yaw="$YAW")
for n in matcher relocalizer optimizer dashboard; do SETS+=(--set "$n.plan.file=$T/building.pbtxt"); done
# The ANNF of both floors once, before the live run (the cache is shared by the nodes).
export FPLOC_ANNF_CACHE="$T/annf"

# FPLOC_FLOOR_NO_IMU=1: the matcher's imu input disconnected: the floor changes from the plan no longer
# matching in the lift area alone (the other floors' plans tried there).
GRAPH="$ROOT/tests/floors/lift.pbtxt"
if [ "${FPLOC_FLOOR_NO_IMU:-}" = "1" ]; then
  GRAPH="$T/lift-noimu.pbtxt"  # every relative path of lift.pbtxt is set below
  # (an input left out of a graph takes its default channel: an empty channel disconnects it)
  sed '/name: "matcher"/,/^}/s/port: "imu" channel: "OS1_IMU"/port: "imu" channel: ""/' "$ROOT/tests/floors/lift.pbtxt" > "$GRAPH"
  grep -q 'port: "imu" channel: ""' <(sed -n '/name: "matcher"/,/^}/p' "$GRAPH") || { echo "FAIL: imu input still connected"; exit 1; }
fi
"$BIN/fploc-launch" "$GRAPH" --set pose_logger.file="$T/live.tum" --set pose_logger.floor_file="$T/live.tum.floors" \
  "${SETS[@]}" 2> "$T/launch.log" &
LP=$!
for _ in $(seq 300); do grep -q "graph 'floors-lift' running" "$T/launch.log" && break; sleep 0.1; done
sleep 2.5
# FPLOC_FLOOR_SCREENSHOT=OUT.png: the dashboard 4 s after the lift's arrival (headless chromium, as
# tests/dashboard/screenshot.mjs; FPLOC_SELECT_FLOOR picks the floor shown).
SHOT=""
if [ -n "${FPLOC_FLOOR_SCREENSHOT:-}" ] && [ -d "$ROOT/tests/dashboard/node_modules/playwright-core" ]; then
  WAIT_MS=$(python3 -c "
import struct
d=open('$T/lift.lcm','rb').read(28); t0=struct.unpack('>IqqII',d)[2]
a=[l.split()[2] for l in open('$T/floors.txt') if l.startswith('# arrival')][0]
print(int((int(a)-t0)/1000)+4000)")
  (cd "$ROOT/tests/dashboard" && node screenshot.mjs http://127.0.0.1:8080/ "$FPLOC_FLOOR_SCREENSHOT" "$WAIT_MS") &
  SHOT=$!
fi
lcm-logplayer --lcm-url="$URL" "$T/lift.lcm"
[ -n "$SHOT" ] && { wait "$SHOT" || echo "screenshot failed"; }
sleep 5
kill -INT "$LP"
wait "$LP" || { echo "FAIL: launcher exit code $?"; tail -n 30 "$T/launch.log"; exit 1; }
grep -E "floor '|lift '" "$T/launch.log" | head -n 8 || true

python3 "$ROOT/tests/floors/score_floors.py" "$T/live.tum" "$T/gt.tum" "$T/floors.txt" "$T/launch.log"
