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
echo OK
