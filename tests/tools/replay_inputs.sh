#!/usr/bin/env bash
# fploc replay with a graph that reads none of the log's channels (graphs/import.pbtxt on a log of Ouster packets,
# `fploc import` without --decode): an error naming the log's channels and the graph's, with the way out for
# packets, exit 1 (it printed "0 of N log events fed" and exited 0).
set -euo pipefail
BIN="${FPLOC_BUILD_DIR:?}/bin"
ROOT="${FPLOC_ROOT:?}"
W="$(mktemp -d "${TMPDIR:-/tmp}/fploc-replay-inputs-XXXXXX")"
trap 'rm -rf "$W"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
# An LCM log (the file format: sync word, event number, utime, channel length, data length, channel, data) of
# three events on OS1_LIDAR_PACKETS and one on OS1_METADATA; no node decodes them, so the bytes are arbitrary.
python3 - "$W/packets.lcm" <<'PY'
import struct, sys
with open(sys.argv[1], "wb") as f:
    for k, ch in enumerate(["OS1_METADATA", "OS1_LIDAR_PACKETS", "OS1_LIDAR_PACKETS", "OS1_LIDAR_PACKETS"]):
        data = bytes(16)
        f.write(struct.pack(">IqqII", 0xEDA1DA01, k, 1000000 + k * 100000, len(ch), len(data)) + ch.encode() + data)
PY
set +e
"$BIN/fploc-replay" --graph "$ROOT/graphs/import.pbtxt" --log "$W/packets.lcm" > /dev/null 2> "$W/err"
rc=$?
set -e
[ "$rc" = 1 ] || { cat "$W/err"; fail "exit $rc, not 1"; }
grep -q "no event of $W/packets.lcm is on an input channel of .*import.pbtxt: the log holds OS1_LIDAR_PACKETS (3), OS1_METADATA (1); the graph reads OS1_SCAN" "$W/err" \
  || { cat "$W/err"; fail "error text: channels"; }
grep -q "Ouster packets: replay it with --graph graphs/replay-packets.pbtxt .*fploc import --decode" "$W/err" \
  || { cat "$W/err"; fail "error text: the way out for packets"; }

# Some inputs fed, the scans not: a point-cloud log (`fploc import` without --decode) through graphs/replay.pbtxt fed its
# IMU, no scan, and said only "0 poses". Now a warning naming the starved channel, the log's unread channels and the
# graph that reads them. The sim's scans renamed POINT_CLOUD stand for the clouds (no node of the graph reads them).
"$BIN/fploc-sim" --scenario room-small-loop-fast --duration 1 --out "$W/sim.lcm" --gt "$W/gt.tum" 2> "$W/sim.err" ||
  { cat "$W/sim.err"; fail "fploc-sim"; }
PYTHONPATH="$ROOT/tools/pylib" python3 - "$W/sim.lcm" "$W/clouds.lcm" <<'PY'
import sys, lcm_log
lcm_log.write_events(sys.argv[2], ((t, "POINT_CLOUD" if ch == "OS1_SCAN" else ch, d)
                                   for t, ch, d in lcm_log.events(sys.argv[1], with_time=True)))
PY
"$BIN/fploc-replay" --graph "$ROOT/graphs/replay.pbtxt" --log "$W/clouds.lcm" --out "$W/c.tum" > /dev/null 2> "$W/err" ||
  { cat "$W/err"; fail "replay of the cloud log: exit $?"; }
grep -q "^fploc replay: warning: $W/clouds.lcm has no event on OS1_SCAN, which .*replay.pbtxt reads; the log's channels it does not read: POINT_CLOUD (10)\. The log holds point clouds .*--graph graphs/replay-clouds.pbtxt" "$W/err" \
  || { cat "$W/err"; fail "no warning about the scans the graph did not get"; }
"$BIN/fploc-replay" --graph "$ROOT/graphs/replay.pbtxt" --log "$W/sim.lcm" --out "$W/s.tum" > /dev/null 2> "$W/err" ||
  { cat "$W/err"; fail "replay of the sim log: exit $?"; }
grep -q "has no event on" "$W/err" && { cat "$W/err"; fail "starved-input warning on the simulator's log"; }
echo OK
