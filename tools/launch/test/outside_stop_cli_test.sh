#!/usr/bin/env bash
# A node of a launched graph stopped by someone else's SIGTERM (`kill PID`, not the launcher) exits 128 + 15 and
# the graph's restart policy (on failure) restarts it; it exited 0 and stayed stopped ("exited with code 0"). The
# launcher's own stop (Ctrl-C, --duration) still ends the run cleanly, exit 0. Inside scripts/netns-run.
set -uo pipefail
L="${FPLOC_BUILD_DIR:?}/bin/fploc-launch"; R="${FPLOC_ROOT:?}"
T="$(mktemp -d)"; trap 'kill $pid 2>/dev/null; rm -rf "$T"' EXIT
fail() { echo "FAIL: $1"; tail -15 "$T/launch.log"; exit 1; }
"$L" "$R/graphs/import.pbtxt" --duration 14 > "$T/launch.log" 2>&1 &
pid=$!
node=""
for _ in $(seq 100); do
  node="$(sed -n "s/.*node 'features' started: pid \([0-9]*\),.*/\1/p" "$T/launch.log" | head -1)"
  [ -n "$node" ] && break
  sleep 0.1
done
[ -n "$node" ] || fail "features never started"
sleep 2
kill -TERM "$node"
for _ in $(seq 60); do grep -q "node 'features' started: .*restart 1" "$T/launch.log" && break; sleep 0.1; done
grep -q "\[features\] stopped by Terminated from pid [0-9]*, not the launcher: exit code 143" "$T/launch.log" || fail "no note of the outside stop"
grep -q "node 'features' exited with code 143; restarting in" "$T/launch.log" || fail "not restarted as a failure"
grep -q "node 'features' started: .*restart 1" "$T/launch.log" || fail "no restart"
wait $pid; rc=$?; pid=""
[ "$rc" = 0 ] || fail "launcher exit $rc after its duration, expected 0"
grep -q "all nodes stopped$" "$T/launch.log" || fail "no clean stop"
# The launcher's own stop (here its --duration) is no outside stop: the restarted node stops with code 0.
grep -q "node 'features' stopped (exited with code 0)" "$T/launch.log" || fail "the launcher's stop did not end features with code 0"
echo OK
