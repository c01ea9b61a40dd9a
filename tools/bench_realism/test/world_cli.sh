#!/usr/bin/env bash
# fploc sim --world / --perturb at the command line: a world file that does not parse and an unknown
# perturbation are one clear error each (file, byte / key), exit 1, nothing written; a good world file
# writes its truth beside the log.
set -euo pipefail
B="${FPLOC_BUILD_DIR:?}/bin"
T="$(mktemp -d)"
trap 'rm -rf "$T"' EXIT
printf '{"world": {"remove": [2,, 3]}}' > "$T/bad.json"
if "$B/fploc-sim" --scenario room-small-loop-medium --world "$T/bad.json" --duration 1 --out "$T/a.lcm" --gt "$T/a.tum" 2> "$T/err"; then
  echo "expected an error"; exit 1; fi
grep -q "bad.json: byte 25: JSON syntax error" "$T/err" || { cat "$T/err"; exit 1; }
test "$(grep -c . "$T/err")" -eq 1 || { cat "$T/err"; exit 1; }
test ! -e "$T/a.lcm"
if "$B/fploc-sim" --scenario room-small-loop-medium --perturb "asbuilt=0.02,wobble=1" --duration 1 --out "$T/b.lcm" --gt "$T/b.tum" 2> "$T/err"; then
  echo "expected an error"; exit 1; fi
grep -q "unknown key 'wobble'" "$T/err" || { cat "$T/err"; exit 1; }
test "$(grep -c . "$T/err")" -eq 1 || { cat "$T/err"; exit 1; }
printf '{"world": {"remove": [2], "add": [{"a": [5, 6], "b": [7, 6]}], "doors": [{"a": [0, 5.75], "b": [0, 6.75], "open": false}]}}' > "$T/good.json"
"$B/fploc-sim" --scenario room-small-loop-medium --world "$T/good.json" --duration 1 --out "$T/c.lcm" --gt "$T/c.tum" 2>/dev/null
python3 - "$T/c.world.json" <<'PY'
import json, sys
t = json.load(open(sys.argv[1]))
assert t["elements"][2]["change"] == "removed", t["elements"][2]
assert [a["kind"] for a in t["added"]] == ["partition", "door-closed"], t["added"]
PY
# A number option given nan or inf: one error naming it, exit 1, nothing written (--noise nan wrote a log of NaN
# ranges; --duration nan simulated the whole scenario).
for bad in "--noise nan" "--duration nan" "--dropout inf"; do
  if "$B/fploc-sim" --scenario room-small-loop-medium $bad --out "$T/n.lcm" --gt "$T/n.tum" 2> "$T/err"; then
    echo "$bad accepted"; exit 1; fi
  grep -qx "fploc sim: $bad: not a finite number" "$T/err" || { cat "$T/err"; exit 1; }
  test ! -e "$T/n.lcm"
done
echo "world cli: ok"
