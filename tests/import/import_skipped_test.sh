#!/usr/bin/env bash
# fploc import of a recording where single messages do not decode: they are skipped, the others written, and the
# exit status says so: 3, with one line per topic naming it, the count and where the first is (chunk byte offset
# and record offset in the chunk). It was exit 0 (the problem printed, the status saying all was imported).
set -uo pipefail
I="${FPLOC_BUILD_DIR:?}/bin/fploc-import"
T="$(mktemp -d)"; trap 'rm -rf "$T"' EXIT
# A bag 2.0 with one uncompressed chunk: 3 sensor_msgs/Imu on /imu, the second cut to 12 bytes.
where="$(python3 - "$T/skip.bag" <<'PY'
import struct, sys
def field(n, v): b = n.encode() + b'=' + v; return struct.pack('<I', len(b)) + b
def rec(h, d): return struct.pack('<I', len(h)) + h + struct.pack('<I', len(d)) + d
def s(x): return struct.pack('<I', len(x)) + x.encode()
def imu(t): return struct.pack('<III', 7, t, 5) + s('imu') + struct.pack('<4d', 0,0,0,1) + b'\0'*72 + struct.pack('<3d', .1,.2,.3) + b'\0'*72 + struct.pack('<3d', 0,0,9.8) + b'\0'*72
chunk = rec(field('op', b'\x07') + field('conn', struct.pack('<I', 0)) + field('topic', b'/imu'),
            field('topic', b'/imu') + field('type', b'sensor_msgs/Imu') + field('md5sum', b'*'))
bad_at = None
for k in range(3):
    data = imu(100 + k)
    if k == 1: bad_at, data = len(chunk), data[:12]
    chunk += rec(field('op', b'\x02') + field('conn', struct.pack('<I', 0)) + field('time', struct.pack('<II', 100 + k, 0)), data)
out = b'#ROSBAG V2.0\n' + rec(field('op', b'\x03') + field('index_pos', struct.pack('<Q', 0)) + field('conn_count', struct.pack('<I', 0)) + field('chunk_count', struct.pack('<I', 0)), b' ' * 16)
chunk_at = len(out)
out += rec(field('op', b'\x05') + field('compression', b'none') + field('size', struct.pack('<I', len(chunk))), chunk)
open(sys.argv[1], 'wb').write(out)
print(f"chunk at byte {chunk_at}, record at chunk offset {bad_at}")
PY
)"
"$I" "$T/skip.bag" --out "$T/skip.lcm" --json --quiet > "$T/skip.json" 2> "$T/skip.err"; rc=$?
[ "$rc" = 3 ] || { echo "FAIL: exit $rc, expected 3"; cat "$T/skip.err"; exit 1; }
grep -q "^fploc import: /imu: 1 message not decoded, skipped (the first at $where: " "$T/skip.err" ||
  { echo "FAIL: no line naming topic, count and '$where'"; cat "$T/skip.err"; exit 1; }
[ "$(grep -c . "$T/skip.err")" = 2 ] || { echo "FAIL: expected the topic's line and the exit line"; cat "$T/skip.err"; exit 1; }
python3 -c "
import json, sys; j = json.load(open('$T/skip.json'))
ok = j['written'] == {'OS1_IMU': 2} and j['not_decoded']['/imu']['count'] == 1 and j['not_decoded']['/imu']['first'].startswith('$where')
sys.exit(0 if ok else print('FAIL:', j['written'], j.get('not_decoded')) or 1)" || exit 1
[ -s "$T/skip.lcm" ] || { echo "FAIL: no log written"; exit 1; }
echo OK
