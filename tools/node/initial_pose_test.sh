#!/usr/bin/env bash
# `fploc node initial-pose X Y YAW --graph G`: the pose is checked against the plan of the graph's localizing nodes
# (fploc/tools/start_pose.h, as `fploc replay`'s warning): far outside it is refused (exit 2, nothing sent) unless
# --force; just outside or in the plan's box but not between its walls it is sent with a warning. Then the tool
# listens for the graph's heartbeats: nothing heard -> "nothing listening ..." and exit 1 (a user trial got "sent",
# exit 0, for x 1e308 with no graph running). Inside scripts/netns-run.
source "$(dirname "${BASH_SOURCE[0]}")/../../tests/support/netns_test.sh"
require_exes fploc-launch fploc-node fploc-matcher
command -v lcm-logger > /dev/null || { echo "lcm-logger missing (liblcm-bin)"; exit 1; }
R="${FPLOC_ROOT:?}"
fail() { echo "FAIL: $1"; cat "$T/out.txt" 2>/dev/null; tail -20 "$T/launch.log" 2>/dev/null; exit 1; }
# The demo room (data/plans/room.json: walls x -0.25 .. 16.25, y -0.25 .. 12.75 m; door leaves out to x -2.25, 18.25); the matcher alone (it heartbeats while
# it waits for features), on this namespace's URL.
cat > "$T/g.pbtxt" <<G
name: "initial-pose"
lcm_url: "$URL"
shutdown_timeout_s: 2
node {
  name: "matcher"
  executable: "fploc-matcher"
  input { port: "features" channel: "" } input { port: "imu" channel: "" }
  matcher { plan { file: "$R/data/plans/room.json" } lookup: "annf-exact" initial_pose { x: 5.8 y: 3.2 yaw: -1.44 } }
}
G
pose() { "$B/fploc-node" initial-pose "$@" > "$T/out.txt" 2>&1; echo $?; }
# What reaches FPLOC_INITIAL_POSE, recorded by lcm-logger for $1 s (an LCM log without events is empty).
record_poses() {
  timeout -s INT "$1" lcm-logger --lcm-url="$URL" --channel='^FPLOC_INITIAL_POSE$' --quiet --force "$T/poses.lcm" > /dev/null 2>&1 &
  pids+=($!)
  sleep 0.5
}

# 1. Absurd coordinates, no graph running: refused, nothing sent.
record_poses 3
rc="$(pose 1e308 1 0 --graph "$T/g.pbtxt")"
[ "$rc" = 2 ] || fail "x 1e308: exit $rc, want 2"
grep -q "error: for matcher the pose (1e+308, 1) lies outside its plan's extent (x -2.25 .. 18.25, y -0.25 .. 12.75 m, $R/data/plans/room.json), 1e+308 m beyond it" "$T/out.txt" ||
  fail "x 1e308: no extent named"
grep -q "not sent: more than 2 m outside the plan of every localizing node" "$T/out.txt" || fail "x 1e308: not refused"
grep -q " sent on " "$T/out.txt" && fail "x 1e308: said sent"
wait "${pids[-1]}" || true
[ ! -s "$T/poses.lcm" ] || fail "x 1e308: a pose on the bus ($(stat -c %s "$T/poses.lcm") bytes logged)"
# 40 m outside (a typo for 4.0): refused too.
[ "$(pose 40 4 0 --graph "$T/g.pbtxt")" = 2 ] || fail "x 40: not refused"

# 2. Inside the room, no graph running: sent, but nothing listening (exit 1).
record_poses 3
rc="$(pose 5 4 90 --graph "$T/g.pbtxt")"
[ "$rc" = 1 ] || fail "no graph running: exit $rc, want 1"
wait "${pids[-1]}" || true
[ -s "$T/poses.lcm" ] || fail "inside: no pose on the bus"
grep -q "initial pose x 5 y 4 yaw 90 deg sent on FPLOC_INITIAL_POSE" "$T/out.txt" || fail "inside: not sent"
grep -q "nothing listening: no node of $T/g.pbtxt heard on FPLOC_TELEMETRY within 1.5 s: is the graph running? (fploc launch $T/g.pbtxt)" "$T/out.txt" ||
  fail "no graph running: not said"
grep -q "warning" "$T/out.txt" && fail "inside: a warning"
# --no-wait: sent, exit 0 without listening.
[ "$(pose 5 4 90 --graph "$T/g.pbtxt" --no-wait)" = 0 ] || fail "--no-wait: exit not 0"
grep -q "nothing listening" "$T/out.txt" && fail "--no-wait listened"
# --force sends a far pose (with the warning).
rc="$(pose 40 4 0 --graph "$T/g.pbtxt" --force --no-wait)"
[ "$rc" = 0 ] && grep -q "warning: for matcher the pose (40, 4) lies outside its plan's extent (x -2.25 .. 18.25, y -0.25 .. 12.75 m, .*), 21.75 m beyond it" "$T/out.txt" && grep -q " sent on " "$T/out.txt" ||
  fail "--force: exit $rc"
# Just outside (0.75 m beyond the door leaves' x 18.25): a warning, sent.
rc="$(pose 19 4 0 --graph "$T/g.pbtxt")"
[ "$rc" = 1 ] && grep -q "warning: for matcher the pose (19, 4) lies outside its plan's extent (x -2.25 .. 18.25, y -0.25 .. 12.75 m, .*), 0.75 m beyond it" "$T/out.txt" && grep -q " sent on " "$T/out.txt" ||
  fail "0.75 m outside: exit $rc"
# Within the extent but outside the walls (beside the east wall, x 16.25): a warning, sent.
rc="$(pose 17 11 0 --graph "$T/g.pbtxt" --no-wait)"
[ "$rc" = 0 ] && grep -q "warning: for matcher the pose (17, 11) lies within its plan's extent but not inside its drawn walls (plan elements in [0-8] of 16 directions" "$T/out.txt" ||
  fail "outside the walls: exit $rc"

# 3. The graph running: its matcher's heartbeat is heard, exit 0.
"$B/fploc-launch" "$T/g.pbtxt" --duration 40 > "$T/launch.log" 2>&1 & pids+=($!)
for _ in $(seq 150); do grep -q "node 'matcher' started" "$T/launch.log" && break; sleep 0.1; done
grep -q "node 'matcher' started" "$T/launch.log" || fail "the matcher did not start"
rc="$(pose 5 4 90 --graph "$T/g.pbtxt")"
[ "$rc" = 0 ] || fail "graph running: exit $rc, want 0"
grep -q "nothing listening" "$T/out.txt" && fail "graph running: nothing heard"
cat "$T/out.txt"
echo OK
