#!/usr/bin/env bash
# `fploc replay` ends with one line counting the poses OK / POOR / LOST on the pose channel (JSON "poses"), and
# warns when a node's initial pose lies outside its plan's extent or its drawn walls (a run started there was LOST
# throughout and said only "N node errors"): not for a matcher that waits for its initial pose, and in a building on
# the floor the node starts on. fploc replay runs over memq:// (no network).
set -uo pipefail
BIN="${FPLOC_BUILD_DIR:?}/bin"; R="${FPLOC_ROOT:?}"
T="$(mktemp -d)"; trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $1"; tail -5 "$T/err"; exit 1; }
"$BIN/fploc-sim" --scenario room-small-loop-fast --seed 3 --duration 4 --out "$T/log.lcm" --gt "$T/gt.tum" 2> "$T/sim.log" ||
  { cat "$T/sim.log"; exit 1; }
read -r X Y YAW < <(python3 -c "
import math
t,x,y,z,qx,qy,qz,qw=map(float,open('$T/gt.tum').readline().split())
print(x,y,math.atan2(2*(qw*qz+qx*qy),1-2*(qy*qy+qz*qz)))")

# From the true start: a summary line, mostly OK, no warning.
"$BIN/fploc-replay" --graph "$R/graphs/replay.pbtxt" --log "$T/log.lcm" --out "$T/a.tum" --json \
  --set matcher.initial_pose.x="$X" --set matcher.initial_pose.y="$Y" --set matcher.initial_pose.yaw="$YAW" > "$T/a.json" 2> "$T/err" ||
  fail "replay from the true start: exit $?"
line="$(grep -E '^fploc replay: [0-9]+ poses on FPLOC_POSE: [0-9]+ OK, [0-9]+ POOR, [0-9]+ LOST' "$T/err")" || fail "no pose summary line"
echo "$line"
rows="$(grep -vc '^#' "$T/a.tum")"
python3 - "$T/a.json" "$rows" <<'PY' || exit 1
import json, sys
j = json.load(open(sys.argv[1])); p = j["poses"]; rows = int(sys.argv[2])
n = p["ok"] + p["poor"] + p["lost"]
assert n == rows, f"summary counts {n} poses, the TUM file has {rows} rows"
assert p["ok"] > 0.8 * n, f"from the true start most poses should be OK: {p}"
PY
grep -q "outside its plan's extent" "$T/err" && fail "warning for a start inside the plan"

# Several pose loggers (graphs/amcl.pbtxt, lidar2d.pbtxt): the summary counts the main one's channel (FPLOC_POSE,
# as --out chooses), whatever the order of the others; a logger whose pose input is not connected counts for none.
{ cat "$R/graphs/replay.pbtxt"
  printf 'node {\n  name: "frame_logger"\n  executable: "fploc-pose-logger"\n  input { port: "pose" channel: "FPLOC_FRAME_POSE" }\n  pose_logger { file: "f.tum" }\n}\n'
  printf 'node {\n  name: "idle_logger"\n  executable: "fploc-pose-logger"\n  input { port: "pose" channel: "" }\n  pose_logger { file: "i.tum" }\n}\n'
} | sed "s#\.\./data/#$R/data/#g" > "$T/multi.pbtxt"
"$BIN/fploc-replay" --graph "$T/multi.pbtxt" --log "$T/log.lcm" --out "$T/m.tum" \
  --set matcher.initial_pose.x="$X" --set matcher.initial_pose.y="$Y" --set matcher.initial_pose.yaw="$YAW" > /dev/null 2> "$T/err" ||
  fail "replay with three pose loggers"
grep -qE '^fploc replay: [0-9]+ poses on FPLOC_POSE: ' "$T/err" || fail "the summary is not FPLOC_POSE's: $(grep 'poses on' "$T/err")"

# From (40, 40), far outside the 16 x 12.5 m room: a warning naming the node, and the summary says LOST.
"$BIN/fploc-replay" --graph "$R/graphs/replay.pbtxt" --log "$T/log.lcm" --out "$T/b.tum" \
  --set matcher.initial_pose.x=40 --set matcher.initial_pose.y=40 > /dev/null 2> "$T/err" || true
grep -qE "^fploc replay: warning: matcher's initial pose \(40, 40\) lies outside its plan's extent \(x " "$T/err" ||
  fail "no warning for an initial pose outside the plan"

grep -E '^fploc replay: [0-9]+ poses on FPLOC_POSE' "$T/err"
# A matcher that waits for its initial pose (wait_for_initial_pose) ignores the configured one: no warning about it
# (it was warned about).
"$BIN/fploc-replay" --graph "$R/graphs/replay.pbtxt" --log "$T/log.lcm" --out "$T/w.tum" \
  --set matcher.wait_for_initial_pose=true --set matcher.initial_pose.x=40 --set matcher.initial_pose.y=40 > /dev/null 2> "$T/err" || true
grep -q "initial pose (40, 40) lies outside" "$T/err" && fail "warned about the initial pose of a matcher that waits for one"
grep -qE '^fploc replay: [0-9]+ poses on FPLOC_POSE' "$T/err" || fail "replay with wait_for_initial_pose did not run"
# A building: the floor the matcher starts on (plan.floor; unset: the first, 'ground' = the demo room) is checked, and
# the warning names it and the floor whose plan holds the pose ('first' = the demo corridor, 25.8 m square about 0).
B2="$R/data/buildings/two-floors.pbtxt"
"$BIN/fploc-replay" --graph "$R/graphs/replay.pbtxt" --log "$T/log.lcm" --out "$T/f.tum" --set matcher.plan.file="$B2" \
  --set matcher.initial_pose.x=-10 --set matcher.initial_pose.y=-10 > /dev/null 2> "$T/err" || true
grep -qF "fploc replay: warning: matcher's initial pose (-10, -10) lies outside its plan's extent (x -2.25 .. 18.25, y -0.25 .. 12.75 m, floor 'ground' of $B2); it lies inside floor 'first' (--set matcher.plan.floor=first to start there)" "$T/err" ||
  fail "building, no plan.floor: no warning naming floor 'ground' and 'first'"
"$BIN/fploc-replay" --graph "$R/graphs/replay.pbtxt" --log "$T/log.lcm" --out "$T/f.tum" --set matcher.plan.file="$B2" \
  --set matcher.plan.floor=first --set matcher.initial_pose.x=-10 --set matcher.initial_pose.y=-10 > /dev/null 2> "$T/err" || true
grep -q "lies outside its plan's extent" "$T/err" && fail "building, plan.floor first: warned for a pose inside floor 'first'"
grep -qE '^fploc replay: [0-9]+ poses on FPLOC_POSE' "$T/err" || fail "replay on floor 'first' did not run"
# From (17, 11): within the plan's extent (the door leaves reach x 18.25) but outside the room's walls (x 16.25): the
# same check as `fploc node initial-pose`'s (tools/start_pose), a warning.
"$BIN/fploc-replay" --graph "$R/graphs/replay.pbtxt" --log "$T/log.lcm" --out "$T/c.tum" \
  --set matcher.initial_pose.x=17 --set matcher.initial_pose.y=11 > /dev/null 2> "$T/err" || true
grep -qE "^fploc replay: warning: matcher's initial pose \(17, 11\) lies within its plan's extent but not inside its drawn walls \(plan elements in [0-8] of 16 directions" "$T/err" ||
  fail "no warning for an initial pose outside the walls"
# graphs/ndt.pbtxt's uncertainty file ("ndt.unc", relative) is written beside --out, not into the working directory.
mkdir -p "$T/out" "$T/cwd"
(cd "$T/cwd" && "$BIN/fploc-replay" --graph "$R/graphs/ndt.pbtxt" --log "$T/log.lcm" --out "$T/out/n.tum" \
  --set ndt.initial_pose.x="$X" --set ndt.initial_pose.y="$Y" --set ndt.initial_pose.yaw="$YAW" > /dev/null 2> "$T/err") ||
  fail "ndt replay: exit $?"
[ -s "$T/out/ndt.unc" ] || fail "ndt.unc not written beside --out ($(ls "$T/out" "$T/cwd" | tr '\n' ' '))"
[ -e "$T/cwd/ndt.unc" ] && fail "ndt.unc written into the working directory"
echo OK

# A log that is not the simulator's (no FPLOC_GROUND_TRUTH: here the sim's log without it, as an import would be)
# replayed on the graph's own (demo) plan: a WARNING as the last word (JSON own_plan_without_truth); the sim's log
# itself, or a plan given with --set, none.
python3 - "$T/log.lcm" "$T/notruth.lcm" <<'PY' || exit 1
import struct, sys
src, dst = open(sys.argv[1], "rb").read(), open(sys.argv[2], "wb")
o = kept = 0
while o + 28 <= len(src):
    sync, num, ts, cl, dl = struct.unpack(">IqqII", src[o:o + 28])
    assert sync == 0xEDA1DA01
    ch = src[o + 28:o + 28 + cl]
    end = o + 28 + cl + dl
    if ch != b"FPLOC_GROUND_TRUTH":
        dst.write(struct.pack(">IqqII", sync, kept, ts, cl, dl) + src[o + 28:end]); kept += 1
    o = end
PY
"$BIN/fploc-replay" --graph "$R/graphs/replay.pbtxt" --log "$T/notruth.lcm" --out "$T/n.tum" --json > "$T/n.json" 2> "$T/err" ||
  fail "replay of a log without truth: exit $?"
tail -1 "$T/err" | grep -q "^fploc replay: WARNING: .*notruth.lcm has no FPLOC_GROUND_TRUTH (not a simulator log.*the graph's own plan (.*room.json).*--set NODE.plan.file=PLAN" ||
  fail "no demo-plan warning as the last line"
python3 -c "import json,sys; assert json.load(open(sys.argv[1]))['own_plan_without_truth'] is True" "$T/n.json" || fail "JSON own_plan_without_truth"
"$BIN/fploc-replay" --graph "$R/graphs/replay.pbtxt" --log "$T/log.lcm" --out "$T/s.tum" --json > "$T/s.json" 2> "$T/err" ||
  fail "replay of the sim log: exit $?"
grep -q "WARNING: .*not a simulator log" "$T/err" && fail "demo-plan warning for the simulator's own log"
python3 -c "import json,sys; assert json.load(open(sys.argv[1]))['own_plan_without_truth'] is False" "$T/s.json" || fail "JSON own_plan_without_truth (sim)"
sets=""
for n in matcher relocalizer optimizer; do sets="$sets --set $n.plan.file=$R/data/plans/room.json"; done
# shellcheck disable=SC2086
"$BIN/fploc-replay" --graph "$R/graphs/replay.pbtxt" --log "$T/notruth.lcm" --out "$T/g.tum" $sets > /dev/null 2> "$T/err" ||
  fail "replay with the plans given: exit $?"
grep -q "WARNING: .*not a simulator log" "$T/err" && fail "demo-plan warning with every plan given ($sets)"
echo "demo-plan warning: OK"
grep -q "initial pose .* is the graph's" "$T/err" && fail "start-pose warning with the graph's own plan given by --set"

# Another plan by --set, the graph's start pose (the demo room's) left as written: one warning saying how to give the
# start or let the relocalizer search; none once the start is given. The plan path is relative to the working directory.
cp "$R/data/plans/corridor.json" "$T/my-plan.json"
(cd "$T" && "$BIN/fploc-replay" --graph "$R/graphs/replay.pbtxt" --log "$T/log.lcm" --out "$T/h.tum" --set matcher.plan.file=my-plan.json \
  --set optimizer.plan.file=my-plan.json --set relocalizer.plan.file=my-plan.json > /dev/null 2> "$T/err") ||
  fail "replay with a plan relative to the working directory: exit $?"
grep -qF "fploc replay: warning: matcher's initial pose (5.80, 3.23) is the graph's, written for $R/data/plans/room.json, but its plan is now $T/my-plan.json: give the start in it: --set matcher.initial_pose.x=X" "$T/err" ||
  fail "no warning about the graph's start pose kept with another plan"
grep -q "wait_for_initial_pose=true" "$T/err" || fail "the warning does not say how to let the relocalizer search"
(cd "$T" && "$BIN/fploc-replay" --graph "$R/graphs/replay.pbtxt" --log "$T/log.lcm" --out "$T/h.tum" --set matcher.plan.file=my-plan.json \
  --set optimizer.plan.file=my-plan.json --set relocalizer.plan.file=my-plan.json --set matcher.initial_pose.x=1 \
  --set matcher.initial_pose.y=1 --set matcher.initial_pose.yaw=0 > /dev/null 2> "$T/err") || fail "replay with its start: exit $?"
grep -q "is the graph's, written for" "$T/err" && fail "start-pose warning with the start given"
echo "start pose with another plan: OK"
