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
source "$HERE/../support/import_checks.sh"
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

# 2. The same bytes in the text output (the summary, --list, the errors): names from the recording printed with \xHH
# escapes (a terminal escape and a byte that is not UTF-8 were printed raw).
ESC=$(printf '\033')
run esc_list 0 "$T/topic_esc.bag" --list
grep -qF '  /imu\x1b[2J\xe9        2  sensor_msgs/Imu  (imported)' "$T/esc_list.out" || fail "esc_list: $(cat -v "$T/esc_list.out")"
run esc_out 0 "$T/topic_esc.bag" --out "$T/esc.lcm"
grep -qxF '  topic /imu\x1b[2J\xe9 -> OS1_IMU' "$T/esc_out.out" || fail "esc_out: $(cat -v "$T/esc_out.out")"
run esc_topics 2 "$T/topic_esc.bag" --topics "/imu${ESC}[2J" --out "$T/esc2.lcm"
grep -qxF "fploc import: no topic '/imu\x1b[2J' in the recording; its topics:" "$T/esc_topics.err" &&
  grep -qxF '  /imu\x1b[2J\xe9  sensor_msgs/Imu' "$T/esc_topics.err" || fail "esc_topics: $(cat -v "$T/esc_topics.err")"
for k in esc_list esc_out esc_topics; do
  LC_ALL=C grep -q "[$ESC$(printf '\351')]" "$T/$k.out" "$T/$k.err" && fail "$k: raw bytes in the output: $(cat -v "$T/$k.out" "$T/$k.err")"
done

# 3. Options that match nothing: an error naming what is missing and listing what is there, exit 2, nothing written
# (they gave an empty or partial log, exit 0).
L="$T/laser.bag"
run no_topic 2 "$L" --topics /nonexistent --out "$T/nt.lcm"
grep -q "^fploc import: no topic '/nonexistent' in the recording; its topics:" "$T/no_topic.err" && grep -q "^  /scan_front  sensor_msgs/LaserScan" "$T/no_topic.err" ||
  fail "no_topic: $(cat "$T/no_topic.err")"
[ ! -e "$T/nt.lcm" ] || fail "no_topic: a log was written"
run late_start 2 "$L" --start 100 --out "$T/ls.lcm"
grep -q "^fploc import: --start 100 s is past the recording's end: its messages span 0 to 4.000 s after the first" "$T/late_start.err" ||
  fail "late_start: $(cat "$T/late_start.err")"
[ ! -e "$T/ls.lcm" ] || fail "late_start: a log was written"
run typo_channel 2 "$L" --channel /scan_bakc=LASER_SCAN --out "$T/tc.lcm"
grep -q "^fploc import: no topic '/scan_bakc' in the recording" "$T/typo_channel.err" || fail "typo_channel: $(cat "$T/typo_channel.err")"
run no_frame 2 "$L" --tum-out "$T/nf.tum" --tf-parent odm --tf-child laser
grep -q "^fploc import: no tf frame 'odm' in the recording's tf messages; its frames: base_link, laser, odom$" "$T/no_frame.err" ||
  fail "no_frame: $(cat "$T/no_frame.err")"
[ ! -e "$T/nf.tum" ] || fail "no_frame: a TUM file was written"
run no_odom 2 "$L" --tum-out "$T/no.tum" --odom-topic /odometry
# The same options naming what is there still work.
run good 0 "$L" --topics /scan_back,/tf --channel /scan_back=LASER_SCAN --start 1 --tum-out "$T/g.tum" --tf-parent /odom --tf-child laser --out "$T/g.lcm" --json
jcheck good "j['written'] == {'LASER_SCAN': 4, '(tf /tf)': 4}"
# 6. --list says /tf is imported only when it is (--tum-out with frames), as the import's "not imported" does.
run list_tf 0 "$L" --list
grep -q "^  /tf .*tf2_msgs/TFMessage  (to TUM with --tum-out F --tf-parent P --tf-child C)$" "$T/list_tf.out" || fail "list_tf: $(cat "$T/list_tf.out")"
run list_tf_json 0 "$L" --list --json
jcheck list_tf_json "j['topics']['/tf']['imported_as'] == '' and j['topics']['/scan_back']['imported_as'] == 'yes'"

# 7. A damaged chunk length in a whole bag (its index after the chunk is in the file): "the length is damaged", not a
# truncation, and the chunk's whole messages are read (the reader said "file truncated?" and read none of them).
run len_bag 1 "$T/len.bag" --out "$T/len.lcm" --json
jcheck len_bag "j['written'] == {'OS1_IMU': 3}"
grep -qF "/len.bag: record at byte 106: chunk (none) of 4294967280 B runs past the end of the file (file size 1424 B; the file is not short (its index at byte 1331 is in it): the length is damaged); the chunk's 3 whole messages before the cut were read" "$T/len_bag.err" ||
  fail "len_bag: $(cat "$T/len_bag.err")"
# 8. A damaged compression name in the text errors: escaped (raw bytes before; the JSON's U+FFFD hid it), for a whole
# chunk and for a chunk the end of the file cuts (MCAP and bag).
grep -qF "/comp.mcap: chunk at byte 860 (\xff\xfe): unsupported compression '\xff\xfe'" "$T/comp_out.err" ||
  fail "comp_out: $(cat -v "$T/comp_out.err")"
run cutcomp_mcap 1 "$T/cutcomp.mcap" --out "$T/ccm.lcm" --json
jcheck cutcomp_mcap "j['written'] == {'OS1_IMU': 2}"
grep -qF "/cutcomp.mcap: chunk at byte 860 (\xff\xfe): length 388 runs past the end of the file (file size 951 B; file truncated, or the length damaged): a cut compressed chunk cannot be decompressed, its messages are lost" "$T/cutcomp_mcap.err" ||
  fail "cutcomp_mcap: $(cat -v "$T/cutcomp_mcap.err")"
run cutcomp_bag 1 "$T/cutcomp.bag" --out "$T/ccb.lcm" --json
jcheck cutcomp_bag "j['written'] == {'OS1_IMU': 2}"
grep -qF "/cutcomp.bag: record at byte 970: chunk (\xff\xfe) of 361 B runs past the end of the file (file size 1057 B; file truncated?): a cut compressed chunk cannot be decompressed, its messages are lost" "$T/cutcomp_bag.err" ||
  fail "cutcomp_bag: $(cat -v "$T/cutcomp_bag.err")"

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
