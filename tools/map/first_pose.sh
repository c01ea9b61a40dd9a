#!/bin/bash
# Time to first pose of a live graph: `lcm-logplayer LOG` starts at the instant t0 `fploc launch GRAPH` starts the
# graph's nodes (its "running" line; before it the launcher checks the graph and listens 1.2 s for nodes of the graph
# already running); lcm-logger records the pose channels with their receive times; prints, per channel, the
# first pose's arrival after t0 and the log time of the scan it belongs to. Runs itself in a private
# network namespace (scripts/netns-run), so no LCM traffic leaves the machine.
#   tools/map/first_pose.sh GRAPH LOG [DURATION_S]
# It runs what is built ($FPLOC_BUILD_DIR, default build/: its bin/fploc-launch), building nothing.
# docs/notes/building.md: SIST-F4 with a warm ANNF cache (FPLOC_ANNF_CACHE). Test: map_first_pose.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
LAUNCH="${FPLOC_BUILD_DIR:-$ROOT/build}/bin/fploc-launch"
[ -x "$LAUNCH" ] || { echo "first_pose.sh: no $LAUNCH (build first: bin/fploc setup, or cmake --build)" >&2; exit 1; }
if [ "${FPLOC_IN_NETNS:-}" != "1" ]; then exec "$ROOT/scripts/netns-run" "$0" "$@"; fi
GRAPH="$1" LOG="$2" DUR="${3:-12}"
T="$(mktemp -d)"
trap 'rm -rf "$T"' EXIT
URL=$(sed -n 's/^lcm_url: *"\(.*\)".*/\1/p' "$GRAPH")
lcm-logger --lcm-url="$URL" -c '^FPLOC_(FRAME_POSE|POSE|POSE_LATEST)$' "$T/pose.lcm" > /dev/null 2>&1 &
G=$!
sleep 0.5
"$LAUNCH" "$GRAPH" --duration "$DUR" > "$T/launch.log" 2>&1 &
L=$!
for _ in $(seq 300); do grep -q "' running: " "$T/launch.log" && break; sleep 0.01; done
t0=$(date +%s%N)
lcm-logplayer --lcm-url="$URL" "$LOG" > /dev/null 2>&1 &
P=$!
wait $P
wait $L || true
kill -INT $G
wait $G || true
grep "fploc annf" "$T/launch.log" || true
python3 - "$t0" "$T/pose.lcm" <<'PY'
import struct, sys
t0 = int(sys.argv[1]) / 1e9
d = open(sys.argv[2], 'rb').read()
first, count, i = {}, {}, 0
while i + 28 <= len(d):
    sync, num, ts, cl, dl = struct.unpack('>IqqII', d[i:i + 28])
    if sync != 0xEDA1DA01: sys.exit("bad LCM log")
    ch = d[i + 28:i + 28 + cl].decode()
    utime = struct.unpack('>q', d[i + 28 + cl + 8:i + 28 + cl + 16])[0]  # pose_t.utime after the fingerprint
    count[ch] = count.get(ch, 0) + 1
    first.setdefault(ch, (ts / 1e6 - t0, utime / 1e6))
    i += 28 + cl + dl
if not first: print("no pose")
for ch, (t, stamp) in sorted(first.items()):
    print(f"{ch}: {count[ch]} messages; first received {t:.3f} s after start (scan stamp {stamp:.3f})")
PY
