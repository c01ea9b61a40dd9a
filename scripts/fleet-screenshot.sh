#!/usr/bin/env bash
# scripts/fleet-screenshot.sh [OUT.png] [SECONDS]: two robots on one network (robot r1 and r2, the demo
# pipeline each, r2 slower on the same loop) in a private network namespace; r1's dashboard also shows r2
# (dashboard.robots); saves a screenshot after SECONDS (default 30) with r2 selected in the robot selector.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="$(realpath -m "${1:-$ROOT/docs/img/fleet.png}")"
WAIT="${2:-30}"
if [ "${FPLOC_IN_NETNS:-}" != "1" ]; then exec "$ROOT/scripts/netns-run" "$0" "$OUT" "$WAIT"; fi
T="$(mktemp -d /tmp/fploc-fleet-XXXXXX)"
trap 'rm -rf "$T"' EXIT
for r in r1 r2; do
  sed -e "s/^name: \"demo\"/name: \"fleet-$r\"\nrobot: \"$r\"/" -e "s#/tmp/fploc-demo-#$T/$r-#g" -e "s#\.\./data/#$ROOT/data/#g" \
      -e "s/port: 8080/port: 18088 robots: \"r2\"/" "$ROOT/graphs/demo.pbtxt" > "$T/$r.pbtxt"
done
python3 - "$T/r2.pbtxt" <<'PY'
import re, sys
p = sys.argv[1]; s = open(p).read()
s = s.replace("room-small-loop-medium", "room-small-loop-slow")
# r2's simulator and drivers on their own UDP ports (both robots share this namespace's loopback)
s = s.replace("metadata_out:", "lidar_port: 7602 imu_port: 7603 metadata_out:", 1)
s = s.replace("lidar_port: 7502", "lidar_port: 7602").replace("imu_port: 7503", "imu_port: 7603")
s = re.sub(r'node \{\n  name: "dashboard".*?\n\}\n', "", s, flags=re.S)   # one dashboard (r1's) shows both
open(p, 'w').write(s)
PY
"${FPLOC_BUILD_DIR:-$ROOT/build}/bin/fploc-launch" "$T/r2.pbtxt" --duration "$((WAIT + 15))" 2> "$T/r2.log" &
L2=$!
"${FPLOC_BUILD_DIR:-$ROOT/build}/bin/fploc-launch" "$T/r1.pbtxt" --duration "$((WAIT + 15))" 2> "$T/r1.log" &
L1=$!
sleep 3
(cd "$ROOT/tests/dashboard" && FPLOC_SELECT_ROBOT=r2 node screenshot.mjs http://127.0.0.1:18088/ "$OUT" "$(( (WAIT - 3) * 1000 ))")
kill -INT "$L1" "$L2" 2>/dev/null || true
wait "$L1" "$L2" || true
grep -c . "$T/r1-poses.tum" "$T/r2-poses.tum" || true
