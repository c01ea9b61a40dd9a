#!/usr/bin/env bash
# fploc bench building on 4 s of two building scenarios on the demo room plan: the JSON contract (rows and
# their keys), sane values, and the z plot.
set -euo pipefail
BIN="${FPLOC_BUILD_DIR:?}/bin"
W="$(mktemp -d "${TMPDIR:-/tmp}/fploc-bench-building-XXXXXX")"
trap 'rm -rf "$W"' EXIT
"$BIN/fploc-bench-building" --plan "${FPLOC_ROOT:?}/data/plans/room.json" --scenario building-mixed-medium \
  --scenario auto-loop-medium --building-heights --duration 4 --plots "$W/plots" --json >"$W/out.json" 2>"$W/err" || { tail -20 "$W/err" >&2; exit 1; }
python3 - "$W/out.json" <<'PY'
import json, os, sys
d = json.load(open(sys.argv[1]))
assert len(d["rows"]) == 2, d
for r in d["rows"]:
    for k in ("plan", "scenario", "ate_xy_m", "z_err_median_m", "z_err_p99_m", "rp_err_p99_deg", "lost", "ms_per_scan"):
        assert k in r and r[k] is not None, (k, r)
    assert r["poses"] >= 35, r
    assert r["z_err_p99_m"] < 0.05 and r["ate_xy_m"] < 0.05 and r["lost"] == 0, r
    # Honest uncertainty (issue 12): the published covariance is scored, no pose is OK while > 0.3 m off.
    assert r["nees_median"] is not None and r["nees_median"] > 0 and r["false_ok"] == 0, r
    assert set(r["ms_per_scan"]) == {"segmenter", "features", "matcher", "optimizer"}, r
    assert os.path.getsize(r["plot"]) > 1000 and open(r["plot"]).read().startswith("<svg"), r
    assert open(r["plot_png"], "rb").read(8) == b"\x89PNG\r\n\x1a\n" and os.path.getsize(r["plot_png"]) > 5000, r
assert "ceilings: mixed" in " ".join(d["rows"][0]["sim"]), d["rows"][0]
# building-*: the segmenter got the simulated ceilings as a building file (segmenter.building + pose feedback).
assert d["rows"][0]["segmenter_building"] is True and d["rows"][1]["segmenter_building"] is False, d["rows"]
print("bench building smoke:", [(r["scenario"], r["z_err_p99_m"], r["rp_err_p99_deg"]) for r in d["rows"]])
PY
# A building: the first 4 s of the demo building's ramp journey (ground floor): the floor rows are there.
"$BIN/fploc-bench-building" --plan "${FPLOC_ROOT:?}/data/buildings/demo-building.pbtxt" --scenario building-ramp-fast \
  --duration 4 --json >"$W/b.json" 2>"$W/err" || { tail -20 "$W/err" >&2; exit 1; }
python3 - "$W/b.json" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
r = d["rows"][0]
assert r["building"] and r["poses"] >= 30, r
assert r["z_err_p99_m"] < 0.05 and r["ate_xy_m"] < 0.05 and r["lost"] == 0, r
if r["floor_scored"]:
    assert r["wrong_floor_poses"] == 0 and r["floor_changes"] == [] and r["lift_rides"] == [], r
else:
    assert "floor" in r["floor_note"], r
print("bench building smoke (building):", r["scenario"], r["z_err_p99_m"], r.get("wrong_floor_poses"))
PY
