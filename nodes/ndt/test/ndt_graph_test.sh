#!/usr/bin/env bash
# fploc-ndt through graphs/ndt.pbtxt (segmenter -> ndt -> pose logger) with `fploc replay` (memq://, one
# process, no network) on 5 s of a simulated room sequence: one pose per scan, tracked to within 5 cm (ATE) of
# the ground truth, statuses and covariances logged and scored by `fploc eval --uncertainty`; a graph
# without the required initial pose fails with one clear error.
set -euo pipefail
BIN="${FPLOC_BUILD_DIR:?}/bin"
ROOT="${FPLOC_ROOT:?}"
for exe in fploc-sim fploc-replay fploc-eval fploc-ndt fploc-segmenter fploc-pose-logger; do
  [ -x "$BIN/$exe" ] || { echo "missing $BIN/$exe (build it first)"; exit 1; }
done
T="$(mktemp -d "${TMPDIR:-/tmp}/fploc-ndt-graph-XXXXXX")"
trap 'rm -rf "$T"' EXIT
"$BIN/fploc-sim" --scenario room-small-loop-medium --seed 4 --duration 5 --out "$T/log.lcm" --gt "$T/gt.tum" 2> "$T/sim.txt"
read -r X Y YAW < <(python3 -c "
import math,sys
r=[float(v) for v in open('$T/gt.tum').readline().split()]
qx,qy,qz,qw=r[4:8]
print(r[1], r[2], math.atan2(2*(qw*qz+qx*qy), 1-2*(qy*qy+qz*qz)))")
SETS=(--set "ndt.initial_pose.x=$X" --set "ndt.initial_pose.y=$Y" --set "ndt.initial_pose.yaw=$YAW"
      --set "pose_logger.file=$T/ndt.tum" --set "pose_logger.uncertainty_file=$T/ndt.unc"
      --set "ndt.stats_file=$T/stats.json")
"$BIN/fploc-replay" --graph "$ROOT/graphs/ndt.pbtxt" --log "$T/log.lcm" --json "${SETS[@]}" > "$T/replay.json" 2> "$T/replay.txt" \
  || { cat "$T/replay.txt"; echo "FAIL: replay"; exit 1; }
grep "\[ndt\]" "$T/replay.txt" || true
"$BIN/fploc-eval" --gt "$T/gt.tum" --est "$T/ndt.tum" --uncertainty "$T/ndt.unc" --json > "$T/eval.json"
python3 - "$T" <<'PY'
import json, sys
T = sys.argv[1]
e = json.load(open(f"{T}/eval.json"))
s = json.load(open(f"{T}/stats.json"))
frames = sum(1 for l in open(f"{T}/gt.tum") if l.strip() and not l.startswith("#"))
print("ndt through graphs/ndt.pbtxt:", {k: e[k] for k in ("poses", "ate_rmse_m", "ate_max_m", "nees_median", "ok_poses", "false_ok_poses")},
      "stats", {k: s[k] for k in ("scans", "ok", "poor", "lost", "cpu_us_per_scan_mean", "iterations_per_scan")})
ok = True
def check(c, msg):
    global ok
    if not c:
        print("FAIL:", msg); ok = False
check(e["poses"] == frames and s["scans"] == frames, f"one pose per scan ({e['poses']} poses, {s['scans']} scans, {frames} frames)")
check(e["ate_rmse_m"] < 0.05 and e["ate_max_m"] < 0.15, f"tracking: ATE {e['ate_rmse_m']} m, max {e['ate_max_m']} m")
check(s["lost"] == 0, "no LOST scan")
check(e["uncertainty_poses"] == e["poses"] and e["nees_poses"] > 0.9 * e["poses"], "covariance logged for every pose")
check(e["nees_median"] is not None and e["nees_median"] > 0, "NEES computed")
check(e["ok_poses"] > 0 and e["false_ok_poses"] == 0, "OK poses, none of them false")
sys.exit(0 if ok else 1)
PY
# Bad input: no initial pose -> one clear error naming the option.
sed 's/ initial_pose { x: 5.7976 y: 3.2267 yaw: -1.4433 }//' "$ROOT/graphs/ndt.pbtxt" > "$T/noinit.pbtxt"
sed -i "s|\.\./data/plans/room.json|$ROOT/data/plans/room.json|" "$T/noinit.pbtxt"
if "$BIN/fploc-replay" --graph "$T/noinit.pbtxt" --log "$T/log.lcm" --set "pose_logger.file=$T/x.tum" > /dev/null 2> "$T/err.txt"; then
  echo "FAIL: a graph without ndt.initial_pose ran"; exit 1
fi
grep -q "ndt.initial_pose" "$T/err.txt" || { cat "$T/err.txt"; echo "FAIL: the error does not name ndt.initial_pose"; exit 1; }
echo "bad input: $(grep -m1 "ndt.initial_pose" "$T/err.txt")"
