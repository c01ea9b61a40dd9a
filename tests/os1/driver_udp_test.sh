#!/usr/bin/env bash
# Runs inside scripts/netns-run (FPLOC_BUILD_DIR, FPLOC_SHARED_DIR set by fploc_add_netns_test).
source "$(dirname "${BASH_SOURCE[0]}")/../support/netns_test.sh"
require_shared ouster/OS-1-64_1024x10_fw20.pcap
require_exes fploc-os1-driver fploc-imu-driver fploc-os1-send fploc-os1-decode
D="${FPLOC_SHARED_DIR:?}/data/ouster"
PCAP="$D/OS-1-64_1024x10_fw20.pcap"
META="$D/OS-1-64_sensor_config_reduced.json"

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

# Xsens source from a recorded serial byte stream: 5 MTData2 messages (a real MTi payload) with garbage
# and one corrupted message in between -> 5 OS1_IMU samples with source "xsens".
python3 - "$T/mti.bin" <<'PY'
import sys
p = bytes.fromhex("10 20 02 8D 90 10 60 04 00 54 DB F1 20 10 10 3F 7F 89 11 BC 11 1D FA 3B A0 CE F0 BD 73 25 73 40 20 0C BD DC "
    "F9 D0 BE 3C 86 19 41 1D 0B 47 40 10 0C B9 8D B0 00 B9 F1 48 00 3C C9 04 30 40 30 0C BC B9 89 2E BB 09 8C 00 "
    "3C A7 08 00 80 20 0C BA 63 BC 01 BC 04 D6 3F BB 6D E3 FE 80 30 10 3F 80 00 01 B5 91 C0 00 B7 2A 08 00 B6 98 "
    "40 00 E0 20 04 00 40 00 03".replace(" ", ""))
m = bytes([0xFA, 0xFF, 0x36, len(p)]) + p
m += bytes([(-sum(m[1:])) & 0xFF])
bad = bytearray(m); bad[40] ^= 1
open(sys.argv[1], "wb").write(b"\x00\xfa\x13" + m + m + bytes(bad) + b"junk" + m + m + m)
PY
lcm-logger --lcm-url="$URL" "$T/log3.lcm" > "$T/logger3.txt" 2>&1 & pids+=($!)
sleep 0.5
timeout 20 "$B/fploc-imu-driver" --lcm-url "$URL" --set source=xsens --set serial_device="$T/mti.bin"
sleep 1
kill -INT "${pids[4]}"
sleep 0.3
python3 - "$T/log3.lcm" <<'PY'
import struct, sys
d = open(sys.argv[1], "rb").read(); o = 0; got = []
while o + 28 <= len(d):
    _, _, _, cl, dl = struct.unpack(">IQQII", d[o:o + 28]); o += 28
    ch = d[o:o + cl].decode(); o += cl; b = d[o:o + dl]; o += dl
    if ch == "OS1_IMU":
        utime = struct.unpack(">q", b[8:16])[0]
        acc = struct.unpack(">3d", b[40:64]); gyr = struct.unpack(">3d", b[64:88])
        n = struct.unpack(">i", b[88:92])[0]; src = b[92:92 + n - 1].decode()
        got.append((utime, acc, gyr, src))
print("xsens samples:", len(got), got[:1])
ok = len(got) == 5 and all(g[3] == "xsens" and abs(g[1][2] - 9.81525326) < 1e-5 and g[0] == 556132900 for g in got)
sys.exit(0 if ok else 1)
PY

