#!/bin/sh
# grid2d without a start pose, through graphs/lidar2d.pbtxt (fploc replay, lock-step): intel's map from the first
# half, scans 50-60 % replayed with only the plan given to grid2d (no initial_pose: global localization). Its poses
# are not OK until it has locked, the first OK pose is within 0.3 m / 5 deg of the reference, no OK pose is more
# than 0.3 m off, it says so on stderr, and a --set initial_pose still starts it there (tracked from the first scan).
# Its global lock starts the matcher there (grid2d.lock -> FPLOC_INITIAL_POSE): the pipeline's own poses (est.tum,
# FPLOC_POSE) from 20 scans after the lock lie within 0.3 m of the reference (the matcher alone, started at the graph's
# (0, 0, 0), was lost: ATE 34 m on intel); grid2d's TUM holds no placeholder pose of its search (status 3, not logged),
# and the summary counts every logged pose channel.
set -e
LOG="$FPLOC_SHARED_DIR/data/recordings/radish/intel-corrected.log.gz"
if [ ! -f "$LOG" ]; then echo "SKIP: $LOG absent (shared data)"; exit 0; fi
B="$FPLOC_BUILD_DIR/bin"
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
"$B/fploc-import-carmen" "$LOG" --out "$T/rest.lcm" --tum "$T/ref.tum" --map "$T/map" --begin 0.5 --map-begin 0 \
  --map-end 0.5 --end 0.6 --json > "$T/imp.json"
M="$T/map/map.yaml"
sets="--set matcher.plan.file=$M --set optimizer.plan.file=$M --set amcl.plan.file=$M --set grid2d.plan.file=$M"
sets="$sets --set grid_logger.file=$T/grid.tum --set grid_logger.uncertainty_file=$T/grid.status"
# shellcheck disable=SC2086
"$B/fploc-replay" --graph "$FPLOC_ROOT/graphs/lidar2d.pbtxt" --log "$T/rest.lcm" --out "$T/est.tum" $sets \
  --set wo_logger.uncertainty_file="$T/est.status" --json > "$T/sum.json" 2> "$T/err"
grep -q "^\[grid2d\] .*no initial pose: global localization" "$T/err" || { cat "$T/err"; echo "global start not said"; exit 1; }
grep -q "^\[grid2d\] scan 0: LOST: global localization" "$T/err" || { cat "$T/err"; echo "global search not said"; exit 1; }
grep -q "^\[grid2d\] scan [0-9]*: global lock at .* published on FPLOC_INITIAL_POSE" "$T/err" || { cat "$T/err"; echo "lock not published"; exit 1; }
grep -qE "^fploc replay: [0-9]+ poses on FPLOC_GRID_POSE \(grid_logger\): [0-9]+ OK, [0-9]+ POOR, [0-9]+ LOST, [0-9]+ no estimate yet" "$T/err" || { cat "$T/err"; echo "no grid2d summary"; exit 1; }
X=$(python3 -c "import math, sys; l=[v for v in open(sys.argv[1]) if v[0]!='#'][0].split(); print(l[1], l[2], 2 * math.atan2(float(l[6]), float(l[7])))" "$T/ref.tum")
set -- $X
# shellcheck disable=SC2086
"$B/fploc-replay" --graph "$FPLOC_ROOT/graphs/lidar2d.pbtxt" --log "$T/rest.lcm" --out "$T/est2.tum" $sets \
  --set grid_logger.file="$T/grid2.tum" --set grid_logger.uncertainty_file="$T/grid2.status" \
  --set grid2d.initial_pose.x="$1" --set grid2d.initial_pose.y="$2" --set grid2d.initial_pose.yaw="$3" > /dev/null 2> "$T/err2" || { cat "$T/err2"; exit 1; }
python3 - "$T" <<'PY'
import math, sys
d = sys.argv[1]
def tum(p):
    out = {}
    for l in open(p):
        v = l.split()
        if v and not v[0].startswith("#"):
            out[round(float(v[0]), 4)] = (float(v[1]), float(v[2]), 2 * math.atan2(float(v[6]), float(v[7])))
    return out
def status(p):
    return {round(float(l.split()[0]), 4): int(l.split()[1]) for l in open(p) if l.strip() and not l.startswith("#")}
ref = tum(f"{d}/ref.tum")
for run in ("grid", "grid2"):
    est, st = tum(f"{d}/{run}.tum"), status(f"{d}/{run}.status")
    ts = sorted(est)
    ok = [t for t in ts if st.get(t) == 0]
    assert ok, f"{run}: never OK"
    err = lambda t: math.hypot(est[t][0] - ref[t][0], est[t][1] - ref[t][1])
    t0 = ok[0]
    dyaw = abs((est[t0][2] - ref[t0][2] + math.pi) % (2 * math.pi) - math.pi) * 180 / math.pi
    wrong = [t for t in ok if err(t) > 0.3]
    print(f"{run}: {len(ts)} poses, first OK at pose {ts.index(t0)} ({err(t0):.3f} m, {dyaw:.2f} deg off), "
          f"{len(ok)} OK, {len(wrong)} more than 0.3 m off")
    assert err(t0) <= 0.3 and dyaw <= 5, (err(t0), dyaw)
    assert not wrong, wrong
    if run == "grid":
        # No placeholder of the search logged: the first pose written is the lock, at the reference's 5th scan or later.
        assert ts[0] == t0, f"{ts.index(t0)} poses logged before the lock (placeholders)"
        assert sorted(ref).index(t0) >= 4, "OK before 5 scans matched: not the global rule"
        lock = t0
    else:
        assert ts.index(t0) == 0, "a start pose given: tracked from the first scan"
# The pipeline (matcher + optimizer, FPLOC_POSE) started at grid2d's lock: from 20 scans after it, near the reference.
est = tum(f"{d}/est.tum")
after = [t for t in sorted(est) if t > lock and t in ref][20:]
assert len(after) > 20, len(after)
errs = sorted(math.hypot(est[t][0] - ref[t][0], est[t][1] - ref[t][1]) for t in after)
med, p90 = errs[len(errs) // 2], errs[int(0.9 * len(errs))]
print(f"est (FPLOC_POSE): {len(after)} poses from 20 scans after the lock: median {med:.3f} m, 90th pct {p90:.3f} m")
assert med < 0.3 and p90 < 0.5, (med, p90)
import json
j = json.load(open(f"{d}/sum.json"))
chans = {c["channel"]: c for c in j["pose_channels"]}
assert {"FPLOC_POSE", "FPLOC_GRID_POSE", "FPLOC_FRAME_POSE", "FPLOC_AMCL_POSE"} <= set(chans), chans
assert chans["FPLOC_GRID_POSE"]["no_estimate"] >= 4 and chans["FPLOC_GRID_POSE"]["ok"] > 0, chans
assert j["poses"]["channel"] == "FPLOC_POSE"
PY
echo OK
