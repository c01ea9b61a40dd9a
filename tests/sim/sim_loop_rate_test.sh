#!/usr/bin/env bash
# The looping simulator keeps its pace: fploc-sim-sensor with loop=true on a 2.5 s pass of a scenario runs
# for ~3 passes; the ground truth (one per frame) and the scans decoded by fploc-os1-driver must arrive at
# 10 Hz of wall time with sensor times advancing 0.1 s per frame across the restarts (the defect was a
# clock that added the loop's length again at each restart and flooded the pipeline).
# Runs inside scripts/netns-run (FPLOC_BUILD_DIR set by fploc_add_netns_test).
source "$(dirname "${BASH_SOURCE[0]}")/../support/netns_test.sh"
require_exes fploc-sim-sensor fploc-os1-driver

lcm-logger --lcm-url="$URL" "$T/run.lcm" > "$T/logger.txt" 2>&1 & pids+=($!)
"$B/fploc-sim-sensor" --lcm-url "$URL" --set scenario=room-small-loop-fast --set seed=2 --set loop=true \
  --set duration_s=2.5 --set clutter=false --set lidar_port=17512 --set imu_port=17513 \
  --set metadata_out="$T/meta.json" > "$T/sim.txt" 2>&1 & pids+=($!)
for _ in $(seq 100); do [ -s "$T/meta.json" ] && break; sleep 0.1; done
[ -s "$T/meta.json" ] || { echo "sim-sensor wrote no metadata"; cat "$T/sim.txt"; exit 1; }
"$B/fploc-os1-driver" --lcm-url "$URL" --set metadata="$T/meta.json" --set lidar_port=17512 > "$T/os1.txt" 2>&1 & pids+=($!)
sleep 8.5
kill -INT "${pids[2]}" "${pids[1]}"
sleep 0.5
kill -INT "${pids[0]}"
wait "${pids[0]}" || true
cat "$T/sim.txt" "$T/os1.txt"
python3 "$(dirname "$0")/check_loop_rate.py" "$T/run.lcm" 2.5