# Broken metadata is bad input too: the driver reports it, drops packets, stays alive and exits cleanly.
echo '{"beam_altitude_angles": [1, 2], "beam_azimuth_angles": [0]}' > "$T/bad.json"
"$B/fploc-os1-driver" --lcm-url "$URL" --set metadata="$T/bad.json" --set lidar_port=17502 > "$T/bad.txt" 2>&1 & bad=$!
pids+=($bad)
sleep 1
"$B/fploc-os1-send" --pcap "$PCAP" --lidar-port 17502 --imu-port 17503 --rate -1
sleep 0.5
kill -0 "$bad" || { echo "FAIL: driver died on bad metadata"; cat "$T/bad.txt"; exit 1; }
kill -INT "$bad"
wait "$bad" || { echo "FAIL: driver exit status after bad metadata"; cat "$T/bad.txt"; exit 1; }
grep -q "beam_azimuth_angles" "$T/bad.txt" || { echo "FAIL: metadata error not reported"; cat "$T/bad.txt"; exit 1; }
grep -q "dropped: no valid metadata" "$T/bad.txt" || { echo "FAIL: dropped packets not reported"; cat "$T/bad.txt"; exit 1; }
# Metadata from the sensor's HTTP API (GET /api/v1/sensor/metadata; a local HTTP server stands in for
# the sensor): the driver fetches it, caches it in `metadata`, and decodes the capture; with the "sensor"
# gone, a restarted driver says so and falls back to the cached file.
mkdir -p "$T/www/api/v1/sensor" && cp "$META" "$T/www/api/v1/sensor/metadata"
python3 -m http.server 18080 --bind 127.0.0.1 --directory "$T/www" > "$T/http.txt" 2>&1 & web=$!
pids+=($web)
for _ in $(seq 50); do python3 -c "import urllib.request; urllib.request.urlopen('http://127.0.0.1:18080/api/v1/sensor/metadata')" 2>/dev/null && break; sleep 0.1; done
for run in http cache; do
  [ "$run" = cache ] && { kill "$web"; wait "$web" 2>/dev/null || true; }
  lcm-logger --lcm-url="$URL" "$T/log_$run.lcm" > /dev/null 2>&1 & lg=$!
  "$B/fploc-os1-driver" --lcm-url "$URL" --set sensor_hostname=127.0.0.1:18080 --set keep_sensor_config=true --set metadata="$T/cached.json" \
    --set lidar_port=17502 > "$T/os1_$run.txt" 2>&1 & drv=$!
  sleep 1.5
  "$B/fploc-os1-send" --pcap "$PCAP" --lidar-port 17502 --imu-port 17503 --rate 1
  sleep 1
  kill -INT "$drv"; wait "$drv" || { echo "FAIL: driver ($run) exit status"; cat "$T/os1_$run.txt"; exit 1; }
  kill -INT "$lg"; wait "$lg" 2>/dev/null || true
  cat "$T/os1_$run.txt"
  cmp -s "$META" "$T/cached.json" || { echo "FAIL: the fetched metadata was not cached"; exit 1; }
  python3 "$(dirname "$0")/check_log.py" --lidar-only "$T/log_$run.lcm" "$T/decode.json"
done
grep -q "http://127.0.0.1:18080/api/v1/sensor/metadata" "$T/os1_http.txt" || { echo "FAIL: metadata not from HTTP"; exit 1; }
grep -q "trying the cached" "$T/os1_cache.txt" || { echo "FAIL: unreachable sensor not reported"; exit 1; }
# A metadata file that appears a moment after the driver starts (graphs/demo.pbtxt: the simulator writes it) is waited
# for quietly, then the capture decodes (the driver printed "cannot open metadata file ... retrying" at every start of
# the demo). One that never appears is reported, naming it, once the grace period is over.
lcm-logger --lcm-url="$URL" "$T/log_late.lcm" > /dev/null 2>&1 & lg=$!
"$B/fploc-os1-driver" --lcm-url "$URL" --set metadata="$T/late.json" --set lidar_port=17502 > "$T/late.txt" 2>&1 & drv=$!
sleep 1
cp "$META" "$T/late.json.part" && mv "$T/late.json.part" "$T/late.json"
sleep 1.5
"$B/fploc-os1-send" --pcap "$PCAP" --lidar-port 17502 --imu-port 17503 --rate 1
sleep 1
kill -INT "$drv"; wait "$drv" || { echo "FAIL: driver (late metadata) exit status"; cat "$T/late.txt"; exit 1; }
kill -INT "$lg"; wait "$lg" 2>/dev/null || true
cat "$T/late.txt"
if grep -qE "error|cannot open|retrying" "$T/late.txt"; then echo "FAIL: a metadata file written 1 s after the start was reported"; exit 1; fi
python3 "$(dirname "$0")/check_log.py" --lidar-only "$T/log_late.lcm" "$T/decode.json"
"$B/fploc-os1-driver" --lcm-url "$URL" --set metadata="$T/never.json" --set lidar_port=17502 > "$T/never.txt" 2>&1 & drv=$!
want="error: $T/never.json: cannot open metadata file (no such file 3 s after the driver started) (lidar packets are dropped; retrying)"
for _ in $(seq 150); do grep -qF "$want" "$T/never.txt" && break; sleep 0.1; done
kill -INT "$drv"; wait "$drv" || { echo "FAIL: driver (no metadata) exit status"; cat "$T/never.txt"; exit 1; }
grep -qF "$want" "$T/never.txt" || { echo "FAIL: a metadata file that never appears is not reported: $(cat "$T/never.txt")"; exit 1; }
[ "$(grep -c "never.json" "$T/never.txt")" = 1 ] || { echo "FAIL: not one report: $(cat "$T/never.txt")"; exit 1; }
echo "os1 driver tests passed"
