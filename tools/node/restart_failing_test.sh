#!/usr/bin/env bash
# `fploc node restart` of a node in state "failing" (running, but not doing its job: Context::set_failing): the tool
# learns its pid from the failing heartbeats and recognises the successor by its pid, failing or not. Here a dashboard
# whose port another process holds fails before and after its restart. Without "failing" counted as alive the tool
# learnt no pid and never saw a successor: "no answer within 8 s", exit 1. Inside scripts/netns-run.
source "$(dirname "${BASH_SOURCE[0]}")/../../tests/support/netns_test.sh"
require_exes fploc-launch fploc-node fploc-dashboard
R="${FPLOC_ROOT:?}"
fail() { echo "FAIL: $1"; tail -20 "$T/launch.log"; cat "$T/node.txt" 2>/dev/null; exit 1; }
# The port, held by someone else for the whole test (loopback, inside the namespace).
python3 -c '
import socket, sys, time
s = socket.socket(); s.bind(("127.0.0.1", 18181)); s.listen(1); print("held", flush=True); time.sleep(120)' > "$T/holder.txt" &
pids+=($!)
for _ in $(seq 50); do grep -q held "$T/holder.txt" && break; sleep 0.1; done
cat > "$T/g.pbtxt" <<G
name: "restart-failing"
lcm_url: "$URL"
shutdown_timeout_s: 2
node {
  name: "dashboard"
  executable: "fploc-dashboard"
  input { port: "telemetry" channel: "FPLOC_TELEMETRY" }
  input { port: "pose" channel: "" } input { port: "frame_pose" channel: "" }
  input { port: "features" channel: "" } input { port: "ground_truth" channel: "" }
  dashboard { plan { file: "$R/data/plans/room.json" } bind: "127.0.0.1" port: 18181 }
}
G
"$B/fploc-launch" "$T/g.pbtxt" --duration 30 > "$T/launch.log" 2>&1 & pids+=($!)
for _ in $(seq 100); do grep -q "cannot listen on 127.0.0.1:18181" "$T/launch.log" && break; sleep 0.1; done
grep -q "cannot listen on 127.0.0.1:18181" "$T/launch.log" || fail "the dashboard did not fail to listen"
old="$(sed -n "s/.*node 'dashboard' started: pid \([0-9]*\),.*/\1/p" "$T/launch.log" | head -1)"
[ -n "$old" ] || fail "no pid of the dashboard"
sleep 1.5  # a heartbeat saying "failing"
"$B/fploc-node" restart dashboard --graph "$T/g.pbtxt" --timeout 8 > "$T/node.txt" 2>&1 || fail "restart of a failing node: exit $?"
cat "$T/node.txt"
new="$(sed -n "s/.*'dashboard' running again as pid \([0-9]*\) (was \([0-9]*\)).*/\1 \2/p" "$T/node.txt")"
[ -n "$new" ] || fail "the restart did not name the new and the old pid"
set -- $new
[ "$2" = "$old" ] || fail "old pid $2, the launcher started $old"
[ "$1" != "$old" ] || fail "the new pid is the old one"
grep -q "node 'dashboard' started: pid $1," "$T/launch.log" || fail "the launcher did not start pid $1"
echo OK
