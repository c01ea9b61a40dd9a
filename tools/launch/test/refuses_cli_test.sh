#!/usr/bin/env bash
# fploc launch refuses to start, exit 1, no node started, when (1) a file an option names does not exist (`--check`
# found it, but a launch started every other node while the matcher died five times), or (2) nodes of the same graph
# already run on its LCM bus (a second launch of the graph mixed both runs' messages). A clean run's shutdown exits
# 0. Inside scripts/netns-run.
set -uo pipefail
L="${FPLOC_BUILD_DIR:?}/bin/fploc-launch"; R="${FPLOC_ROOT:?}"
T="$(mktemp -d)"; trap 'kill $first 2>/dev/null; rm -rf "$T"' EXIT
first=""
fail() { echo "FAIL: $1"; echo "$out" | tail -8; exit 1; }

# (1) A missing plan: the same error as --check, nothing started.
out="$(timeout 30 "$L" "$R/graphs/demo.pbtxt" --set matcher.plan.file="$T/nope.json" 2>&1)"; rc=$?
[ "$rc" = 1 ] || fail "missing plan: exit $rc, expected 1"
echo "$out" | grep -q "node 'matcher': matcher.plan.file '$T/nope.json' does not exist" || fail "missing plan: no error naming it"
echo "$out" | grep -q "started" && fail "missing plan: a node was started"

# (2) A second launch of a running graph.
"$L" "$R/graphs/import.pbtxt" --duration 12 > "$T/first.log" 2>&1 &
first=$!
for _ in $(seq 100); do grep -q "node 'features' started" "$T/first.log" && break; sleep 0.1; done
sleep 2.5  # the nodes' first heartbeats
t0=$(date +%s.%N)
out="$(timeout 30 "$L" "$R/graphs/import.pbtxt" --duration 5 2>&1)"; rc=$?
[ "$rc" = 1 ] || fail "second launch: exit $rc, expected 1"
echo "$out" | grep -Eq "refusing to start: a node named '(segmenter|features)' \(pid [0-9]+.*\) already runs on udpm://" ||
  fail "second launch: no error naming the running node"
echo "$out" | grep -q "started" && fail "second launch: a node was started"
# The first run goes on undisturbed and exits 0 at its duration.
wait $first; rc=$?; first=""
out="$(cat "$T/first.log")"
[ "$rc" = 0 ] || fail "first launch: exit $rc after its duration, expected 0"
echo "$out" | grep -q "all nodes stopped$" || fail "first launch: no clean stop"
# Once it is gone, the graph starts again.
out="$(timeout 30 "$L" "$R/graphs/import.pbtxt" --duration 2 2>&1)"; rc=$?
[ "$rc" = 0 ] || fail "launch after the first ended: exit $rc, expected 0"
echo OK
