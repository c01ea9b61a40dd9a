#!/usr/bin/env bash
# Live sensor set-up over the Ouster HTTP API against a fake sensor (tests/os1/fake_sensor.py) on a network
# built here: the test's private namespace (scripts/netns-run) holds "this host" (10.77.0.1/24 on hs0), a
# second namespace holds the sensor (10.77.0.2/24), joined by a veth pair. Nothing leaves the namespaces.
#  1. fploc os1 configure: firmware 2.1 / 2.3 / 3.0 (cmd/ and /api/v1/sensor/config APIs), udp_dest from the
#     routing table (10.77.0.1) and @auto, PTP timestamp mode, a slow sensor (RUNNING after 3 s), one that
#     never gets there (timeout error), an ERROR state (its alerts in the error), firmware 2.0 and no HTTP
#     API (clear refusals), a wrong parameter (named, nothing sent).
#  2. fploc-os1-driver: configures the sensor on start, waits for RUNNING, re-reads the metadata; the
#     sensor then streams the OS-1-64 capture to the configured udp_dest:port from its namespace, and the
#     frame through LCM equals `fploc os1 decode`; a WARNING alert raised while running reaches the
#     driver's telemetry (node_status_t.detail and last_error on FPLOC_TELEMETRY).
set -euo pipefail
B="${FPLOC_BUILD_DIR:?}/bin"
D="${FPLOC_SHARED_DIR:?}/data/ouster"
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
skip() { echo "SKIP: $*"; exit 77; }
[ -f "$D/OS-1-64_1024x10_fw20.pcap" ] || skip "no ../shared/data"
[ "$(id -u)" -eq 0 ] || skip "needs root (a second network namespace and a veth pair)"
for c in ip unshare nsenter python3 lcm-logger; do command -v "$c" >/dev/null || skip "$c not found"; done
for exe in fploc-os1-driver fploc-os1-configure fploc-os1-send fploc-os1-decode; do
  [ -x "$B/$exe" ] || { echo "missing $B/$exe (build it first)"; exit 1; }
done
PCAP="$D/OS-1-64_1024x10_fw20.pcap"
META="$D/OS-1-64_sensor_config_reduced.json"
T="$(mktemp -d)"
pids=()
FS=""
cleanup() { set +e; [ -n "$FS" ] && kill "$FS" 2>/dev/null; for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done; wait 2>/dev/null; rm -rf "$T"; }
trap cleanup EXIT

# ---- the network: this host 10.77.0.1 <-veth-> sensor 10.77.0.2 (its own namespace, held by a sleep)
unshare -n sleep 600 & SNS=$!
pids+=($SNS)
sleep 0.2
ip link add hs0 type veth peer name sn0
ip link set sn0 netns "$SNS"
ip addr add 10.77.0.1/24 dev hs0
ip link set hs0 up
nsenter -t "$SNS" -n sh -c 'ip link set lo up && ip addr add 10.77.0.2/24 dev sn0 && ip link set sn0 up'
insensor() { nsenter -t "$SNS" -n "$@"; }

SENSOR=10.77.0.2:8080
start_sensor() {  # args for fake_sensor.py
  # Empty the log here, not in the background job's redirection: that runs in the child, and until it does
  # the previous sensor's "fake sensor" line is still there for the wait below to find.
  : > "$T/sensor.txt"
  nsenter -t "$SNS" -n python3 "$HERE/fake_sensor.py" --bind 10.77.0.2 --port 8080 --metadata "$META" "$@" > "$T/sensor.txt" 2>&1 &
  FS=$!
  for _ in $(seq 200); do grep -q "fake sensor" "$T/sensor.txt" && return 0; sleep 0.05; done
  echo "FAIL: fake sensor did not start"; cat "$T/sensor.txt"; exit 1
}
stop_sensor() { kill "$FS" 2>/dev/null || true; wait "$FS" 2>/dev/null || true; }
active_config() {  # the fake sensor's active configuration, as the sensor reports it
  python3 -c "import json,urllib.request; print(json.dumps(json.load(urllib.request.urlopen('http://$SENSOR/api/v1/sensor/cmd/get_config_param?args=active'))))"
}
expect_fail() {  # name, regex, fploc-os1-configure args...
  local name="$1" re="$2"; shift 2
  if "$B/fploc-os1-configure" --sensor "$SENSOR" "$@" > "$T/out.txt" 2> "$T/err.txt"; then
    echo "FAIL ($name): succeeded"; cat "$T/out.txt" "$T/err.txt"; exit 1
  fi
  grep -Eq "$re" "$T/err.txt" || { echo "FAIL ($name): error does not match /$re/:"; cat "$T/err.txt"; exit 1; }
  echo "ok ($name): $(tail -1 "$T/err.txt")"
}

