#!/bin/sh
# fploc bench real on a slice of one log (intel: map from the first half, localize scans 50-60 %): the JSON
# contract, and fploc tracking that slice from the reference start (a real run; seconds).
set -e
if [ ! -d "$FPLOC_SHARED_DIR/data/recordings/radish" ]; then echo "SKIP: shared data absent"; exit 0; fi
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
"$FPLOC_BUILD_DIR/bin/fploc-bench-real" --json --logs intel --end 0.6 --rows ref --out "$T" > "$T/r.json"
python3 - "$T/r.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
r = j["rows"][0]
print(r)
for k in ("log", "start", "scans", "fploc", "amcl", "plot"):
    assert k in r, k
for k in ("ate_m", "max_m", "lost_pct", "ms_per_scan"):
    assert k in r["fploc"] and k in r["amcl"], k
assert r["scans"] == 91, r["scans"]
assert r["fploc"]["ate_m"] < 0.3 and r["fploc"]["lost_pct"] < 10, r["fploc"]
PY
test -s "$T/intel/ref.png"
echo OK
