#!/usr/bin/env bash
# fploc map diff end to end on a renovated world: sim -> replay (record) -> map diff (JSON + DXF) -> the DXF
# loads in `fploc map render`; a log without features is one clear error.
set -euo pipefail
B="${FPLOC_BUILD_DIR:?}/bin"
R="${FPLOC_ROOT:?}"
T="$(mktemp -d)"
trap 'rm -rf "$T"' EXIT
"$B/fploc-sim" --scenario room-small-loop-medium --seed 3 --perturb renovated --duration 8 --out "$T/sim.lcm" --gt "$T/gt.tum" 2>/dev/null
test -s "$T/sim.world.json"
"$B/fploc-replay" --graph "$R/graphs/realism.pbtxt" --log "$T/sim.lcm" --record "$T/run.lcm" \
  --set plan_diff.out_json="$T/node.json" --set amcl_lidar_logger.file="$T/a.tum" --set wo_logger.file="$T/w.tum" 2>/dev/null
"$B/fploc-map-diff" --graph "$R/graphs/realism.pbtxt" --log "$T/run.lcm" --out "$T/diff.json" --out "$T/diff.dxf"
grep -q '"summary"' "$T/diff.json"
test -s "$T/node.json"   # the node wrote its own diff at shutdown
for l in FPLOC-MISSING FPLOC-MOVED FPLOC-NEW; do grep -qx "$l" "$T/diff.dxf"; done
"$B/fploc-map" render --plan "$T/diff.dxf" --out "$T/diff.svg" 2>/dev/null
test -s "$T/diff.svg"
# A CAD library reads it strictly, its audit finds nothing, the layers are there (Debian's python3-ezdxf).
if /usr/bin/python3 -c "import ezdxf" 2>/dev/null; then
  /usr/bin/python3 - "$T/diff.dxf" <<'PY'
import sys, ezdxf
doc = ezdxf.readfile(sys.argv[1])
a = doc.audit()
assert not a.errors, [str(e.message) for e in a.errors]
names = {l.dxf.name for l in doc.layers}
assert {"FPLOC-MISSING", "FPLOC-MOVED", "FPLOC-NEW", "FPLOC-PLAN"} <= names, names
assert any(e.dxf.layer == "FPLOC-PLAN" for e in doc.modelspace())
PY
else
  echo "map diff: python3-ezdxf not installed (scripts/setup.sh installs it): CAD read-back skipped"
fi
# A log without features (the simulator's own: scans only) -> one clear error, exit 1.
if "$B/fploc-map-diff" --graph "$R/graphs/realism.pbtxt" --log "$T/sim.lcm" --out "$T/x.json" 2>"$T/err"; then
  echo "expected an error for a log without features"; exit 1
fi
grep -q "no FPLOC_FEATURES (features_t) events" "$T/err" || { cat "$T/err"; exit 1; }
test "$(wc -l < "$T/err")" -eq 1 || { cat "$T/err"; exit 1; }
# The run's --set reaches the diff (a run replayed with --set matcher.plan.file=PLAN was diffed against the graph
# file's plan): the plan named by --set is the one diffed against; a --set naming no node is one error, exit 2.
"$B/fploc-map-diff" --graph "$R/graphs/realism.pbtxt" --log "$T/run.lcm" --out "$T/c.json" \
  --set plan_diff.plan.file="$R/data/plans/corridor.json" 2> "$T/err"
grep -q "against $R/data/plans/corridor.json:" "$T/err" || { cat "$T/err"; exit 1; }
# A building's floor (plan.floor) is the plan diffed against (it was ignored: the first floor's plan was used):
# data/buildings/two-floors.pbtxt floor "first" is corridor.json, so the same diff as above; an unknown floor is one
# error naming it.
"$B/fploc-map-diff" --graph "$R/graphs/realism.pbtxt" --log "$T/run.lcm" --out "$T/f.json" \
  --set plan_diff.plan.file="$R/data/buildings/two-floors.pbtxt" --set plan_diff.plan.floor=first 2> "$T/ferr"
grep -q "against $R/data/buildings/two-floors.pbtxt (floor first):" "$T/ferr" || { cat "$T/ferr"; exit 1; }
[ "$(sed 's/.*: //' "$T/ferr")" = "$(sed 's/.*: //' "$T/err")" ] || { echo "floor first != corridor.json:"; cat "$T/ferr" "$T/err"; exit 1; }
rc=0
"$B/fploc-map-diff" --graph "$R/graphs/realism.pbtxt" --log "$T/run.lcm" --out "$T/f.json" \
  --set plan_diff.plan.file="$R/data/buildings/two-floors.pbtxt" --set plan_diff.plan.floor=attic 2> "$T/ferr" || rc=$?
[ "$rc" = 1 ] && grep -q "attic" "$T/ferr" && [ "$(grep -c . "$T/ferr")" = 1 ] || { echo "unknown floor: exit $rc"; cat "$T/ferr"; exit 1; }
rc=0
"$B/fploc-map-diff" --graph "$R/graphs/realism.pbtxt" --log "$T/run.lcm" --out "$T/c.json" --set nonode.plan.file=x 2> "$T/err" || rc=$?
[ "$rc" = 2 ] && grep -q "nonode.plan.file=x" "$T/err" || { echo "exit $rc"; cat "$T/err"; exit 1; }
# A recorded run cut short: the diff of the events before the cut, and one error saying so, exit 1 (it was exit 0:
# lcm's reader stops at a cut event without a word).
head -c "$(( $(stat -c %s "$T/run.lcm") - 1000 ))" "$T/run.lcm" > "$T/cut.lcm"
rc=0
"$B/fploc-map-diff" --graph "$R/graphs/realism.pbtxt" --log "$T/cut.lcm" --out "$T/cut.json" 2> "$T/err" || rc=$?
[ "$rc" = 1 ] && grep -q "cut.lcm: event [0-9]* at byte [0-9]*: its data length [0-9]* runs past the end of the file" "$T/err" && test -s "$T/cut.json" ||
  { echo "cut log: exit $rc"; cat "$T/err"; exit 1; }
# --poses (diagnostic): the scans placed with the simulator's truth instead of the localizer's poses; every scan finds
# its pose; a trajectory whose times match no scan is one error, exit 1.
"$B/fploc-map-diff" --graph "$R/graphs/realism.pbtxt" --log "$T/run.lcm" --out "$T/t.json" --poses "$T/gt.tum" 2> "$T/err"
grep -q "scans placed with the poses of $T/gt.tum (0 scans without one within 5 ms" "$T/err" || { cat "$T/err"; exit 1; }
grep -q '"summary"' "$T/t.json"
awk '{ printf "%.6f", $1 + 1000; for (i = 2; i <= NF; ++i) printf " %s", $i; print "" }' "$T/gt.tum" > "$T/late.tum"
rc=0
"$B/fploc-map-diff" --graph "$R/graphs/realism.pbtxt" --log "$T/run.lcm" --out "$T/l.json" --poses "$T/late.tum" 2> "$T/err" || rc=$?
[ "$rc" = 1 ] && grep -q "late.tum: no pose within 5 ms of any of the" "$T/err" && [ "$(grep -c . "$T/err")" = 1 ] ||
  { echo "--poses late: exit $rc"; cat "$T/err"; exit 1; }
echo "map diff: ok"
