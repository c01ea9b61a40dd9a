#!/usr/bin/env bash
# fploc bench building on 4 s of two building scenarios on the demo room plan: the JSON contract (rows and
# their keys), sane values, and the z plot.
set -euo pipefail
BIN="${FPLOC_BUILD_DIR:?}/bin"
W="$(mktemp -d "${TMPDIR:-/tmp}/fploc-bench-building-XXXXXX")"
trap 'rm -rf "$W"' EXIT
"$BIN/fploc-bench-building" --plan "${FPLOC_ROOT:?}/data/plans/room.json" --scenario building-mixed-medium \
  --scenario auto-loop-medium --duration 4 --plots "$W/plots" --json >"$W/out.json" 2>"$W/err" || { tail -20 "$W/err" >&2; exit 1; }
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
assert "ceilings: mixed" in " ".join(d["rows"][0]["sim"]), d["rows"][0]
print("bench building smoke:", [(r["scenario"], r["z_err_p99_m"], r["rp_err_p99_deg"]) for r in d["rows"]])
PY
