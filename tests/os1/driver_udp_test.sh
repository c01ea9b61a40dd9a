#!/usr/bin/env bash
# Runs inside scripts/netns-run (FPLOC_BUILD_DIR, FPLOC_SHARED_DIR set by fploc_add_netns_test).
set -euo pipefail
B="${FPLOC_BUILD_DIR:?}/bin"
D="${FPLOC_SHARED_DIR:?}/data/ouster"
[ -f "$D/OS-1-64_1024x10_fw20.pcap" ] || { echo "no ../shared/data: skipped"; exit 77; }
for exe in fploc-os1-driver fploc-imu-driver fploc-os1-send fploc-os1-decode; do
  [ -x "$B/$exe" ] || { echo "missing $B/$exe (build it first)"; exit 1; }
done
T="$(mktemp -d)"
pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; wait 2>/dev/null || true; rm -rf "$T"; }
trap cleanup EXIT
PCAP="$D/OS-1-64_1024x10_fw20.pcap"
META="$D/OS-1-64_sensor_config_reduced.json"
URL="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608"

lcm-logger --lcm-url="$URL" "$T/log.lcm" > "$T/logger.txt" 2>&1 & pids+=($!)
"$B/fploc-os1-driver" --lcm-url "$URL" --set metadata="$META" --set lidar_port=17502 > "$T/os1.txt" 2>&1 & pids+=($!)
"$B/fploc-imu-driver" --lcm-url "$URL" --set imu_port=17503 > "$T/imu.txt" 2>&1 & pids+=($!)
sleep 1.5
# Garbage first (must be counted, not fatal), then the capture twice: frame 189 is published once, the
# second copy is a late repeat of a published frame and must be dropped, not merged.
head -c 1000 /dev/urandom > "$T/junk"
python3 - "$T/junk" <<'PY'
import socket, sys
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
d = open(sys.argv[1], 'rb').read()
s.sendto(d, ("127.0.0.1", 17502)); s.sendto(d[:47], ("127.0.0.1", 17503))
PY
"$B/fploc-os1-send" --pcap "$PCAP" --lidar-port 17502 --imu-port 17503 --rate 1 --loop 2
sleep 1.5
kill -INT "${pids[1]}" "${pids[2]}"
sleep 0.5
kill -INT "${pids[0]}"
wait "${pids[1]}" "${pids[2]}" || { echo "driver exited non-zero"; cat "$T/os1.txt" "$T/imu.txt"; exit 1; }
sleep 0.3
"$B/fploc-os1-decode" --pcap "$PCAP" --metadata "$META" --json > "$T/decode.json" 2>/dev/null
cat "$T/os1.txt" "$T/imu.txt"
python3 "$(dirname "$0")/check_log.py" "$T/log.lcm" "$T/decode.json"

# Pcap mode (as fast as possible): the drivers stop by themselves at the end of the file; the scan that
# went through LCM must still match the Ouster SDK's RANGE digest of OS-1-32-G.
G="$D/OS-1-32-G_v2.1.1_1024x10"
lcm-logger --lcm-url="$URL" "$T/log2.lcm" > "$T/logger2.txt" 2>&1 & pids+=($!)
sleep 0.5
timeout 20 "$B/fploc-os1-driver" --lcm-url "$URL" --set metadata="$G.json" --set pcap="$G.pcap" --set pcap_rate=-1
timeout 20 "$B/fploc-imu-driver" --lcm-url "$URL" --set pcap="$PCAP" --set pcap_rate=-1
sleep 1
kill -INT "${pids[3]}"
sleep 0.3
python3 "$(dirname "$0")/check_log.py" --sdk-digest "$T/log2.lcm" "$G""_digest.json" 11
