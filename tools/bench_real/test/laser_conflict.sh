#!/bin/sh
# grid2d's laser_conflict_inlier_ratio on the real log where it matters (intel, the bench's split, the reference
# start): with the default, no pose of the covered scans is published OK more than 0.3 m from the reference (false
# OK); with the rule off (control) some are (scans 591 and 705: weak map fits that left a matched laser step).
set -e
LOG="$FPLOC_SHARED_DIR/data/recordings/radish/intel-corrected.log.gz"
if [ ! -f "$LOG" ]; then echo "SKIP: $LOG absent (shared data)"; exit 0; fi
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
"$FPLOC_BUILD_DIR/bin/fploc-import-carmen" "$LOG" --auto-split --map "$T/map" --min-hits 1 --occupied-ratio 0.1 \
  --hit-clearance 0.1 --json > "$T/imp.json"
F=$(python3 -c "import json,sys; j=json.load(open(sys.argv[1])); print(j['first_scan'], j['end_scan'])" "$T/imp.json")
set -- $F
"$FPLOC_BUILD_DIR/bin/fploc-real-track" "$LOG" --map "$T/map/map.yaml" --first-scan "$1" --end-scan "$2" --start ref > "$T/on.json"
"$FPLOC_BUILD_DIR/bin/fploc-real-track" "$LOG" --map "$T/map/map.yaml" --first-scan "$1" --end-scan "$2" --start ref \
  --laser-conflict-inlier-ratio 0 > "$T/off.json"
python3 - "$T/imp.json" "$T/on.json" "$T/off.json" <<'PY'
import json, sys
imp = json.load(open(sys.argv[1]))
def false_ok(path):
    s = json.load(open(path))["scans"]
    cov = [r for r in s if imp["coverage"][r["scan"] - imp["first_scan"]] >= imp["coverage_ratio"]]
    return [r["scan"] for r in cov if r["status"] == 0 and r["err_m"] > 0.3], len(cov)
on, n = false_ok(sys.argv[2])
off, _ = false_ok(sys.argv[3])
print(f"covered scans {n}: false OK with the rule {on}, without {off}")
assert off, "control: without the rule no pose was a false OK; the test does not test the rule"
assert not on, on
PY
echo OK
