#!/usr/bin/env python3
"""Compares the OS1_SCAN frames decoded by the drivers from sim-sensor packets with the scans `fploc sim`
wrote directly (same scenario and seed): every complete decoded frame must have the same range image
(integer millimetres, so the XYZ points are identical) and column times; IMU and ground truth must flow."""
import struct
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "pylib"))
from lcm_log import events  # noqa: E402


def scan(b):
    o = 8
    utime, seq, frame_id = struct.unpack('>qqi', b[o:o + 20]); o += 20
    (n,) = struct.unpack('>i', b[o:o + 4]); o += 4 + n
    h, w, npx = struct.unpack('>hhi', b[o:o + 8]); o += 8
    rng = b[o:o + 4 * npx]; o += 4 * npx
    o += 2 * npx + npx  # signal, reflectivity
    cols = struct.unpack(f'>{w}q', b[o:o + 8 * w])
    missing, status = struct.unpack('>ib', b[-5:])
    return utime, h, w, rng, cols, missing


def gt_utime(b):
    return struct.unpack('>q', b[8:16])[0]


drv, ref = sys.argv[1], sys.argv[2]
ref_scans = {}
for ch, b in events(ref):
    if ch == 'OS1_SCAN':
        s = scan(b)
        ref_scans[s[0]] = s
got = {'OS1_SCAN': 0, 'OS1_IMU': 0, 'FPLOC_GROUND_TRUTH': 0}
compared = 0
gt_times = set()
for ch, b in events(drv):
    if ch in got:
        got[ch] += 1
    if ch == 'FPLOC_GROUND_TRUTH':
        gt_times.add(gt_utime(b))
    if ch != 'OS1_SCAN':
        continue
    s = scan(b)
    if s[5] != 0:
        continue  # the frame that was in flight when the driver started
    r = ref_scans.get(s[0])
    assert r is not None, f"decoded scan utime {s[0]} not in the reference log"
    assert (s[1], s[2]) == (r[1], r[2]), "image size differs"
    assert s[3] == r[3], f"range image of scan {s[0]} differs from the simulator's"
    assert s[4] == r[4], f"column times of scan {s[0]} differ"
    compared += 1
print(f"messages {got}; {compared} decoded frames identical to the simulator's")
assert compared >= 20, "too few complete frames came through the driver"
assert got['OS1_IMU'] >= 300, "too few IMU samples"
assert got['FPLOC_GROUND_TRUTH'] >= 30
