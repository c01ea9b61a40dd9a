#!/usr/bin/env bash
# `fploc sim --help` names every --perturb key the parser takes (it listed 9 of 14: doors_moved, move_min, move_max,
# door_shift_min and door_shift_max were missing). The keys are taken from the parser's own error for an unknown key,
# so a key added to the parser and not to the help fails here.
set -euo pipefail
B="${FPLOC_BUILD_DIR:?run through ctest}/bin"
T="$(mktemp -d)"
trap 'rm -rf "$T"' EXIT
rc=0
"$B/fploc-sim" --scenario room-small-loop-medium --perturb wobble=1 --duration 1 --out "$T/x.lcm" --gt "$T/x.tum" 2> "$T/err" || rc=$?
[ "$rc" != 0 ] || { echo "--perturb wobble=1 accepted"; exit 1; }
keys=$(sed -n "s/.*unknown key 'wobble' (keys: \([^)]*\)).*/\1/p" "$T/err" | tr -d ' ' | tr ',' ' ')
[ -n "$keys" ] || { echo "no key list in the error:"; cat "$T/err"; exit 1; }
"$B/fploc-sim" --help > "$T/help" 2>&1
# CLI11 wraps the help text: join it into one line.
help=$(tr -s ' \n' '  ' < "$T/help")
n=0
for k in $keys; do
  n=$((n + 1))
  grep -qw -- "$k" <<< "$help" || { echo "--help does not name --perturb key $k:"; cat "$T/help"; exit 1; }
done
[ "$n" -ge 14 ] || { echo "only $n keys in the parser's list: $keys"; exit 1; }
echo "sim --help: all $n --perturb keys"
