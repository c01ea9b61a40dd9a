#!/usr/bin/env bash
# A remote host that cannot be reached, at the start and during a run (the user trial: the remote nodes ended dead
# after five restarts and stayed dead once the host was back). Two network namespaces (drv: the launcher and a local
# node; compute: an sshd and two remote nodes) joined by veth pairs to a bridge, all inside `unshare -n -m`: no
# address or route outside the test's namespaces. The host goes away and comes back with `ip link set v-compute
# down|up` (its veth on the bridge).
#  (1) compute unreachable at the start: `fploc launch` refuses (exit 1), naming the host and its nodes; nothing starts.
#  (2) --wait-for-hosts: the local node runs, the remote nodes wait for the host (launcher log, telemetry state
#      "waiting"), and run once the link is back (the time is printed).
#  (3) a running graph whose remote host is away for OUTAGE_S (25) seconds: the remote nodes wait for the host
#      instead of spending their restart budget, and run (and report) again afterwards; the local node is untouched.
#      (Before, their ssh sessions failed five times within ~19 s and they stayed dead.)
#  (4) a remote node that itself exits 255 (ssh's own failure code) on a reachable host still ends dead.
# Skips (exit 77) without root, unshare, ip or sshd.
set -euo pipefail
BIN="${FPLOC_BUILD_DIR:?}/bin"
skip() { echo "SKIP: $*"; exit 77; }
if [ "${FPLOC_HD_INNER:-}" != "1" ]; then
  [ "$(id -u)" -eq 0 ] || skip "needs root (network namespaces, veth, an sshd)"
  for c in unshare ip ssh ssh-keygen /usr/sbin/sshd pgrep awk; do
    command -v "$c" >/dev/null 2>&1 || skip "$c not found (apt-get install iproute2 openssh-client openssh-server procps)"
  done
  exec unshare -n -m -- env FPLOC_HD_INNER=1 "$0" "$@"
fi
OUTAGE_S="${OUTAGE_S:-25}"
. "$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/hosts_lib.sh"
mh_private_view hd
T="$(mktemp -d /tmp/fploc-hd-XXXXXX)"
G="$T/g.pbtxt"
HOSTS=(drv compute)
bg=()   # launchers and probes started here
cleanup() {
  set +e
  for p in "${bg[@]}"; do kill -KILL "$p" 2>/dev/null; done
  [ -f "$T/sshd-compute.pid" ] && kill "$(cat "$T/sshd-compute.pid")" 2>/dev/null
  for p in $(pgrep -f -- "--graph $T/"); do kill -KILL "$p" 2>/dev/null; done  # this test's graphs only (unique dir)
  for h in "${HOSTS[@]}"; do ip netns del "$h" 2>/dev/null; done
  umount /run/netns 2>/dev/null
  [ -n "${KEEP:-}" ] || rm -rf "$T"
}
trap cleanup EXIT
now() { date +%s.%N; }
since() { awk -v a="$(date +%s.%N)" -v b="$1" 'BEGIN { printf "%.2f", a - b }'; }
# wait_until SECONDS COMMAND...: polls every 0.1 s; 0 once COMMAND succeeds, 1 after SECONDS.
wait_until() {
  local end; end=$(awk -v a="$(date +%s.%N)" -v d="$1" 'BEGIN { printf "%.3f", a + d }'); shift
  while ! "$@"; do
    awk -v a="$(date +%s.%N)" -v e="$end" 'BEGIN { exit !(a > e) }' && return 1
    sleep 0.1
  done
}
fail=0
FAIL() { echo "FAIL: $*"; fail=1; }
node_pid() { pgrep -f -- "^$BIN/fploc-[a-z0-9-]+ --graph $G --node $1( |\$)" || true; }  # the node process itself
remote_running() { [ -n "$(node_pid logger)" ] && [ -n "$(node_pid source2)" ]; }
remote_new() { local a b; a=$(node_pid logger); b=$(node_pid source2)
               [ -n "$a" ] && [ -n "$b" ] && [ "$a" != "$old_logger" ] && [ "$b" != "$old_source2" ]; }
# A line of the states file (fploc-test-lcm-probe --states) received after wall time $2 (seconds) matching $1.
state_after() { awk -v t="$2" -v re="$1" '$1 == "state" && $2 / 1e6 >= t && $0 ~ re { found = 1 } END { exit !found }' "$T/states.txt"; }

