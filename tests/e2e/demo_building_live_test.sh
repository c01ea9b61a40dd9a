#!/usr/bin/env bash
# graphs/demo-building.pbtxt live under `fploc launch` (the simulated OS-1-64 on its journey through the
# two-floor demo building, real UDP packets, the localizer loading every floor, the dashboard), for the
# first DEMO_DURATION_S seconds (the ground floor, towards the ramp): poses arrive, carry the floor
# ("ground"), and match the simulator's ground truth. Runs inside a private network namespace.
set -euo pipefail
BIN="${FPLOC_BUILD_DIR:?}/bin"
ROOT="${FPLOC_ROOT:?}"
DUR="${DEMO_DURATION_S:-40}"
T="$(mktemp -d /tmp/fploc-demo-building-live-XXXXXX)"
trap 'rm -rf "$T"' EXIT
set +e
"$BIN/fploc-launch" "$ROOT/graphs/demo-building.pbtxt" --duration "$DUR" \
  --set sim.metadata_out="$T/os1.json" --set os1_driver.metadata="$T/os1.json" \
  --set pose_logger.file="$T/est.tum" --set pose_logger.floor_file="$T/est.floors" \
  --set gt_logger.file="$T/gt.tum" --set dashboard.port=18081 2> "$T/launch.log"
rc=$?
set -e
echo "--- launcher log (tail)"; tail -n 25 "$T/launch.log"
[ "$rc" -eq 0 ] || { echo "FAIL: fploc launch exited with $rc"; exit 1; }
if grep -E "restarting|hung|dead" "$T/launch.log"; then echo "FAIL: a node failed during the demo"; exit 1; fi
"$BIN/fploc-eval" --gt "$T/gt.tum" --est "$T/est.tum" --json > "$T/eval.json"
cat "$T/eval.json"; echo
python3 - "$T/eval.json" "$T/gt.tum" "$T/est.floors" "$DUR" <<'PY'
import json, sys
e = json.load(open(sys.argv[1]))
gt = sum(1 for l in open(sys.argv[2]) if l.strip() and not l.startswith('#'))
floors = [l.split()[2] for l in open(sys.argv[3]) if l.strip() and not l.startswith('#')]
dur = float(sys.argv[4])
print(f"ground truth {gt} scans, {e['poses']} poses, ATE rmse {e['ate_rmse_m']:.4f} m, floors {sorted(set(floors))}")
ok = True
if gt < 0.8 * 10 * (dur - 3):
    print(f"FAIL: only {gt} ground-truth scans in {dur} s"); ok = False
if e['poses'] < gt - 2:
    print(f"FAIL: {e['poses']} poses for {gt} scans"); ok = False
if e['ate_rmse_m'] > 0.03:
    print("FAIL: ATE above 0.03 m"); ok = False
if not floors or set(floors) != {"ground"}:
    print(f"FAIL: the poses should all be on the ground floor: {sorted(set(floors))}"); ok = False
sys.exit(0 if ok else 1)
PY
