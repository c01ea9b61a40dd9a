#!/usr/bin/env bash
# The README's demo, live, as a user runs it: graphs/demo.pbtxt under `fploc launch` (simulated OS-1-64
# sending real UDP packets -> drivers -> segmenter -> features -> matcher -> optimizer -> pose logger, plus
# the dashboard), then `fploc eval` of the logged poses against the simulator's ground truth.
# With --swap, modules are swapped during the run while the rest keeps going: the segmenter for the PCL
# RANSAC one, then the matcher (a new process with another ANNF look-up, re-seeded by the relocalizer).
# Runs inside a private network namespace (ctest: fploc_add_netns_test).
set -euo pipefail
SWAP="${1:-}"
BIN="${FPLOC_BUILD_DIR:?}/bin"
ROOT="${FPLOC_ROOT:?}"
DUR="${DEMO_DURATION_S:-40}"
T="$(mktemp -d /tmp/fploc-demo-live-XXXXXX)"
trap 'rm -rf "$T"' EXIT
if [ "$SWAP" = "--swap" ]; then
  (sleep 12 && "$BIN/fploc-node" restart segmenter --exe fploc-segmenter-ransac --graph "$ROOT/graphs/demo.pbtxt" &&
   sleep 4 && "$BIN/fploc-node" restart matcher --set lookup=annf-paper --graph "$ROOT/graphs/demo.pbtxt") \
    > "$T/swap.log" 2>&1 &
  SW=$!
fi
set +e
"$BIN/fploc-launch" "$ROOT/graphs/demo.pbtxt" --duration "$DUR" \
  --set sim.metadata_out="$T/os1.json" --set os1_driver.metadata="$T/os1.json" \
  --set pose_logger.file="$T/est.tum" --set gt_logger.file="$T/gt.tum" --set dashboard.port=18080 \
  2> "$T/launch.log"
rc=$?
set -e
if [ "$SWAP" = "--swap" ]; then
  wait "$SW" || { echo "FAIL: a module swap failed"; cat "$T/swap.log"; exit 1; }
  cat "$T/swap.log"
  grep -E "control:|relocalizer\]|waiting for a pose" "$T/launch.log"
  grep -q "NOT_INITIALISED): found" "$T/launch.log" || { echo "FAIL: the new matcher was not re-seeded"; exit 1; }
fi
echo "--- launcher log (tail)"; tail -n 25 "$T/launch.log"
[ "$rc" -eq 0 ] || { echo "FAIL: fploc launch exited with $rc"; exit 1; }
if grep -E "restarting|hung|dead" "$T/launch.log"; then echo "FAIL: a node failed during the demo"; exit 1; fi
"$BIN/fploc-eval" --gt "$T/gt.tum" --est "$T/est.tum" --json --plot "$T/demo.svg" > "$T/eval.json"
cat "$T/eval.json"; echo
# The issue's room target (ATE <= 3 cm after windowed optimisation); with the swaps 5 cm: the RANSAC
# segmenter is the less accurate comparison baseline and the matcher hand-over costs a scan or two.
# A swapped matcher misses the scans of its restart (start-up, map load, re-seeding): at most 1 s of them.
MAX_ATE=0.03 MAX_MISSING=2; [ "$SWAP" = "--swap" ] && MAX_ATE=0.05 MAX_MISSING=10
python3 - "$T/eval.json" "$T/gt.tum" "$DUR" "$MAX_ATE" "$MAX_MISSING" <<'PY'
import json, sys
e = json.load(open(sys.argv[1]))
gt = sum(1 for l in open(sys.argv[2]) if l.strip() and not l.startswith('#'))
dur, max_ate, max_missing = float(sys.argv[3]), float(sys.argv[4]), int(sys.argv[5])
print(f"ground truth {gt} scans, {e['poses']} estimated poses associated, ATE rmse {e['ate_rmse_m']:.4f} m, RPE mean {e['rpe_mean_m']:.4f} m")
ok = True
# Every scan the simulator sent becomes a pose: the launcher stops sources first, so the optimizer's
# last window still reaches the pose logger (at most the sweep in flight at the stop is lost).
if gt < 0.8 * 10 * (dur - 3):
    print(f"FAIL: only {gt} ground-truth scans in {dur} s (the simulator should send 10 Hz)"); ok = False
if e['poses'] < gt - max_missing:
    print(f"FAIL: {e['poses']} poses for {gt} scans"); ok = False
if e['ate_rmse_m'] > max_ate:
    print(f"FAIL: ATE above {max_ate} m"); ok = False
sys.exit(0 if ok else 1)
PY
