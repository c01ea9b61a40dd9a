#!/bin/sh
# fploc bench real on a slice of one log (intel: map from the first half, localize scans 50-60 %): the JSON
# contract, and fploc tracking that slice from the reference start (a real run; seconds); and the split rule's
# JSON (import-carmen --auto-split on aces).
set -e
# --help describes each option with its default (--logs, --rows, --resolution, --lost-m, --out, --graph had none).
"$FPLOC_BUILD_DIR/bin/fploc-bench-real" --help | python3 -c '
import re, sys
h = " ".join(sys.stdin.read().split())
for o in ("--logs", "--rows", "--resolution", "--lost-m", "--out", "--graph", "--end", "--split"):
    m = re.search(" " + o + r" [A-Z_]+ (.*?)(?= --[a-z]|$)", h)
    assert m and "(default: " in m.group(1), (o, m and m.group(1))
'
if [ ! -d "$FPLOC_SHARED_DIR/data/recordings/radish" ]; then echo "SKIP: shared data absent"; exit 0; fi
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
"$FPLOC_BUILD_DIR/bin/fploc-bench-real" --json --logs intel --split 0.5 --end 0.6 --rows ref --out "$T" --markdown "$T/r.md" > "$T/r.json"
# The Markdown tables: one row per run row in each table, and the same again from the JSON alone.
test "$(grep -c '^| intel | ref |' "$T/r.md")" = 2
"$FPLOC_BUILD_DIR/bin/fploc-bench-real" --from-json "$T/r.json" --markdown "$T/r2.md"
test "$(grep -c '^| intel | ref |' "$T/r2.md")" = 2
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
assert 0 < r["floor"]["ate_m"] < 0.2, r["floor"]
assert 0 < r["floor"]["cauchy"]["ate_m"] < 0.2, r["floor"]
for k in ("covered_scans", "split", "floor"):
    assert k in r, k
for k in ("all", "uncovered", "missing"):
    assert k in r["fploc"] and k in r["amcl"], k
assert r["fploc"]["all"]["scans"] == 91 and r["fploc"]["missing"] == 0, r["fploc"]
assert 0 < r["covered_scans"] <= 91 and r["fploc"]["uncovered"]["scans"] == 91 - r["covered_scans"], r
assert r["fploc"]["ate_m"] < 0.3 and r["fploc"]["lost_pct"] < 10, r["fploc"]
# What each method said of itself (its loggers' uncertainty files): every covered pose has a status.
for m in ("fploc", "amcl"):
    for k in ("status_poses", "false_ok_poses", "false_ok_pct", "poor_pct", "said_lost_pct", "nees_median"):
        assert k in r[m] and k in r[m]["all"], (m, k)
    assert r[m]["status_poses"] == r["covered_scans"] - r[m]["missing"], r[m]
assert r["fploc"]["nees_median"] > 0, r["fploc"]
# The reference's own noise (three-cornered hat of reference, fploc and the wheels over the slice's 90 increments):
# a few cm per pose on intel; fploc's ATE less it is below its ATE; adding the reference's variance lowers the NEES.
n = r["reference_noise"]
assert 50 <= n["increments"] <= 90 and 0.005 < n["pose_sigma_xy_m"] < 0.1 and "lag2" in n, n
for m in ("fploc", "amcl"):
    assert r[m]["ate_less_reference_noise_m"] < r[m]["ate_m"], r[m]
    assert r[m]["nees_median_with_reference_noise"] < r[m]["nees_median"], r[m]
PY
test -s "$T/intel/ref.png"
# The plan path in-process (fploc-real-plan-track: laser2d features -> one Localizer) over the same slice and map
# scores what the graph's two processes scored (the same code; the window feeds the matcher in both).
first=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['rows'][0]['map_scans'])" "$T/r.json")
"$FPLOC_BUILD_DIR/bin/fploc-real-plan-track" "$FPLOC_SHARED_DIR/data/recordings/radish/intel-corrected.log.gz" \
  --map "$T/intel/map/map.yaml" --first-scan "$first" --end-scan $((first + 91)) > "$T/plan.json"
python3 - "$T/plan.json" "$T/r.json" <<'PY'
import json, math, sys
s = json.load(open(sys.argv[1]))["scans"]
g = json.load(open(sys.argv[2]))["rows"][0]["fploc_plan"]["all"]["ate_m"]
assert len(s) == 91, len(s)
ate = math.sqrt(sum(r["err_m"] ** 2 for r in s) / len(s))
print("plan path in-process ATE", ate, "graph", g)
assert abs(ate - g) <= 0.2 * g + 0.01, (ate, g)
PY
test -s "$T/intel/ref-fploc.png"
# The split rule on a whole log: the JSON states the rule, the split and the covered share it reached.
"$FPLOC_BUILD_DIR/bin/fploc-import-carmen" "$FPLOC_SHARED_DIR/data/recordings/radish/aces-corrected.log.gz" --auto-split \
  --map "$T/aces-map" --json > "$T/aces.json"
python3 - "$T/aces.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
s = j["split"]
assert s["met"] == (s["covered_share"] >= s["rule"]["covered_share"]), s
assert j["first_scan"] == s["split"] == j["map"]["end_scan"], j
assert len(j["coverage"]) == j["end_scan"] - j["first_scan"], len(j["coverage"])
print("aces split", s["fraction"], "covered", s["covered_share"])
PY
echo OK
