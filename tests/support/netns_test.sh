# Sourced by the shell tests that fploc_add_netns_test runs inside scripts/netns-run (a private network
# namespace: loopback only, multicast routed to lo). After sourcing:
#   B     the build's bin folder ($FPLOC_BUILD_DIR/bin)
#   T     a temporary folder, removed at exit
#   URL   the LCM URL of the namespace (ttl 0: nothing leaves loopback)
#   pids  background processes to stop at exit: `cmd & pids+=($!)`
#   require_exes NAME...   one line naming the first missing binary, then exit 1
#   require_shared FILE    skip (exit 77, ctest's SKIP_RETURN_CODE) when ../shared/data/FILE is absent
#   gt_start_pose GT.tum   prints "x y yaw_deg" of the TUM file's first pose (e.g. a matcher's initial pose)
set -euo pipefail
B="${FPLOC_BUILD_DIR:?run through ctest (fploc_add_netns_test sets FPLOC_BUILD_DIR)}/bin"
T="$(mktemp -d)"
pids=()
fploc_test_cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$T"
}
trap fploc_test_cleanup EXIT
URL="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608"
require_exes() {
  for exe in "$@"; do
    [ -x "$B/$exe" ] || { echo "missing $B/$exe (build it first)"; exit 1; }
  done
}
require_shared() {
  [ -f "${FPLOC_SHARED_DIR:?}/data/$1" ] || { echo "no ../shared/data/$1: skipped"; exit 77; }
}
gt_start_pose() {
  python3 -c "
import math, sys
r = list(map(float, open(sys.argv[1]).readline().split()))
qx, qy, qz, qw = r[4:8]
print(r[1], r[2], math.degrees(math.atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))))" "$1"
}
