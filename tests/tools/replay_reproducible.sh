#!/usr/bin/env bash
# A short simulated sequence through the whole pipeline (graphs/paper.pbtxt: segmenter, features, matcher,
# optimizer, odometry, pose loggers) with `fploc replay`, twice: the trajectories must be byte-identical,
# complete, and on the ground truth.
set -euo pipefail
BIN="${FPLOC_BUILD_DIR:?}/bin"
ROOT="${FPLOC_ROOT:?}"
W="$(mktemp -d "${TMPDIR:-/tmp}/fploc-replay-repro-XXXXXX")"
trap 'rm -rf "$W"' EXIT
"$BIN/fploc-sim" --scenario room-small-loop-fast --seed 3 --duration 4 --out "$W/log.lcm" --gt "$W/gt.tum" 2>"$W/sim.err"
read -r X Y YAW < <(python3 -c "
import math
r=list(map(float,open('$W/gt.tum').readline().split()))
qx,qy,qz,qw=r[4:8]
print(repr(r[1]),repr(r[2]),repr(math.atan2(2*(qw*qz+qx*qy),1-2*(qy*qy+qz*qz))))")
source "$ROOT/tests/support/paper_replay.sh"
# Run b records two channels with a regular expression; the wrong-plan run below gives a comma list, which matches
# no channel: the replay must say so (it wrote an empty file without a word).
for run in a b; do
  rec=()
  [ "$run" = b ] && rec=(--record "$W/b-rec.lcm" --record-channels 'FPLOC_POSE|FPLOC_FRAME_POSE')
  paper_replay "$W/log.lcm" "$W/$run" "${rec[@]}" \
    --set matcher.initial_pose.x="$X" --set matcher.initial_pose.y="$Y" --set matcher.initial_pose.yaw="$YAW" \
    --set odometry.initial_pose.x="$X" --set odometry.initial_pose.y="$Y" --set odometry.initial_pose.yaw="$YAW" \
    --set odometry_map.initial_pose.x="$X" --set odometry_map.initial_pose.y="$Y" --set odometry_map.initial_pose.yaw="$YAW"
done
frames=$(grep -c . "$W/gt.tum")
fail=0
for k in sfr wo odom odom_map; do
  if ! cmp -s "$W/a-$k.tum" "$W/b-$k.tum"; then
    echo "FAIL: $k trajectories of two replays differ" >&2
    diff "$W/a-$k.tum" "$W/b-$k.tum" | head -5 >&2
    fail=1
  fi
  n=$(grep -c . "$W/a-$k.tum" || true)
  if [ "$n" -ne "$frames" ]; then
    echo "FAIL: $k has $n poses for $frames scans" >&2
    fail=1
  fi
done
for k in sfr wo; do
  ate=$("$BIN/fploc-eval" --gt "$W/gt.tum" --est "$W/a-$k.tum" --json 2>/dev/null | python3 -c "import json,sys;print(json.load(sys.stdin)['ate_rmse_m'])")
  echo "$k: $frames poses, byte-identical, ATE $ate m"
  python3 -c "import sys; sys.exit(0 if $ate < 0.02 else 1)" || { echo "FAIL: $k ATE $ate m >= 0.02 m" >&2; fail=1; }
done
# The wrong floor plan (the corridor's) for the room sequence: the matcher must report POOR, then LOST
# (in the frame poses and as a node error), and hold its prediction instead of jumping.
"$BIN/fploc-replay" --graph "$ROOT/graphs/paper.pbtxt" --log "$W/log.lcm" --json \
  --set matcher.plan.file="$ROOT/data/plans/corridor.json" --set optimizer.plan.file="$ROOT/data/plans/corridor.json" \
  --set matcher.initial_pose.x="$X" --set matcher.initial_pose.y="$Y" --set matcher.initial_pose.yaw="$YAW" \
  --set sfr_logger.file="$W/bad-sfr.tum" --set wo_logger.file="$W/bad-wo.tum" --set odom_logger.file="$W/bad-odom.tum" \
  --set odom_map_logger.file="$W/bad-odom_map.tum" --record "$W/bad-rec.lcm" --record-channels 'FPLOC_POSE,FPLOC_FRAME_POSE' \
  >"$W/bad.json" 2>"$W/bad.err" || { cat "$W/bad.err" >&2; exit 1; }
if grep -q "record" "$W/b.err" || [ ! -s "$W/b-rec.lcm" ]; then
  echo "FAIL: --record-channels 'FPLOC_POSE|FPLOC_FRAME_POSE' recorded nothing or warned" >&2; cat "$W/b.err" >&2; fail=1
fi
grep -q "warning: --record $W/bad-rec.lcm is empty: --record-channels 'FPLOC_POSE,FPLOC_FRAME_POSE' matched none of the channels of the run (.*FPLOC_FRAME_POSE.*); it is a regular expression" "$W/bad.err" \
  || { echo "FAIL: no warning for a --record-channels that matched nothing" >&2; cat "$W/bad.err" >&2; fail=1; }
python3 - "$W/bad.json" "$W/bad-sfr.tum" <<'PY' || fail=1
import json, math, sys
rep = json.loads(open(sys.argv[1]).read().strip().splitlines()[-1])
m = [n for n in rep["nodes"] if n["name"] == "matcher"][0]
poses = [list(map(float, l.split())) for l in open(sys.argv[2]) if l.strip()]
jump = max(math.dist(a[1:3], b[1:3]) for a, b in zip(poses, poses[1:]))
print(f"wrong plan: matcher errors {m['errors']}, last '{m['last_error']}', largest step {jump:.3f} m over {len(poses)} poses")
assert m["errors"] >= 1 and "LOST" in m["last_error"], m
assert jump < 0.2, jump
PY
exit $fail