# ---- the network: a bridge and a veth per host namespace, an sshd on compute
mh_bridge "${HOSTS[@]}"
mh_client_key "$T" fploc-hd-test
mh_sshd "$T" compute 10.213.0.2
SSHO="-o BatchMode=yes -o StrictHostKeyChecking=no -o UserKnownHostsFile=/dev/null -o LogLevel=ERROR -i $T/id"
wait_until 10 ip netns exec drv ssh $SSHO root@10.213.0.2 true 2>/dev/null || { echo "sshd on compute not reachable"; exit 1; }

# ---- the graphs: a local pose source; on compute a pose logger (fed from drv across the link) and a second source.
URL="udpm://239.255.76.67:7667?recv_buf_size=4194304"
HOST="host { name: \"compute\" address: \"10.213.0.2\" user: \"root\" ssh_option: \"IdentityFile=$T/id\"
       ssh_option: \"StrictHostKeyChecking=no\" ssh_option: \"UserKnownHostsFile=/dev/null\" }"
cat > "$G" <<EOF
name: "host-down"
lcm_url: "$URL"
lcm_ttl: 1
shutdown_timeout_s: 2
$HOST
node { name: "source" executable: "fploc-test-pose-source" }
node { name: "logger" executable: "fploc-pose-logger" host: "compute"
       input { port: "pose" channel: "FPLOC_POSE" } pose_logger { file: "$T/logger.tum" } }
node { name: "source2" executable: "fploc-test-pose-source" host: "compute"
       output { port: "pose" channel: "FPLOC_POSE2" } }
EOF
cat > "$T/crash.pbtxt" <<EOF
name: "host-up-node-crashes"
lcm_url: "$URL"
lcm_ttl: 1
$HOST
node { name: "crasher" executable: "sh" args: "-c" args: "exit 255" host: "compute"
       restart { max_restarts: 3 window_s: 60 backoff_initial_s: 0.1 } }
EOF
ip netns exec drv "$BIN/fploc-launch" --check "$G" 2> "$T/check.log" || { cat "$T/check.log"; FAIL "--check with the host up"; }
ip netns exec drv "$BIN/fploc-test-lcm-probe" --url "$URL" --out "$T/states.txt" --duration 600 --states FPLOC_TELEMETRY &
bg+=($!)

# ---- (1) the host is away at the start: the launch refuses, naming the host and the nodes on it
ip link set v-compute down
rc=0
t0=$(now)
timeout 60 ip netns exec drv "$BIN/fploc-launch" "$G" --duration 5 2> "$T/refuse.log" || rc=$?
echo "(1) host away at the start: launch exit $rc after $(since "$t0") s:"
grep -v "^\[launch" "$T/refuse.log" | head -5 || true
[ "$rc" = 1 ] || FAIL "(1) exit $rc, expected 1"
grep -q "host 'compute'.*not reachable.*'logger'.*'source2'" "$T/refuse.log" ||
  FAIL "(1) no error naming host 'compute' and its nodes 'logger', 'source2'"
grep -q "started" "$T/refuse.log" && FAIL "(1) a node was started"

# ---- (2) --wait-for-hosts: the local part runs, the remote nodes wait for the host and start when it is back
t_launch=$(now)
ip netns exec drv "$BIN/fploc-launch" "$G" --wait-for-hosts 2> "$T/wait.log" &
L=$!; bg+=($L)
wait_until 20 grep -q "node 'source' started" "$T/wait.log" || FAIL "(2) the local node did not start"
wait_until 20 grep -q "waiting for host 'compute'" "$T/wait.log" || FAIL "(2) the launcher did not say the nodes wait"
wait_until 10 state_after "logger launcher waiting .*host 'compute'" "$t_launch" ||
  FAIL "(2) no telemetry state 'waiting' (naming host 'compute') for the remote logger"
