#!/usr/bin/env bash
# The localization nodes as separate processes over real LCM (inside scripts/netns-run): `fploc launch`
# runs segmenter -> features -> matcher -> optimizer -> pose loggers, the matcher waiting for its initial
# pose; `fploc node initial-pose` sends it; lcm-logplayer plays a simulated sequence. The live
# trajectories must cover the sequence and lie on the ground truth.
source "$(dirname "${BASH_SOURCE[0]}")/../support/netns_test.sh"
ROOT="${FPLOC_ROOT:?}"
"$B/fploc-sim" --scenario room-small-loop-fast --seed 5 --duration 6 --out "$T/log.lcm" --gt "$T/gt.tum" 2> "$T/sim.txt"
read -r X Y YAW_DEG < <(gt_start_pose "$T/gt.tum")
PLAN="$ROOT/data/plans/room.json"
cat > "$T/live.pbtxt" <<G
name: "live-localization-test"
lcm_url: "$URL"
shutdown_timeout_s: 3
node { name: "log" executable: "lcm-logplayer" disabled: true
       output { port: "scan" channel: "OS1_SCAN" } output { port: "imu" channel: "OS1_IMU" } }
node { name: "segmenter" executable: "fploc-segmenter" input { port: "scan" channel: "OS1_SCAN" }
       output { port: "segments" channel: "FPLOC_SEGMENTS" } segmenter {} }
node { name: "features" executable: "fploc-features" input { port: "segments" channel: "FPLOC_SEGMENTS" }
       output { port: "features" channel: "FPLOC_FEATURES" } features {} }
node { name: "matcher" executable: "fploc-matcher" input { port: "features" channel: "FPLOC_FEATURES" }
       input { port: "imu" channel: "OS1_IMU" } input { port: "initial_pose" channel: "FPLOC_INITIAL_POSE" }
       output { port: "frame_pose" channel: "FPLOC_FRAME_POSE" }
       matcher { plan { file: "$PLAN" } wait_for_initial_pose: true initial_search_m: 0.3 } }
node { name: "optimizer" executable: "fploc-optimizer" input { port: "features" channel: "FPLOC_FEATURES" }
       input { port: "frame_pose" channel: "FPLOC_FRAME_POSE" } output { port: "pose" channel: "FPLOC_POSE" }
       output { port: "latest" channel: "FPLOC_POSE_LATEST" } optimizer { plan { file: "$PLAN" } } }
node { name: "wo_logger" executable: "fploc-pose-logger" input { port: "pose" channel: "FPLOC_POSE" }
       pose_logger { file: "$T/wo.tum" } }
node { name: "latest_logger" executable: "fploc-pose-logger" input { port: "pose" channel: "FPLOC_POSE_LATEST" }
       pose_logger { file: "$T/latest.tum" } }
node { name: "sfr_logger" executable: "fploc-pose-logger" input { port: "frame_pose" channel: "FPLOC_FRAME_POSE" }
       input { port: "pose" channel: "" } pose_logger { file: "$T/sfr.tum" } }
G
"$B/fploc-launch" "$T/live.pbtxt" --check > "$T/check.txt" 2>&1 || { cat "$T/check.txt"; exit 1; }
"$B/fploc-launch" "$T/live.pbtxt" > "$T/launch.txt" 2>&1 & pids+=($!)
sleep 3  # nodes up, the matcher loading its map
"$B/fploc-node" initial-pose "$X" "$Y" "$YAW_DEG" --graph "$T/live.pbtxt" 2> "$T/ip.txt"
sleep 0.5
lcm-logplayer --lcm-url="$URL" -s 0.5 "$T/log.lcm" > "$T/player.txt" 2>&1
sleep 1.5
kill -INT "${pids[0]}"
wait "${pids[0]}" || true
pids=()
cat "$T/ip.txt"
frames=$(grep -c . "$T/gt.tum")
fail=0
# Final windowed poses: all but the last second (the optimizer's max_final_delay_s), which becomes final only
# when the optimizer shuts down, at the same time as the logger.
for k in sfr latest wo; do
  n=$(grep -c . "$T/$k.tum" 2>/dev/null || echo 0)
  need=$((frames * 8 / 10))
  [ $k = wo ] && need=$((frames - 25))
  if [ "$n" -lt $need ]; then
    echo "FAIL: live $k has $n poses for $frames scans" >&2; fail=1; continue
  fi
  ate=$("$B/fploc-eval" --gt "$T/gt.tum" --est "$T/$k.tum" --json 2>/dev/null | python3 -c "import json,sys;print(json.load(sys.stdin)['ate_rmse_m'])")
  echo "live $k: $n of $frames scans, ATE $ate m"
  python3 -c "import sys; sys.exit(0 if $ate < 0.02 else 1)" || { echo "FAIL: live $k ATE $ate m" >&2; fail=1; }
done
[ $fail -eq 0 ] || tail -30 "$T/launch.txt" >&2
exit $fail
