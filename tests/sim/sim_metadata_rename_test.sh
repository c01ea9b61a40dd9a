#!/usr/bin/env bash
# fploc-sim-sensor writes its OS-1 metadata (metadata_out) beside the file and renames it into place, so a driver
# polling for the file never reads it half-written, nor an older one truncated while it is rewritten. Seen from
# outside: the path gets a new file (a hard link to the old one keeps the old text; writing in place would change it)
# and no temporary file is left. Runs inside scripts/netns-run (UDP to loopback).
source "$(dirname "${BASH_SOURCE[0]}")/../support/netns_test.sh"
require_exes fploc-sim-sensor
fail() { echo "FAIL: $1"; cat "$T/sim.txt"; exit 1; }
mkdir "$T/d"
echo "an older metadata file" > "$T/d/meta.json"
ln "$T/d/meta.json" "$T/old-link"
"$B/fploc-sim-sensor" --lcm-url "$URL" --set scenario=room-small-loop-fast --set lidar_port=17512 --set imu_port=17513 \
  --set metadata_out="$T/d/meta.json" > "$T/sim.txt" 2>&1 & pids+=($!)
for _ in $(seq 100); do grep -q data_format "$T/d/meta.json" 2>/dev/null && break; sleep 0.1; done
kill -INT "${pids[0]}"; wait "${pids[0]}" || true
python3 -c "import json,sys; d=json.load(open(sys.argv[1])); assert d['data_format']['pixels_per_column'] > 0" "$T/d/meta.json" \
  || fail "no complete metadata at the path"
[ "$(cat "$T/old-link")" = "an older metadata file" ] || fail "the metadata was written into the old file, not renamed over it"
[ "$(ls "$T/d")" = "meta.json" ] || fail "left beside it: $(ls "$T/d")"
echo OK
