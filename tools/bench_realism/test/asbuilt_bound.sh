#!/usr/bin/env bash
# The as-built bound end to end: a world whose plan vertices stand N(0, 2 cm) off (fploc sim --perturb asbuilt-2cm
# writes the sigma into its truth), its features recorded by a replay, `fploc eval --asbuilt-bound` over them at the
# true poses: a bound of the size the room's geometry gives, twice that at twice the sigma; bad input is one error.
set -euo pipefail
B="${FPLOC_BUILD_DIR:?}/bin"
R="${FPLOC_ROOT:?}"
T="$(mktemp -d)"
trap 'rm -rf "$T"' EXIT
"$B/fploc-sim" --scenario room-small-loop-medium --perturb asbuilt-2cm --duration 3 --out "$T/sim.lcm" --gt "$T/gt.tum" 2>/dev/null
python3 -c "import json,sys; t=json.load(open(sys.argv[1])); assert t['asbuilt_sigma_m'] == 0.02, t['asbuilt_sigma_m']" "$T/sim.world.json"
"$B/fploc-replay" --graph "$R/graphs/realism.pbtxt" --log "$T/sim.lcm" --record "$T/rec.lcm" --record-channels FPLOC_FEATURES \
  --set "wo_logger.file=$T/wo.tum" --set "amcl_lidar_logger.file=$T/amcl.tum" --set "plan_diff.out_json=$T/diff.json" > /dev/null 2>&1
b() { s=$1; shift; "$B/fploc-eval" --gt "$T/gt.tum" --est "$T/gt.tum" --plan "$R/data/plans/room.json" --features "$T/rec.lcm" --asbuilt-bound "$s" "$@" --json 2>/dev/null; }
python3 - "$(b 0.02 --bound-window 2)" "$(b 0.04)" <<'PY'
import json, sys
a, b = (json.loads(x)["asbuilt_bound"] for x in sys.argv[1:3])
# Scans 1 s either side sharing the pose error (exact odometry) can only lower it.
assert a["window_s"] == 2 and 0 < a["window_rms_m"] <= a["rms_m"], a
assert "window_rms_m" not in b, b
assert a["scans"] >= 25 and a["scans_open"] == 0 and a["scans_without_gt"] == 0, a
# The room, many walls in view: a bound of a few mm at 2 cm (0.73 cm over the whole sequence).
assert 0.002 < a["rms_m"] < 0.015, a
assert 1.9 < b["rms_m"] / a["rms_m"] < 2.05, (a, b)
PY
# Bad input: no --features; a log without features (the simulator's own); a sigma that is not > 0; a features log
# cut short; a window without a bound.
rc=0; "$B/fploc-eval" --gt "$T/gt.tum" --est "$T/gt.tum" --plan "$R/data/plans/room.json" --asbuilt-bound 0.02 2> "$T/err" || rc=$?
[ "$rc" = 2 ] && grep -q "needs a SIGMA > 0 \[m\], --features LOG and --plan FILE" "$T/err" || { cat "$T/err"; echo "rc $rc"; exit 1; }
rc=0; "$B/fploc-eval" --gt "$T/gt.tum" --est "$T/gt.tum" --plan "$R/data/plans/room.json" --features "$T/sim.lcm" --asbuilt-bound 0.02 2> "$T/err" || rc=$?
[ "$rc" = 1 ] && grep -q "sim.lcm: no FPLOC_FEATURES (features_t) events among" "$T/err" || { cat "$T/err"; echo "rc $rc"; exit 1; }
test "$(grep -c . "$T/err")" -eq 1 || { cat "$T/err"; exit 1; }
rc=0; "$B/fploc-eval" --gt "$T/gt.tum" --est "$T/gt.tum" --plan "$R/data/plans/room.json" --features "$T/rec.lcm" --asbuilt-bound -0.02 2> "$T/err" || rc=$?
[ "$rc" = 2 ] || { cat "$T/err"; echo "rc $rc"; exit 1; }
# A features log cut short: the bound of the events read in the JSON, the cut said in one line, exit 1.
head -c $(( $(stat -c %s "$T/rec.lcm") * 6 / 10 )) "$T/rec.lcm" > "$T/cut.lcm"
rc=0; "$B/fploc-eval" --gt "$T/gt.tum" --est "$T/gt.tum" --plan "$R/data/plans/room.json" --features "$T/cut.lcm" --asbuilt-bound 0.02 --json > "$T/out" 2> "$T/err" || rc=$?
[ "$rc" = 1 ] && grep -q "cut.lcm: event [0-9]* at byte [0-9]*: its data length [0-9]* runs past the end of the file ([0-9]* B: truncated, or the length damaged); the [0-9]* events before it were read; the bound is of the events read" "$T/err" || { cat "$T/err"; echo "rc $rc"; exit 1; }
python3 -c "import json,sys; b=json.load(open(sys.argv[1]))['asbuilt_bound']; assert b['scans'] >= 10 and 'truncated' in b['features_problem'], b" "$T/out"
rc=0; "$B/fploc-eval" --gt "$T/gt.tum" --est "$T/gt.tum" --bound-window 10 2> "$T/err" || rc=$?
[ "$rc" = 2 ] && grep -q "read for --asbuilt-bound SIGMA only" "$T/err" || { cat "$T/err"; echo "rc $rc"; exit 1; }
echo "asbuilt bound: ok"
