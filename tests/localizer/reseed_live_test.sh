#!/usr/bin/env bash
# The optimizer's re-seed of a LOST matcher across processes (FPLOC_RESEED, the optimizer node's `reseed` output to
# the matcher node's `reseed` input), inside scripts/netns-run: `fploc launch` runs segmenter -> features ->
# matcher -> optimizer -> pose loggers over real LCM, with no relocalizer; lcm-logplayer plays a simulated room;
# the matcher waits for its initial pose (sent before the log plays); 4 s into the log an operator's pose 50 m off
# (`fploc node initial-pose 40 40 0 --force`: far outside the plan it is refused without) throws the matcher off the plan, and it goes LOST. The optimizer's dead reckoning still knows where the robot is: with the re-seed wired, the matcher
# is started again at the optimizer's fit and every frame from 1 s after the wrong pose lies on the ground truth;
# without it (the same graph, the two ports unconnected), the matcher stays lost to the end.
source "$(dirname "${BASH_SOURCE[0]}")/../support/netns_test.sh"
ROOT="${FPLOC_ROOT:?}"
require_exes fploc-sim fploc-launch fploc-node fploc-segmenter fploc-features fploc-matcher fploc-optimizer fploc-pose-logger
"$B/fploc-sim" --scenario room-small-loop-fast --seed 5 --duration 10 --out "$T/log.lcm" --gt "$T/gt.tum" 2> "$T/sim.txt"
read -r X Y YAW_DEG < <(gt_start_pose "$T/gt.tum")
PLAN="$ROOT/data/plans/room.json"

run() {  # run NAME WIRED(0|1): the graph, the log played at half speed, the wrong pose sent 8 s (4 s of log) in
  local d="$T/$1" ro="" ri=""
  mkdir -p "$d"
  if [ "$2" = 1 ]; then
    ro='output { port: "reseed" channel: "FPLOC_RESEED" }'
    ri='input { port: "reseed" channel: "FPLOC_RESEED" }'
  fi
  cat > "$d/g.pbtxt" <<G
name: "reseed-live-test"
lcm_url: "$URL"
shutdown_timeout_s: 3
node { name: "log" executable: "lcm-logplayer" disabled: true
       output { port: "scan" channel: "OS1_SCAN" } output { port: "imu" channel: "OS1_IMU" } }
node { name: "segmenter" executable: "fploc-segmenter" input { port: "scan" channel: "OS1_SCAN" }
       input { port: "imu" channel: "OS1_IMU" } output { port: "segments" channel: "FPLOC_SEGMENTS" } segmenter {} }
node { name: "features" executable: "fploc-features" input { port: "segments" channel: "FPLOC_SEGMENTS" }
       output { port: "features" channel: "FPLOC_FEATURES" } features {} }
node { name: "matcher" executable: "fploc-matcher" input { port: "features" channel: "FPLOC_FEATURES" }
       input { port: "imu" channel: "OS1_IMU" } input { port: "initial_pose" channel: "FPLOC_INITIAL_POSE" } $ri
       output { port: "frame_pose" channel: "FPLOC_FRAME_POSE" }
       matcher { plan { file: "$PLAN" } wait_for_initial_pose: true initial_search_m: 0.3 } }
node { name: "optimizer" executable: "fploc-optimizer" input { port: "features" channel: "FPLOC_FEATURES" }
       input { port: "frame_pose" channel: "FPLOC_FRAME_POSE" } input { port: "imu" channel: "OS1_IMU" }
       output { port: "pose" channel: "FPLOC_POSE" } $ro optimizer { plan { file: "$PLAN" } } }
node { name: "wo_logger" executable: "fploc-pose-logger" input { port: "pose" channel: "FPLOC_POSE" }
       pose_logger { file: "$d/wo.tum" } }
node { name: "sfr_logger" executable: "fploc-pose-logger" input { port: "frame_pose" channel: "FPLOC_FRAME_POSE" }
       input { port: "pose" channel: "" } pose_logger { file: "$d/sfr.tum" } }
G
  "$B/fploc-launch" "$d/g.pbtxt" --check > "$d/check.txt" 2>&1 || { cat "$d/check.txt"; exit 1; }
  "$B/fploc-launch" "$d/g.pbtxt" > "$d/launch.txt" 2>&1 & pids+=($!)
  local lp=$!
  sleep 3  # nodes up, the maps loaded
  "$B/fploc-node" initial-pose "$X" "$Y" "$YAW_DEG" --graph "$d/g.pbtxt" 2> "$d/ip.txt" || { cat "$d/ip.txt"; exit 1; }
  sleep 0.5
  lcm-logplayer --lcm-url="$URL" -s 0.5 "$T/log.lcm" > "$d/player.txt" 2>&1 & pids+=($!)
  local pp=$!
  sleep 8
  "$B/fploc-node" initial-pose 40 40 0 --graph "$d/g.pbtxt" --force --no-wait 2>> "$d/ip.txt" || { cat "$d/ip.txt"; exit 1; }
  wait "$pp" || { echo "lcm-logplayer failed:"; cat "$d/player.txt"; exit 1; }
  sleep 1.5
  kill -INT "$lp"
  wait "$lp" || true
  pids=()
  awk '/LOST|re-seed/ && n++ < 4' "$d/launch.txt" | cut -c1-160
}

