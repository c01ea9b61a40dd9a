#!/bin/sh
# fploc os1 decode on a capture cut short: one error naming the file, exit 1, and the summary of what was read
# before the cut (it printed the error and exited 0). Skips without ../shared/data.
set -e
DECODE="$1"; O="$2/data/ouster"
if [ ! -f "$O/OS-1-64_1024x10_fw20.pcap" ]; then echo "SKIP: no $O"; exit 0; fi
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
P="$O/OS-1-64_1024x10_fw20.pcap"; M="$O/OS-1-64_sensor_config_reduced.json"
"$DECODE" --pcap "$P" --metadata "$M" --json > "$T/full.json" 2> /dev/null || fail "whole capture"
head -c $(( $(wc -c < "$P") / 2 )) "$P" > "$T/cut.pcap"
rc=0
"$DECODE" --pcap "$T/cut.pcap" --metadata "$M" --json > "$T/cut.json" 2> "$T/err" || rc=$?
[ "$rc" = 1 ] || fail "cut capture: exit $rc, expected 1"
[ "$(grep -c "^fploc os1 decode: $T/cut.pcap: .*truncated" "$T/err")" = 1 ] || { cat "$T/err"; fail "error text"; }
python3 - "$T/cut.json" <<'PY' || fail "summary of the part before the cut"
import json, sys
j = json.load(open(sys.argv[1]))
assert j["packets"] > 0 and len(j["errors"]) == 1, (j["packets"], j["errors"])
PY
echo OK