grep -m3 "compute" "$T/wait.log" || true
sleep 3
[ -z "$(node_pid logger)" ] || FAIL "(2) the logger runs although its host is away"
t_up=$(now)
ip link set v-compute up
back=""
wait_until 40 remote_running && back=$(since "$t_up")
beat=""
wait_until 20 state_after "logger node running" "$t_up" && beat=$(since "$t_up")
echo "(2) host back -> remote nodes running after ${back:-never} s, the logger's first heartbeat after ${beat:-never} s"
[ -n "$back" ] || FAIL "(2) the remote nodes did not start once the host was back"
[ -n "$beat" ] || FAIL "(2) no heartbeat of the remote logger once the host was back"
grep "host 'compute'.*answers\|node 'logger' started" "$T/wait.log" || true
kill -INT $L 2>/dev/null || true
rc=0; wait $L || rc=$?
[ "$rc" = 0 ] || { tail -5 "$T/wait.log"; FAIL "(2) launcher exit $rc after Ctrl-C, expected 0"; }

# ---- (3) the host goes away for OUTAGE_S seconds during a run: the remote nodes wait for it, then run again
t_launch=$(now)
ip netns exec drv "$BIN/fploc-launch" "$G" 2> "$T/run.log" &
L=$!; bg+=($L)
wait_until 30 remote_running || FAIL "(3) the remote nodes did not start"
wait_until 20 state_after "logger node running" "$t_launch" || FAIL "(3) no heartbeat of the remote logger"
old_logger=$(node_pid logger) old_source2=$(node_pid source2) old_source=$(node_pid source)
sleep 1
t_down=$(now)
ip link set v-compute down
said=""
wait_until $((OUTAGE_S - 2)) grep -q "waiting for host 'compute'" "$T/run.log" && said=$(since "$t_down")
echo "(3) link down: the launcher said the nodes wait for host 'compute' after ${said:-never} s"
[ -n "$said" ] || FAIL "(3) the launcher did not say the remote nodes wait for their host"
sleep "$(awk -v a="$(date +%s.%N)" -v b="$t_down" -v d="$OUTAGE_S" 'BEGIN { r = b + d - a; printf "%.2f", (r > 0 ? r : 0) }')"
t_up=$(now)
ip link set v-compute up
back=""
wait_until 40 remote_new && back=$(since "$t_up")
beat=""
wait_until 20 state_after "logger node running" "$t_up" && beat=$(since "$t_up")
echo "(3) host away for $(awk -v a="$t_up" -v b="$t_down" 'BEGIN { printf "%.1f", a - b }') s; back -> remote nodes running" \
     "after ${back:-never} s (logger pid $old_logger -> $(node_pid logger)), the logger's first heartbeat after ${beat:-never} s"
[ -n "$back" ] || FAIL "(3) the remote nodes are not running again after the host came back"
[ -n "$beat" ] || FAIL "(3) no heartbeat of the remote logger after the host came back"
state_after "logger launcher waiting" "$t_down" || FAIL "(3) no telemetry state 'waiting' for the logger during the outage"
grep "giving up" "$T/run.log" && FAIL "(3) the launcher gave a node up while its host was away"
grep -E "node '(logger|source2)' .*restarting in" "$T/run.log" && FAIL "(3) a restart was spent while the host was away"
[ "$(node_pid source)" = "$old_source" ] || FAIL "(3) the local node was restarted"
grep "compute" "$T/run.log" | grep -v "^\[logger@\|^\[source2@" | tail -n +3 | head -12 || true
kill -INT $L 2>/dev/null || true
rc=0; wait $L || rc=$?
[ "$rc" = 0 ] || { tail -5 "$T/run.log"; FAIL "(3) launcher exit $rc after Ctrl-C, expected 0"; }

# ---- (4) the host is there and the node itself exits 255 every time: it still ends dead (no endless wait)
t0=$(now)
rc=0
timeout 60 ip netns exec drv "$BIN/fploc-launch" "$T/crash.pbtxt" --duration 40 2> "$T/crash.log" || rc=$?
echo "(4) a remote node exiting 255 on a reachable host: launch exit $rc after $(since "$t0") s"
grep "giving up\|answers" "$T/crash.log" | head -3 || true
[ "$rc" = 1 ] || FAIL "(4) exit $rc, expected 1 (the node dead)"
grep -q "node 'crasher'.*giving up (dead)" "$T/crash.log" || FAIL "(4) the crashing node was not given up"

[ "$fail" = 0 ] || { for f in wait run crash; do echo "--- $f.log"; tail -25 "$T/$f.log"; done; exit 1; }
echo PASS
