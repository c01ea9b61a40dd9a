#!/usr/bin/env bash
# One stop delivered twice at once (GNU `timeout` signals the launcher and then its process group; systemd's
# control-group stop does the same) is one stop: every node is stopped in order and exits 0, the launcher exits 0.
# It was taken as a second signal ("second signal: killing every node now"): every node SIGKILLed, exit 1, a pose
# logger's last lines lost. A second Ctrl-C later than 0.5 s still kills at once. Inside scripts/netns-run.
set -uo pipefail
L="${FPLOC_BUILD_DIR:?}/bin/fploc-launch"; R="${FPLOC_ROOT:?}"
T="$(mktemp -d)"; trap 'kill -9 $pid 2>/dev/null; rm -rf "$T"' EXIT
fail() { echo "FAIL: $1"; tail -15 "$T/launch.log"; exit 1; }
"$L" "$R/graphs/import.pbtxt" --duration 60 > "$T/launch.log" 2>&1 &
pid=$!
for _ in $(seq 100); do grep -q "node 'features' started" "$T/launch.log" && break; sleep 0.1; done
grep -q "node 'features' started" "$T/launch.log" || fail "features never started"
sleep 2
kill -TERM "$pid"; sleep 0.05; kill -TERM "$pid"  # two deliveries (at once they may merge into one)
wait $pid; rc=$?; pid=""
grep -q "second signal" "$T/launch.log" && fail "the doubled stop was taken as a second signal"
[ "$rc" = 0 ] || fail "launcher exit $rc, expected 0"
grep -q "all nodes stopped$" "$T/launch.log" || fail "no clean stop"
grep -q "node 'features' stopped (exited with code 0)" "$T/launch.log" || fail "features did not stop with code 0"
echo OK