# ---- 1. the set-up against each kind of sensor
for fw in ousteros-image-prod-aries-v2.1.2+20210608 ousteros-image-prod-aries-v2.3.0+20220415163956 ousteros-image-prod-bootes-v3.0.1+0123456789; do
  start_sensor --fw "$fw" --init-s 0.5
  "$B/fploc-os1-configure" --sensor "$SENSOR" --lidar-mode 1024x10 --timestamp-mode TIME_FROM_PTP_1588 \
    --lidar-port 17502 --imu-port 17503 --metadata-out "$T/meta.json" --json > "$T/out.json"
  cat "$T/out.json"
  python3 - "$T/out.json" "$(active_config)" "$T/meta.json" <<'PY'
import json, sys
out, cfg, meta = json.load(open(sys.argv[1])), json.loads(sys.argv[2]), json.load(open(sys.argv[3]))
assert out["status"] == "RUNNING" and out["reinitialised"], out
assert cfg["udp_dest"] == "10.77.0.1", cfg      # this host's address on the sensor's subnet (routing table)
assert cfg["lidar_mode"] == "1024x10" and cfg["timestamp_mode"] == "TIME_FROM_PTP_1588", cfg
assert cfg["udp_port_lidar"] == 17502 and cfg["udp_port_imu"] == 17503, cfg
assert meta["config_params"]["lidar_mode"] == "1024x10" and meta["lidar_data_format"]["columns_per_frame"] == 1024, meta
PY
  # Again: nothing differs, so no reinitialisation (as the SDK: only a changed configuration is written).
  "$B/fploc-os1-configure" --sensor "$SENSOR" --lidar-mode 1024x10 --timestamp-mode TIME_FROM_PTP_1588 \
    --lidar-port 17502 --imu-port 17503 --json | grep -q '"reinitialised": false' || { echo "FAIL: reinitialised twice"; exit 1; }
  # @auto: the sensor takes the address the request came from.
  "$B/fploc-os1-configure" --sensor "$SENSOR" --udp-dest @auto --lidar-port 17502 --imu-port 17503 > /dev/null
  [ "$(active_config | python3 -c 'import json,sys; print(json.load(sys.stdin)["udp_dest"])')" = 10.77.0.1 ] || { echo "FAIL: @auto"; exit 1; }
  stop_sensor
  echo "ok (firmware $fw)"
done
grep -q "REQ GET /api/v1/sensor/cmd/reinitialize" "$T/sensor.txt" && { echo "FAIL: fw 3 used the cmd API"; exit 1; }
grep -q "REQ POST /api/v1/sensor/config?reinit=true&persist=false" "$T/sensor.txt" || { echo "FAIL: fw 3 did not POST the config"; exit 1; }

start_sensor --init-s 3
t0=$(date +%s.%N)
"$B/fploc-os1-configure" --sensor "$SENSOR" --lidar-mode 2048x10 --profile RNG19_RFL8_SIG16_NIR16 --json > "$T/out.json"
python3 -c "import json,sys; o=json.load(open(sys.argv[1])); assert o['status']=='RUNNING' and o['waited_s']>=2.5, o; print('ok (slow sensor): RUNNING after', round(o['waited_s'],1), 's')" "$T/out.json"
stop_sensor

start_sensor --init-s -1
expect_fail "never RUNNING" "timeout after 3 s .*waiting for RUNNING; last status INITIALIZING" --lidar-mode 1024x10 --timeout 3
stop_sensor
start_sensor --error --init-s 0.3
expect_fail "ERROR state" "10.77.0.2:8080 reports status ERROR .*0x01000001 ERROR OVERTEMP: Unit internal temperature is too high" --lidar-mode 1024x10
stop_sensor
start_sensor --fw v2.0.0
expect_fail "firmware 2.0" "firmware v2.0.0 .*is not supported" --lidar-mode 1024x10
stop_sensor
start_sensor --fw none
expect_fail "no HTTP API" "system/firmware: HTTP 404: this sensor has no HTTP API" --lidar-mode 1024x10
stop_sensor
start_sensor --fw ousteros-image-prod-aries-v2.1.2+20210608
expect_fail "profile on fw 2.1" "udp_profile_lidar RNG15_RFL8_NIR8: firmware v2.1.2 has no packet profiles" --profile RNG15_RFL8_NIR8
stop_sensor
start_sensor
expect_fail "bad lidar_mode" "lidar_mode '1024x15' is not an Ouster lidar mode" --lidar-mode 1024x15
expect_fail "dual profile" "udp_profile_lidar 'RNG19_RFL8_SIG16_NIR16_DUAL' is not decoded by fploc" --profile RNG19_RFL8_SIG16_NIR16_DUAL
grep -q "REQ" "$T/sensor.txt" && { echo "FAIL: a request was sent for a bad parameter"; exit 1; }
stop_sensor

