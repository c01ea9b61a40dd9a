#!/usr/bin/env bash
# fploc launch --duration that is not a number of seconds > 0: one error naming it, exit 2, no node started
# (atof read "ten" as 0: the graph ran until Ctrl-C; "nan" likewise). Inside scripts/netns-run.
set -uo pipefail
L="${FPLOC_BUILD_DIR:?}/bin/fploc-launch"; G="${FPLOC_ROOT:?}/graphs/import.pbtxt"
for d in ten nan -3 0 10x; do
  out="$(timeout 20 "$L" "$G" --duration "$d" 2>&1)"; rc=$?
  [ "$rc" = 2 ] || { echo "FAIL: --duration $d: exit $rc, expected 2"; echo "$out" | tail -3; exit 1; }
  [ "$out" = "fploc launch: --duration $d: expected a number of seconds > 0" ] || { echo "FAIL: --duration $d: $out"; exit 1; }
done
echo OK
