#!/usr/bin/env bash
# Runs inside scripts/netns-run (FPLOC_BUILD_DIR set by fploc_add_netns_test). Optional argument: a beam
# pattern (fploc sim --beams; e.g. vlp16: 16-beam OS-1 packets with a 16-beam metadata).
source "$(dirname "${BASH_SOURCE[0]}")/../support/netns_test.sh"
require_exes fploc-sim-sensor fploc-os1-driver fploc-imu-driver fploc-sim
SCEN=room-small-loop-fast
SEED=3
BEAMS="${1:-}"
SIM_BEAMS=(); REF_BEAMS=()
if [ -n "$BEAMS" ]; then SIM_BEAMS=(--set "beams=$BEAMS"); REF_BEAMS=(--beams "$BEAMS"); fi

lcm-logger --lcm-url="$URL" "$T/drv.lcm" > "$T/logger.txt" 2>&1 & pids+=($!)
"$B/fploc-sim-sensor" --lcm-url "$URL" --set scenario=$SCEN --set seed=$SEED --set lidar_port=17502 \
  --set imu_port=17503 --set metadata_out="$T/meta.json" "${SIM_BEAMS[@]}" > "$T/sim.txt" 2>&1 & pids+=($!)
for _ in $(seq 100); do [ -s "$T/meta.json" ] && break; sleep 0.1; done
[ -s "$T/meta.json" ] || { echo "sim-sensor wrote no metadata"; cat "$T/sim.txt"; exit 1; }
sleep 0.2
"$B/fploc-os1-driver" --lcm-url "$URL" --set metadata="$T/meta.json" --set lidar_port=17502 > "$T/os1.txt" 2>&1 & pids+=($!)
"$B/fploc-imu-driver" --lcm-url "$URL" --set imu_port=17503 > "$T/imu.txt" 2>&1 & pids+=($!)
sleep 6
kill -INT "${pids[2]}" "${pids[3]}" "${pids[1]}"
sleep 0.5
kill -INT "${pids[0]}"
wait "${pids[2]}" "${pids[3]}" || { echo "driver exited non-zero"; cat "$T/os1.txt" "$T/imu.txt"; exit 1; }
sleep 0.3
cat "$T/sim.txt" "$T/os1.txt" "$T/imu.txt"
# The reference: the same scenario and seed written directly as an LCM log.
"$B/fploc-sim" --scenario $SCEN --seed $SEED "${REF_BEAMS[@]}" --out "$T/ref.lcm" --gt "$T/ref.tum" --duration 15 2> "$T/ref.txt"
if [ -n "$BEAMS" ]; then
  python3 -c "import json,sys; d=json.load(open(sys.argv[1])); n=d['data_format']['pixels_per_column']; assert n == int(sys.argv[2]), n; print('metadata: pixels_per_column', n)" "$T/meta.json" "${2:?expected beam count}"
fi
python3 "$(dirname "$0")/check_sim_log.py" "$T/drv.lcm" "$T/ref.lcm"
