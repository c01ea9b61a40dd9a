#!/usr/bin/env bash
# Tools' --json with a file name holding a byte that is not UTF-8 (Latin-1 0xE9): exit 0 and one JSON document, the
# byte as U+FFFD (fploc::json_text). nlohmann's dump() threw type_error 316 on it: fploc replay and fploc map build
# printed "[json.exception.type_error.316] invalid UTF-8 byte" instead of their JSON and exited 1, fploc sim too
# (its world_truth path), and tools without a try around the dump aborted (exit 134).
set -uo pipefail
BIN="${FPLOC_BUILD_DIR:?run through ctest}/bin"
ROOT="${FPLOC_ROOT:?run through ctest}"
W="$(mktemp -d "${TMPDIR:-/tmp}/fploc-json-utf8-XXXXXX")"
trap 'rm -rf "$W"' EXIT
E=$'\xe9'
fails=0
# check NAME EXPECTED_KEY: exit 0 and stdout is JSON (strict UTF-8) whose EXPECTED_KEY holds U+FFFD
check() {
  local name="$1" key="$2" rc="$3"
  if [ "$rc" != 0 ]; then echo "FAIL: $name: exit $rc"; tail -3 "$W/$name.err"; fails=$((fails + 1)); return; fi
  python3 - "$W/$name.json" "$key" <<'PY' || { echo "FAIL: $name: not a JSON document with U+FFFD in '$2'"; head -c 300 "$W/$name.json"; fails=$((fails + 1)); }
import json, sys
j = json.loads(open(sys.argv[1], "rb").read().decode("utf-8"))
v = j[sys.argv[2]]
print(f"{sys.argv[2]}: {v!r}")
sys.exit(0 if "\ufffd" in v else 1)
PY
}
"$BIN/fploc-sim" --scenario room-small-loop-fast --seed 3 --duration 1 --perturb doors --out "$W/log$E.lcm" --gt "$W/gt.tum" \
  --json > "$W/sim.json" 2> "$W/sim.err"
check sim world_truth $?
"$BIN/fploc-replay" --graph "$ROOT/graphs/replay.pbtxt" --log "$W/log$E.lcm" --out "$W/est$E.tum" --json > "$W/replay.json" 2> "$W/replay.err"
check replay out $?
"$BIN/fploc-map" build --plan "$ROOT/data/plans/room.json" --depth 4 --out "$W/room$E.fpmap" --json > "$W/map.json" 2> "$W/map.err"
check map out $?
[ "$fails" = 0 ] || { echo "$fails failed"; exit 1; }
echo OK
