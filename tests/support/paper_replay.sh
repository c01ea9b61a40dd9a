# Sourced by the shell tests that replay a simulated log through graphs/paper.pbtxt (lock-step `fploc replay`,
# memq://, no network). Needs BIN (the build's bin folder) and ROOT (the source tree).
#   paper_replay LOG PREFIX [ARG...]
#     replays LOG against data/plans/room.json; the pose loggers write PREFIX-{sfr,wo,odom,odom_map}.tum, the
#     replay's report goes to PREFIX.json and its stderr to PREFIX.err (printed, and the test stopped, when the
#     replay fails); ARG... are passed on (more --set, --record ...).
paper_replay() {
  local log="$1" prefix="$2" plan="$ROOT/data/plans/room.json"
  shift 2
  "$BIN/fploc-replay" --graph "$ROOT/graphs/paper.pbtxt" --log "$log" --json \
    --set matcher.plan.file="$plan" --set optimizer.plan.file="$plan" \
    --set sfr_logger.file="$prefix-sfr.tum" --set wo_logger.file="$prefix-wo.tum" \
    --set odom_logger.file="$prefix-odom.tum" --set odom_map_logger.file="$prefix-odom_map.tum" "$@" \
    >"$prefix.json" 2>"$prefix.err" || { cat "$prefix.err" >&2; exit 1; }
}
