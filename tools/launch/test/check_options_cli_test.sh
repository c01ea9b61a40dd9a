#!/usr/bin/env bash
# fploc launch --check runs the option checks each node does at start (fploc::config::check_options): an
# option value the node would refuse is one error naming file:line, node and option, exit 1 (it passed
# --check and was first found when the node died at start). Inside scripts/netns-run.
set -uo pipefail
L="${FPLOC_BUILD_DIR:?}/bin/fploc-launch"; R="${FPLOC_ROOT:?}"
T="$(mktemp -d)"; trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $1"; echo "$out" | tail -5; exit 1; }

out="$(timeout 60 "$L" --check --skip-hosts "$R/graphs/demo.pbtxt" 2>&1)"; rc=$?
[ "$rc" = 0 ] || fail "demo graph: exit $rc, expected 0"

# A --set value: the line of the node's options block.
out="$(timeout 60 "$L" --check --skip-hosts "$R/graphs/demo.pbtxt" --set matcher.loss=bogus 2>&1)"; rc=$?
[ "$rc" = 1 ] || fail "--set matcher.loss=bogus: exit $rc, expected 1"
line="$(grep -n '^  matcher {' "$R/graphs/demo.pbtxt" | cut -d: -f1)"
echo "$out" | grep -qxF "$R/graphs/demo.pbtxt:$line: node 'matcher': matcher.loss: unknown loss 'bogus' (use \"cauchy\", \"geman-mcclure\", \"huber\" or \"none\")" ||
  fail "--set matcher.loss=bogus: no error naming file:$line, node and option"
[ "$(echo "$out" | grep -c "node '")" = 1 ] || fail "--set matcher.loss=bogus: not exactly one error"

# A look-up name the matcher would refuse at start (the map builder's own list, matcher::lookup_names).
out="$(timeout 60 "$L" --check --skip-hosts "$R/graphs/demo.pbtxt" --set matcher.lookup=kd 2>&1)"; rc=$?
[ "$rc" = 1 ] || fail "--set matcher.lookup=kd: exit $rc, expected 1"
echo "$out" | grep -qF "node 'matcher': matcher.lookup: unknown look-up 'kd' (use \"annf-exact\"" ||
  fail "--set matcher.lookup=kd: no error naming the option and the valid names"

# Output files in a folder that does not exist (the pose loggers could not open them at start).
out="$(FPLOC_DEMO_DIR=/nonexistent-fploc/dir timeout 60 "$L" --check --skip-hosts "$R/graphs/demo.pbtxt" 2>&1)"; rc=$?
[ "$rc" = 1 ] || fail "FPLOC_DEMO_DIR=/nonexistent-fploc/dir: exit $rc, expected 1"
echo "$out" | grep -qF "pose_logger.file '/nonexistent-fploc/dir/fploc-demo-poses.tum' cannot be written: its folder '/nonexistent-fploc/dir' does not exist" ||
  fail "FPLOC_DEMO_DIR=/nonexistent-fploc/dir: no error naming the output file"

# A value in the file: the option's own line.
check_file() {  # $1: sed expression applied to a copy of the demo graph (plans made absolute)
  sed -e "s#\"\\.\\./data/#\"$R/data/#g" -e "$1" "$R/graphs/demo.pbtxt" > "$T/g.pbtxt"
  out="$(timeout 60 "$L" --check --skip-hosts "$T/g.pbtxt" 2>&1)"; rc=$?
}
check_file 's#window: 10 alpha#window: 10\n              loss: "bogus" alpha#'
[ "$rc" = 1 ] || fail "optimizer loss bogus: exit $rc, expected 1"
line="$(grep -n 'loss: "bogus"' "$T/g.pbtxt" | cut -d: -f1)"
echo "$out" | grep -qF "$T/g.pbtxt:$line: node 'optimizer': optimizer.loss: unknown loss 'bogus'" ||
  fail "optimizer loss bogus: no error at line $line"

# A negative value where only > 0 means something (0 = the default) is an error, not the default.
check_file 's#window: 10 alpha#window: -3 alpha#'
[ "$rc" = 1 ] || fail "optimizer window -3: exit $rc, expected 1"
line="$(grep -n 'window: -3' "$T/g.pbtxt" | cut -d: -f1)"
echo "$out" | grep -qxF "$T/g.pbtxt:$line: node 'optimizer': optimizer.window: must be > 0 (0 = the default), got -3" ||
  fail "optimizer window -3: no error at line $line"
# One misspelt field: that one error and no other (the parse stopped before the ${FPLOC_DEMO_DIR:-/tmp} values were
# expanded, and three output files were said to be in a folder '.../${FPLOC_DEMO_DIR:-/tmp}' that does not exist).
check_file 's#window: 10 alpha#window: 10 windw: 3 alpha#'
[ "$rc" = 1 ] || fail "optimizer windw: exit $rc, expected 1"
line="$(grep -n 'windw: 3' "$T/g.pbtxt" | cut -d: -f1)"
echo "$out" | grep -qF "$T/g.pbtxt:$line: Message type \"fploc.OptimizerOptions\" has no field named \"windw\"" ||
  fail "optimizer windw: no error at line $line"
[ "$(echo "$out" | grep -c "^$T/g.pbtxt:[0-9]*: ")" = 1 ] || fail "optimizer windw: not exactly one error"
# A matcher without a plan.
check_file '/^  matcher {/ s#plan { file: "[^"]*" } ##'
[ "$rc" = 1 ] || fail "matcher without plan: exit $rc, expected 1"
echo "$out" | grep -qF "node 'matcher': matcher.plan.file: no floor plan given" || fail "matcher without plan: no error"
# A graph without a node to run (an empty file, comments only, every node disabled): one error, exit 1.
printf '# nothing here\n' > "$T/empty.pbtxt"
out="$(timeout 60 "$L" --check --skip-hosts "$T/empty.pbtxt" 2>&1)"; rc=$?
[ "$rc" = 1 ] || fail "empty graph: exit $rc, expected 1"
echo "$out" | grep -qxF "$T/empty.pbtxt: no node: the graph declares none (an empty or wrong file?)" || fail "empty graph: error text"
sed -e "s#\"\.\./data/#\"$R/data/#g" "$R/graphs/demo.pbtxt" | awk '/^node \{$/ {print; print "  disabled: true"; next} {print}' > "$T/off.pbtxt"
out="$(timeout 60 "$L" --check --skip-hosts "$T/off.pbtxt" 2>&1)"; rc=$?
[ "$rc" = 1 ] || fail "all nodes disabled: exit $rc, expected 1"
echo "$out" | grep -qF "no node to run: every node is disabled" || fail "all nodes disabled: error text"
echo OK