# ---- 2. the driver sets the sensor up, the sensor streams to where it was told, alerts reach telemetry
URL="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608"
start_sensor --fw ousteros-image-prod-bootes-v3.0.1+0123456789 --init-s 2 --warn-after 1
lcm-logger --lcm-url="$URL" "$T/log.lcm" > /dev/null 2>&1 & lg=$!
pids+=($lg)
"$B/fploc-os1-driver" --lcm-url "$URL" --set sensor_hostname=$SENSOR --set lidar_mode=1024x10 \
  --set timestamp_mode=TIME_FROM_PTP_1588 --set lidar_port=17502 --set metadata="$T/cached.json" \
  --set alerts_period_s=0.5 > "$T/drv.txt" 2>&1 & drv=$!
pids+=($drv)
for _ in $(seq 150); do grep -q "metadata from http" "$T/drv.txt" && break; sleep 0.1; done
grep -q "metadata from http://$SENSOR/api/v1/sensor/metadata (after the set-up)" "$T/drv.txt" || { echo "FAIL: driver did not set the sensor up"; cat "$T/drv.txt"; exit 1; }
read -r dest port < <(active_config | python3 -c 'import json,sys; c=json.load(sys.stdin); print(c["udp_dest"], c["udp_port_lidar"])')
echo "sensor configured by the driver: udp_dest $dest:$port"
[ "$dest" = 10.77.0.1 ] && [ "$port" = 17502 ] || { echo "FAIL: udp_dest $dest:$port"; exit 1; }
insensor "$B/fploc-os1-send" --pcap "$PCAP" --host "$dest" --lidar-port "$port" --imu-port 17503 --rate 1
sleep 2.5
kill -INT "$drv"; wait "$drv" || { echo "FAIL: driver exit status"; cat "$T/drv.txt"; exit 1; }
kill -INT "$lg"; wait "$lg" 2>/dev/null || true
stop_sensor
cat "$T/drv.txt"
grep -q "alert 0x01000017 WARNING UDP_TRANSMISSION" "$T/drv.txt" || { echo "FAIL: the running sensor's alert was not reported"; exit 1; }
cmp -s "$T/meta.json" "$T/cached.json" 2>/dev/null || true
python3 -c "import json,sys; m=json.load(open(sys.argv[1])); assert m['config_params']['timestamp_mode']=='TIME_FROM_PTP_1588'" "$T/cached.json"
"$B/fploc-os1-decode" --pcap "$PCAP" --metadata "$META" --json > "$T/decode.json" 2>/dev/null
python3 "$HERE/check_log.py" --lidar-only "$T/log.lcm" "$T/decode.json"
python3 - "$T/log.lcm" <<'PY'
import struct, sys
d = open(sys.argv[1], "rb").read(); o = 0; seen = []
while o + 28 <= len(d):
    _, _, _, cl, dl = struct.unpack(">IQQII", d[o:o + 28]); o += 28
    ch = d[o:o + cl].decode(); o += cl; b = d[o:o + dl]; o += dl
    if ch == "FPLOC_TELEMETRY" and b"os1_driver" in b:
        seen.append(b)
detail = [b for b in seen if b"RUNNING, 1024x10 LEGACY TIME_FROM_PTP_1588 -> 10.77.0.1:17502" in b]
alert = [b for b in detail if b"[0x01000017 WARNING UDP_TRANSMISSION" in b]
print(f"telemetry: {len(seen)} os1_driver status messages, {len(detail)} with the sensor state, {len(alert)} with the active alert")
sys.exit(0 if detail and alert else 1)
PY
# A sensor that never reaches RUNNING: the driver reports the timeout in telemetry, stays alive (retrying),
# and a Ctrl-C while it waits ends it at once.
start_sensor --init-s -1
"$B/fploc-os1-driver" --lcm-url "$URL" --set sensor_hostname=$SENSOR --set lidar_port=17502 \
  --set sensor_timeout_s=1.5 > "$T/drv2.txt" 2>&1 & drv=$!
pids+=($drv)
for _ in $(seq 100); do grep -q "timeout after 1.5 s" "$T/drv2.txt" && break; sleep 0.1; done
grep -q "error: sensor set-up failed: sensor $SENSOR: timeout after 1.5 s (sensor_timeout_s) waiting for RUNNING; last status INITIALIZING" "$T/drv2.txt" \
  || { echo "FAIL: timeout not reported by the driver"; cat "$T/drv2.txt"; exit 1; }
kill -0 "$drv" || { echo "FAIL: driver died on a sensor that does not start"; exit 1; }
t0=$(date +%s%N); kill -INT "$drv"; wait "$drv" || { echo "FAIL: driver exit status"; cat "$T/drv2.txt"; exit 1; }
ms=$(( ($(date +%s%N) - t0) / 1000000 ))
echo "ok (driver, never RUNNING): timeout reported, exit on SIGINT after $ms ms"
[ "$ms" -lt 5000 ] || { echo "FAIL: shutdown took $ms ms"; exit 1; }
stop_sensor
echo "sensor config tests passed"