# score NAME TRACK -> "frames_after bad_after scans_after first_off_s": the wrong pose's time is the first matcher
# frame (FPLOC_FRAME_POSE, sfr.tum) > 1 m off; the TRACK's frames from 1 s after it, how many of them are > 5 cm from
# the ground truth, and how many scans the log has from then on (the pose logger writes LOST and POOR frames at the
# pose they carry; a frame missing is not a good frame).
score() {
  python3 - "$T/gt.tum" "$T/$1/sfr.tum" "$T/$1/$2.tum" <<'PY'
import bisect, math, sys
rd = lambda p: [list(map(float, l.split())) for l in open(p) if l.strip()]
g, sfr, e = rd(sys.argv[1]), rd(sys.argv[2]), rd(sys.argv[3])
t = [r[0] for r in g]
def err(r):
    i = min(range(max(0, bisect.bisect_left(t, r[0]) - 1), min(len(g), bisect.bisect_left(t, r[0]) + 1)), key=lambda k: abs(t[k] - r[0]))
    return math.dist(r[1:3], g[i][1:3])
off = [r[0] for r in sfr if err(r) > 1.0]
if not off:
    print(0, 0, 0, -1); sys.exit()
after = [r for r in e if r[0] >= off[0] + 1.0]
print(len(after), sum(1 for r in after if err(r) > 0.05), sum(1 for x in t if x >= off[0] + 1.0), round(off[0] - t[0], 1))
PY
}

fail=0
echo "--- re-seed wired"
run wired 1
grep -q "re-seeded at" "$T/wired/launch.txt" || { echo "FAIL: the optimizer made no re-seed"; fail=1; }
for k in sfr wo; do
  read -r n bad scans at < <(score wired $k)
  echo "wired $k: wrong pose taken at $at s; $n frames of $scans scans from 1 s later, $bad of them > 5 cm off"
  python3 -c "import sys; sys.exit(0 if 0 <= $at <= 6.5 and $scans >= 20 and $n >= 0.8 * $scans and $bad == 0 else 1)" ||
    { echo "FAIL: wired $k"; fail=1; }
done
echo "--- re-seed not wired"
run unwired 0
grep -q "re-seeded at" "$T/unwired/launch.txt" && { echo "FAIL: a re-seed with the output unconnected"; fail=1; }
read -r n bad scans at < <(score unwired sfr)
echo "unwired sfr: wrong pose taken at $at s; $n frames of $scans scans from 1 s later, $bad of them > 5 cm off"
python3 -c "import sys; sys.exit(0 if 0 <= $at and $scans >= 20 and $n >= 0.8 * $scans and $bad >= 0.9 * $n else 1)" ||
  { echo "FAIL: without the re-seed the matcher should stay lost"; fail=1; }
if [ $fail -ne 0 ]; then
  for r in wired unwired; do
    echo "--- $r: initial poses, launch log (last 20 lines)" >&2
    cat "$T/$r/ip.txt" >&2
    tail -20 "$T/$r/launch.txt" >&2
  done
  exit 1
fi
echo "re-seed across processes: passed"
