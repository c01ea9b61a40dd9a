#!/usr/bin/env bash
# scripts/demo-screenshot.sh [OUT.png] [SECONDS] [GRAPH]: runs the README's demo (graphs/demo.pbtxt, or GRAPH,
# e.g. graphs/demo-building.pbtxt) in a private network namespace and saves a screenshot of its dashboard after
# SECONDS (default 35), e.g. for the README (docs/img/demo.png). Needs the browser-test dependencies
# (scripts/setup-web.sh).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="$(realpath -m "${1:-$ROOT/docs/img/demo.png}")"
WAIT="${2:-35}"
GRAPH="$(realpath -m "${3:-$ROOT/graphs/demo.pbtxt}")"
[ -f "$GRAPH" ] || { echo "demo-screenshot.sh: no graph file $GRAPH" >&2; exit 2; }
if [ "${FPLOC_IN_NETNS:-}" != "1" ]; then exec "$ROOT/scripts/netns-run" "$0" "$OUT" "$WAIT" "$GRAPH"; fi
LOG="${FPLOC_DEMO_DIR:-/tmp}/fploc-demo-screenshot.log"  # beside the demo graph's own files
"$ROOT/bin/fploc" launch "$GRAPH" --duration "$((WAIT + 15))" 2> "$LOG" &
L=$!
# Until the dashboard answers (bin/fploc may first bring the build up to date), at most 10 minutes.
for _ in $(seq 3000); do
  (exec 3<>/dev/tcp/127.0.0.1/8080) 2>/dev/null && break
  kill -0 "$L" 2>/dev/null || { echo "fploc launch exited; see $LOG" >&2; exit 1; }
  sleep 0.2
done
(cd "$ROOT/tests/dashboard" && node screenshot.mjs http://127.0.0.1:8080/ "$OUT" "$(( (WAIT - 3) * 1000 ))")
kill -INT "$L" 2>/dev/null || true
wait "$L" || true
