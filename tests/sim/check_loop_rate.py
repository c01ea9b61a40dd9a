#!/usr/bin/env python3
"""check_loop_rate.py LOG PASS_S: the ground truth and OS1_SCAN messages of a looping fploc-sim-sensor run
(recorded by lcm-logger) arrive at 10 Hz of wall time, over more than two passes of PASS_S seconds, and
their sensor times advance by 0.1 s per frame (no jump at the restarts)."""
import struct
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "pylib"))
from lcm_log import events  # noqa: E402


log, pass_s = sys.argv[1], float(sys.argv[2])
msgs = {'FPLOC_GROUND_TRUTH': [], 'OS1_SCAN': []}
for wall_us, ch, b in events(log, with_time=True):
    if ch in msgs:
        msgs[ch].append((wall_us * 1e-6, struct.unpack('>q', b[8:16])[0] * 1e-6))  # (wall, sensor utime)
# The driver's first scan is the frame that was in flight when it started (partial, a later utime).
msgs['OS1_SCAN'] = msgs['OS1_SCAN'][1:]
ok = True
for ch, m in msgs.items():
    if len(m) < 10:
        print(f"FAIL {ch}: only {len(m)} messages")
        ok = False
        continue
    wall = m[-1][0] - m[0][0]
    sensor = m[-1][1] - m[0][1]
    rate = (len(m) - 1) / wall
    steps = [b[1] - a[1] for a, b in zip(m, m[1:])]
    # Each one-second window of wall time holds ~10 messages (the flood showed up as 37-55 Hz; a pass of
    # 2.5 s restarting 2.5 s ahead would put 25 frames in one second).
    worst = max(sum(1 for w, _ in m if t <= w < t + 1.0) for t, _ in m if t + 1.0 <= m[-1][0])
    print(f"{ch}: {len(m)} messages over {wall:.2f} s wall, {sensor:.2f} s sensor time: {rate:.2f} Hz; "
          f"max in any 1 s window {worst}; sensor steps {min(steps):.3f}..{max(steps):.3f} s")
    if wall < 2 * pass_s + 0.5:
        print(f"FAIL {ch}: the run covered {wall:.2f} s, not more than two passes of {pass_s} s")
        ok = False
    if not 9.0 <= rate <= 11.0 or worst > 14:
        print(f"FAIL {ch}: {rate:.2f} Hz (max {worst} in 1 s), expected 10 Hz")
        ok = False
    if abs(sensor - wall) > 0.1 * wall + 0.3:
        print(f"FAIL {ch}: sensor time ran {sensor:.2f} s in {wall:.2f} s of wall time")
        ok = False
    # Scans can be lost whole by LCM under load (not a clock fault), so a step may be 0.2 s; never <= 0.
    if min(steps) < 0.099 or max(steps) > 0.31:
        print(f"FAIL {ch}: sensor time steps {min(steps):.3f}..{max(steps):.3f} s, expected 0.1 s")
        ok = False
sys.exit(0 if ok else 1)
