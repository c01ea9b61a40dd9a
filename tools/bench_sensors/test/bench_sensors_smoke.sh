#!/usr/bin/env bash
# fploc bench sensors on 4 s of the small room with a VLP-16-like and an OS-1-128 beam pattern: the JSON
# contract (rows and their keys) and sane values.
set -euo pipefail
BIN="${FPLOC_BUILD_DIR:?}/bin"
W="$(mktemp -d "${TMPDIR:-/tmp}/fploc-bench-sensors-XXXXXX")"
trap 'rm -rf "$W"' EXIT
"$BIN/fploc-bench-sensors" --beams vlp16,os1-128 --scenario room-small-loop-medium --duration 4 --json \
  >"$W/out.json" 2>"$W/err" || { tail -20 "$W/err" >&2; exit 1; }
python3 - "$W/out.json" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
assert [r["beams"] for r in d["rows"]] == ["vlp16", "os1-128"], d
for r in d["rows"]:
    for k in ("beams", "beam_source", "scenario", "ate_xy_m", "z_err_median_m", "z_err_p99_m", "lost", "ms_per_scan"):
        assert k in r and r[k] is not None, (k, r)
    assert r["poses"] >= 35, r
    assert r["ate_xy_m"] < 0.05 and r["lost"] == 0, r
    assert set(r["ms_per_scan"]) == {"segmenter", "features", "matcher", "optimizer"}, r
print("bench sensors smoke:", [(r["beams"], r["ate_xy_m"], r["z_err_p99_m"]) for r in d["rows"]])
PY
