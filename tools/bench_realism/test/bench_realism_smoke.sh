#!/usr/bin/env bash
# fploc bench realism on one renovated world, 10 s of sequence: the JSON contract, every pose scored (no LOST,
# errors of a localizer that is on the plan, not lost), the detector's rates are fractions.
set -euo pipefail
B="${FPLOC_BUILD_DIR:?}/bin"
methods=fploc,fploc+downweight,amcl
[ -x "$B/fploc-ndt" ] && methods="$methods,ndt"
out="$("$B/fploc-bench-realism" --families renovated --duration 10 --seed 2 --methods "$methods" --json 2>/dev/null)"
python3 - "$out" "$methods" <<'PY'
import json, sys
r = json.loads(sys.argv[1])
rows = {x["method"]: x for x in r["rows"]}
assert set(sys.argv[2].split(",")) <= set(rows), rows.keys()
# Every method's CPU is divided by the scans, one pose each (NDT's once counted its segmenter's IMU samples too).
for m, x in rows.items():
    assert abs(x["scans"] - x["poses"]) <= 2, (m, x["scans"], x["poses"])
f = rows["fploc"]
for k in ("ate_m", "max_m", "lost", "false_ok", "false_ok_poses", "poor", "nees_median", "ms_per_scan", "ms_per_scan_localizer", "poses"):
    assert k in f, k
assert 0 < f["ms_per_scan_localizer"] < f["ms_per_scan"], f
# Aligned ATE: the best rigid alignment can only lower the rms; the floor of a world without as-built offsets is 0.
assert f["ate_aligned_m"] is not None and f["ate_aligned_m"] <= f["ate_m"] + 1e-12, f
assert f["ate_floor_m"] == 0.0, f
assert f["ate_bound_m"] is None, f  # no as-built offsets in the renovated world
dw = rows["fploc+downweight"]
assert dw["poses"] == f["poses"] and dw["lost"] == 0 and dw["ate_m"] < 0.5, dw
assert f["poses"] >= 90, f
assert f["lost"] == 0 and f["false_ok"] == 0, f
# Honest covariance: the median NEES (3 if consistent) was 300 here when points were taken as independent.
assert f["nees_median"] is not None and 0.3 < f["nees_median"] < 20, f
assert f["ate_m"] < 0.5 and f["max_m"] < 1.0, f
d = r["detection"][0]
for k in ("removed", "removed_found", "moved", "moved_found", "added", "added_found", "false_flags_per_100m", "precision", "recall"):
    assert k in d, k
assert d["precision"] is None or 0 <= d["precision"] <= 1
assert d["recall"] is None or 0 <= d["recall"] <= 1
print("bench realism smoke: ok", f["ate_m"], d)
PY
