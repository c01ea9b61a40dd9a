#!/usr/bin/env python3
"""Checks an LCM log of the OS-1 drivers against `fploc os1 decode --json` of the same capture."""
import hashlib
import json
import struct
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "pylib"))
from lcm_log import events  # noqa: E402


def scan(b):
    o = 8  # fingerprint
    utime, seq, frame_id = struct.unpack('>qqi', b[o:o + 20]); o += 20
    (n,) = struct.unpack('>i', b[o:o + 4]); o += 4
    sensor = b[o:o + n - 1].decode(); o += n
    h, w, npx = struct.unpack('>hhi', b[o:o + 8]); o += 8
    rng = struct.unpack(f'>{npx}i', b[o:o + 4 * npx])
    missing, status = struct.unpack('>ib', b[-5:])
    md5 = hashlib.md5(struct.pack(f'<{npx}I', *rng)).hexdigest()
    return dict(frame_id=frame_id, sensor=sensor, h=h, w=w, missing=missing, status=status, md5=md5,
                valid=sum(1 for r in rng if r))


def imu(b):
    utime, seq, au, gu = struct.unpack('>qqqq', b[8:40])
    acc = struct.unpack('>3d', b[40:64])
    gyr = struct.unpack('>3d', b[64:88])
    return dict(utime=utime, seq=seq, acc=acc, gyr=gyr)


def sdk_digest_mode(log, digest_path, imu_expected):
    """Pcap-mode run: one OS1_SCAN whose range image hashes to the SDK's scan RANGE digest."""
    ref = json.load(open(digest_path))['scans']
    scans = [scan(d) for ch, d in events(log) if ch == 'OS1_SCAN']
    imus = [imu(d) for ch, d in events(log) if ch == 'OS1_IMU']
    errors = []
    if [s['md5'] for s in scans] != [r['RANGE'] for r in ref]:
        errors.append(f"scan RANGE md5 {[s['md5'] for s in scans]} != SDK digest {[r['RANGE'] for r in ref]}")
    if [str(s['frame_id']) for s in scans] != [r['FRAME_ID'] for r in ref]:
        errors.append("frame ids differ from the SDK digest")
    if len(imus) != imu_expected:
        errors.append(f"OS1_IMU: {len(imus)} messages, expected {imu_expected}")
    print(json.dumps({'scans': scans, 'imu': len(imus)}, indent=1))
    for e in errors:
        print("FAIL:", e)
    sys.exit(1 if errors else 0)


def main():
    lidar_only = '--lidar-only' in sys.argv  # no IMU driver ran: check the scans only
    if lidar_only:
        sys.argv.remove('--lidar-only')
    if sys.argv[1] == '--sdk-digest':
        sdk_digest_mode(sys.argv[2], sys.argv[3], int(sys.argv[4]))
    log, ref_path = sys.argv[1], sys.argv[2]
    ref = json.load(open(ref_path))
    scans, imus = [], []
    for ch, data in events(log):
        if ch == 'OS1_SCAN':
            scans.append(scan(data))
        elif ch == 'OS1_IMU':
            imus.append(imu(data))
    errors = []
    if len(scans) != ref['complete_frames']:
        errors.append(f"OS1_SCAN: {len(scans)} messages, expected {ref['complete_frames']} (late repeat must be dropped)")
    for s in scans:
        if (s['h'], s['w']) != (ref['pixels_per_column'], ref['columns_per_frame']):
            errors.append(f"scan size {s['h']}x{s['w']}")
        if s['missing'] != 0 or s['status'] != 0:
            errors.append(f"scan {s['frame_id']}: missing {s['missing']} status {s['status']}")
        if s['md5'] != ref['range_md5'][0]:
            errors.append(f"scan {s['frame_id']}: range md5 {s['md5']} != decode {ref['range_md5'][0]}")
    if not lidar_only and len(imus) != 2 * ref['imu_packets']:
        errors.append(f"OS1_IMU: {len(imus)} messages, expected {2 * ref['imu_packets']} (capture sent twice)")
    for m in imus:
        if not 9.0 < m['acc'][2] < 10.6:
            errors.append(f"imu accel z {m['acc'][2]} m/s^2 not ~g")
    print(json.dumps({'scans': scans, 'imu': len(imus)}, indent=1))
    for e in errors:
        print("FAIL:", e)
    sys.exit(1 if errors else 0)


main()
