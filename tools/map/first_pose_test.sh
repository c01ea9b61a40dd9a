#!/usr/bin/env bash
# tools/map/first_pose.sh runs what is built (no setup, no cmake: it ran bin/fploc launch, which built first, here from
# inside ctest) and reports the first poses of a live graph fed from a log: graphs/replay.pbtxt on 4 s of the demo
# room's simulated scans. A `cmake` first in PATH records any call: there must be none. Inside scripts/netns-run.
source "$(dirname "${BASH_SOURCE[0]}")/../../tests/support/netns_test.sh"
require_exes fploc-launch fploc-sim fploc-matcher fploc-optimizer
R="${FPLOC_ROOT:?}"
mkdir "$T/fakebin"
printf '#!/bin/sh\necho "cmake $*" >> "%s/cmake-called"\n' "$T" > "$T/fakebin/cmake"
chmod +x "$T/fakebin/cmake"
"$B/fploc-sim" --scenario room-small-loop-medium --duration 4 --out "$T/run.lcm" --gt "$T/run.tum" 2> "$T/sim.txt" || { cat "$T/sim.txt"; exit 1; }
PATH="$T/fakebin:$PATH" FPLOC_ANNF_CACHE="$T/cache" "$R/tools/map/first_pose.sh" "$R/graphs/replay.pbtxt" "$T/run.lcm" 10 \
  > "$T/out.txt" 2>&1 || { cat "$T/out.txt"; echo "FAIL: first_pose.sh exit $?"; exit 1; }
cat "$T/out.txt"
[ ! -e "$T/cmake-called" ] || { cat "$T/cmake-called"; echo "FAIL: first_pose.sh ran cmake"; exit 1; }
grep -Eq "^FPLOC_FRAME_POSE: [1-9][0-9]* messages; first received [0-9.]+ s after start" "$T/out.txt" \
  || { echo "FAIL: no first frame pose reported"; exit 1; }
echo OK
