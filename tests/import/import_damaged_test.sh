#!/usr/bin/env bash
# fploc import on damaged recordings and on options that match nothing (no network: plain test). Recordings from
# make_damaged.py (always) and byte-flipped copies of ../shared/data/ouster/512x10_raw.bag (skipped, saying so,
# when the shared data is absent).
set -uo pipefail
I="${FPLOC_BUILD_DIR:?}/bin/fploc-import"
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
SHARED="${FPLOC_SHARED_DIR:-$HERE/../../../shared}/data"
T="$(mktemp -d)"; trap 'rm -rf "$T"' EXIT
python3 "$HERE/make_damaged.py" "$T" || { echo "FAIL: make_damaged.py"; exit 1; }
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }
# run NAME EXPECTED_RC ARGS...: stdout -> $T/NAME.out, stderr -> $T/NAME.err
run() {
  local name="$1" want="$2"; shift 2
  "$I" "$@" > "$T/$name.out" 2> "$T/$name.err"; local rc=$?
  [ "$rc" = "$want" ] || { fail "$name: exit $rc, expected $want"; sed 's/^/    /' "$T/$name.err" | head -5; }
}
# jcheck NAME PYTHON_EXPR: $T/NAME.out is a JSON document and the expression over j holds
jcheck() {
  python3 - "$T/$1.out" "$2" 2>/dev/null <<'PY' || fail "$1: $2"
import json, sys
j = json.load(open(sys.argv[1], encoding="utf-8"))
sys.exit(0 if eval(sys.argv[2]) else 1)
PY
}
# flip SRC DST OFFSET BYTE: a copy of SRC with one byte replaced
flip() { python3 -c "import sys; d = bytearray(open(sys.argv[1], 'rb').read()); d[int(sys.argv[3])] = int(sys.argv[4], 0); open(sys.argv[2], 'wb').write(d)" "$@"; }

# 1. --json on bytes that are not UTF-8 (a topic name, a compression name): a JSON document with U+FFFD for each bad
# byte and the usual exit (it aborted: nlohmann type_error 316, exit 134).
run topic_e9 0 "$T/topic_e9.bag" --list --json
jcheck topic_e9 "j['topics']['/imu\ufffd']['count'] == 3"
run topic_e9_out 0 "$T/topic_e9.bag" --out "$T/e9.lcm" --json
jcheck topic_e9_out "j['channels'] == {'/imu\ufffd': 'OS1_IMU'} and j['written'] == {'OS1_IMU': 3}"
run comp_list 1 "$T/comp.mcap" --list --json
jcheck comp_list "j['topics']['/imu']['count'] == 2 and 'unsupported compression' in j['error']"
run comp_out 1 "$T/comp.mcap" --out "$T/comp.lcm" --json
jcheck comp_out "j['written'] == {'OS1_IMU': 2} and len(j['errors']) == 1"

BAG="$SHARED/ouster/512x10_raw.bag"
if [ -f "$BAG" ]; then
  # The metadata JSON with one byte flipped (0x84, not UTF-8).
  flip "$BAG" "$T/o_md.bag" 13293 0x84
  run o_md 1 "$T/o_md.bag" --out "$T/o_md.lcm" --json
  jcheck o_md "j['written']['OS1_IMU_PACKETS'] == 10"
  # 4. It is one error saying the topic is there but does not parse (it also said "no metadata topic"), and the
  # lidar packets are written as they are (they were all dropped).
  jcheck o_md "j['written']['OS1_LIDAR_PACKETS'] == 32 and len(j['errors']) == 1"
  grep -q "^fploc import: /os_node0/metadata: the metadata topic is there but its JSON (10432 B) does not parse at byte 1 (0x84), the message at chunk at byte 4109, record at chunk offset 9085; 32 Ouster lidar packets written as they are, without metadata: give --metadata FILE" "$T/o_md.err" ||
    fail "o_md: no single line naming the topic, the byte and what to do"
  [ "$(grep -c . "$T/o_md.err")" = 1 ] || { fail "o_md: not one error line"; cat "$T/o_md.err"; }
  run o_md_decode 1 "$T/o_md.bag" --decode --out "$T/o_mdd.lcm" --quiet
  grep -q "does not parse at byte 1 (0x84).*; 32 Ouster lidar packets could not be decoded: give --metadata FILE" "$T/o_md_decode.err" ||
    fail "o_md --decode: $(cat "$T/o_md_decode.err")"
  [ "$(grep -c . "$T/o_md_decode.err")" = 1 ] || { fail "o_md --decode: not one error line"; cat "$T/o_md_decode.err"; }
  # 5. An IMU packet whose length field says 4 B: skipped and reported on its topic (exit 3), not written as a lidar packet.
  flip "$BAG" "$T/o_imu.bag" 23771 0x04
  run o_imu 3 "$T/o_imu.bag" --out "$T/o_imu.lcm" --json
  jcheck o_imu "j['written']['OS1_LIDAR_PACKETS'] == 32 and j['written']['OS1_IMU_PACKETS'] == 9 and j['not_decoded']['/os_node0/imu_packets']['count'] == 1"
  grep -q "^fploc import: /os_node0/imu_packets: 1 message not decoded, skipped (the first at .*: IMU packet of 4 B (an IMU packet has 48))" "$T/o_imu.err" ||
    fail "o_imu: $(cat "$T/o_imu.err")"
  run o_imu_decode 3 "$T/o_imu.bag" --decode --out "$T/o_imud.lcm" --json
  jcheck o_imu_decode "j['written']['OS1_IMU'] == 9 and j['ouster']['lidar_packets'] == 32"
else
  echo "no $BAG (../shared/data absent): the Ouster bag cases are skipped"
fi
[ "$fails" = 0 ] || { echo "$fails failed"; exit 1; }
echo OK
