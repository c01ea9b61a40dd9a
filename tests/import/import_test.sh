#!/usr/bin/env bash
# fploc import end to end (inside scripts/netns-run; FPLOC_BUILD_DIR, FPLOC_SHARED_DIR, FPLOC_ROOT set):
# the ouster_ros bag -> LCM log of its packets -> fploc replay through the OS-1 and IMU drivers
# (graphs/replay-packets.pbtxt) gives byte for byte the scan_t and imu_t of `--decode`; the --decode log
# -> fploc replay (segmenter + features) and lcm-logplayer -> lcm-logger (a valid LCM event log); the ship-interior bag -> LaserScan channels and TUM from
# odometry and tf; a truncated bag -> one error, exit 1, and a log of what came before; an MCAP from
# @mcap/core: its PointCloud2 topics as point_cloud2_t, converted on replay by the cloud-to-scan node
# (graphs/replay-clouds.pbtxt) into the scan_t `--decode` writes, byte for byte.
source "$(dirname "${BASH_SOURCE[0]}")/../support/netns_test.sh"
require_shared ouster/512x10_raw.bag
D="$FPLOC_SHARED_DIR/data"
BAG="$D/ouster/512x10_raw.bag"
check() {
  python3 - "$1" "$2" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
ok = eval(sys.argv[2])
print(sys.argv[1].split("/")[-1] + ":", "ok" if ok else "FAILED: " + sys.argv[2])
sys.exit(0 if ok else 1)
PY
}

"$B/fploc-import" --list --json "$BAG" > "$T/list.json"
check "$T/list.json" "j['topics']['/os_node0/lidar_packets']['count']==32 and j['topics']['/os_node0/imu_packets']['count']==10 and j['topics']['/os_node0/metadata']['type']=='std_msgs/String' and 0.05<j['duration_s']<0.2"

# Lidar packets and no metadata (its topic left out, no --metadata): they cannot be written; one error saying so and
# exit 1 (it was exit 0 with a log of the IMU packets only), the IMU packets still written.
set +e
"$B/fploc-import" "$BAG" --topics /os_node0/lidar_packets,/os_node0/imu_packets --out "$T/nometa.lcm" --json \
  > "$T/nometa.json" 2> "$T/nometa.err"
rc=$?
set -e
[ "$rc" = 1 ] || { echo "lidar packets without metadata: exit $rc, expected 1"; exit 1; }
grep -q "32 Ouster lidar packets without metadata .*--metadata FILE" "$T/nometa.err" || { cat "$T/nometa.err"; exit 1; }
[ "$(grep -c . "$T/nometa.err")" = 1 ] || { echo "more than one error line"; cat "$T/nometa.err"; exit 1; }
check "$T/nometa.json" "j['written']=={'OS1_IMU_PACKETS':10}"

# Default: the packets as they are, decoded on replay by the OS-1 and IMU drivers (graphs/replay-packets.pbtxt).
"$B/fploc-import" "$BAG" --out "$T/p.lcm" --json > "$T/importp.json"
check "$T/importp.json" "j['replay_graph']=='graphs/replay-packets.pbtxt' and j['written']['OS1_LIDAR_PACKETS']==32 and j['written']['OS1_IMU_PACKETS']==10 and j['written']['OS1_METADATA']==1 and 'OS1_SCAN' not in j['written'] and j['ouster']['mode']=='packets' and j['ouster']['pixels_per_column']==128 and j['errors']==[]"
"$B/fploc-replay" --graph "$FPLOC_ROOT/graphs/replay-packets.pbtxt" --log "$T/p.lcm" --json --out "$T/p.tum" \
  --record "$T/p_rec.lcm" --record-channels 'OS1_SCAN|OS1_IMU' > "$T/replayp.json" 2> "$T/replayp.err"
check "$T/replayp.json" "j['channels_fed']=={'OS1_LIDAR_PACKETS':32,'OS1_IMU_PACKETS':10,'OS1_METADATA':1} and [n['messages_out'] for n in j['nodes'] if n['name'] in ('os1_driver','imu_driver','segmenter')]==[1,10,1] and all(n['errors']==0 for n in j['nodes'] if n['name'] in ('os1_driver','imu_driver'))"

# The text summary's replay command is whole: --out (without it the poses went to ./poses.tum) and the plan and start
# pose of each localizing node as placeholders; replay names the plan of each localizing node left on the graph's own
# (the demo room's), and with --set matcher.plan.file no longer the matcher.
"$B/fploc-import" "$BAG" --out "$T/p2.lcm" > "$T/importp.txt"
grep -q -- "bin/fploc replay --graph graphs/replay-packets.pbtxt --log $T/p2.lcm --out $T/p2-poses.tum" "$T/importp.txt" \
  || { cat "$T/importp.txt"; echo "import: the replay command has no --out"; exit 1; }
grep -q -- "--set matcher.plan.file=PLAN --set optimizer.plan.file=PLAN --set relocalizer.plan.file=PLAN" "$T/importp.txt" \
  && grep -q -- "--set matcher.initial_pose.x=X --set matcher.initial_pose.y=Y --set matcher.initial_pose.yaw=YAW" "$T/importp.txt" \
  || { cat "$T/importp.txt"; echo "import: the replay command has no plan / start pose"; exit 1; }
grep -q "^fploc replay: the graph's own plan (no --set NODE.plan.file=PLAN): matcher, relocalizer, optimizer -> $FPLOC_ROOT/data/plans/room.json$" "$T/replayp.err" \
  || { cat "$T/replayp.err"; echo "replay: no line naming the graph's own plan"; exit 1; }

# --start/--end that are no time span: one error naming the option, exit 2, nothing written (NaN and negative ones
# were ignored; an END before START wrote an empty log, exit 0).
for bad in "--start nan" "--end -1" "--start 5 --end 1"; do
  set +e
  "$B/fploc-import" "$BAG" $bad --out "$T/span.lcm" > /dev/null 2> "$T/span.err"
  rc=$?
  set -e
  [ "$rc" = 2 ] || { echo "import $bad: exit $rc, expected 2"; exit 1; }
  grep -q "^fploc import: --" "$T/span.err" || { cat "$T/span.err"; exit 1; }
  [ ! -e "$T/span.lcm" ] || { echo "import $bad wrote a log"; exit 1; }
done

# Not an LCM log, or one cut short: one error naming the file and exit 1 (both replayed "0 of 0 log events", exit 0).
for bad in bag cut; do
  if [ $bad = bag ]; then L="$BAG"; else L="$T/p_cut.lcm"; head -c $(( $(stat -c %s "$T/p.lcm") - 100 )) "$T/p.lcm" > "$L"; fi
  set +e
  "$B/fploc-replay" --graph "$FPLOC_ROOT/graphs/replay-packets.pbtxt" --log "$L" > /dev/null 2> "$T/bad.err"
  rc=$?
  set -e
  [ "$rc" = 1 ] || { echo "replay of a $bad log: exit $rc, expected 1"; exit 1; }
  grep -q "^fploc replay: $L: " "$T/bad.err" || { echo "replay of a $bad log:"; cat "$T/bad.err"; exit 1; }
done

# --decode: scan_t and imu_t written by the importer, byte for byte what the drivers give on replay.
"$B/fploc-import" "$BAG" --decode --out "$T/x.lcm" --json > "$T/import.json"
PYTHONPATH="$FPLOC_ROOT/tools/pylib" python3 - "$T/x.lcm" "$T/p_rec.lcm" <<'PY'
import sys, lcm_log
a = [(c, d) for c, d in lcm_log.events(sys.argv[1]) if c in ('OS1_SCAN', 'OS1_IMU')]
b = list(lcm_log.events(sys.argv[2]))
for ch in ('OS1_SCAN', 'OS1_IMU'):
    x, y = [d for c, d in a if c == ch], [d for c, d in b if c == ch]
    assert x and x == y, f"{ch}: --decode gives {len(x)} messages, the drivers on the packets {len(y)} (or different bytes)"
print("--decode == drivers on the packets: ok", len(a), "messages")
PY
check "$T/import.json" "j['ouster']['mode']=='scans' and j['written']['OS1_SCAN']==1 and j['written']['OS1_IMU']==10 and j['ouster']['frame_list'][0]['width']==512 and j['ouster']['frame_list'][0]['height']==j['ouster']['pixels_per_column']==128 and j['ouster']['frame_list'][0]['missing_columns']==0 and j['errors']==[]"

"$B/fploc-replay" --graph "$FPLOC_ROOT/graphs/import.pbtxt" --log "$T/x.lcm" --json > "$T/replay.json" 2> "$T/replay.err"
check "$T/replay.json" "j['channels_fed']=={'OS1_SCAN':1,'OS1_IMU':10} and [n['messages_out'] for n in j['nodes'] if n['name']=='segmenter']==[1] and [n['messages_out'] for n in j['nodes'] if n['name']=='features']==[1]"

# lcm-logplayer plays it; lcm-logger records the same events.
lcm-logger --lcm-url="$URL" "$T/played.lcm" > "$T/logger.txt" 2>&1 & pids+=($!)
sleep 0.5
lcm-logplayer --lcm-url="$URL" --speed=1 "$T/x.lcm"
sleep 1
kill "${pids[0]}"; wait "${pids[0]}" 2>/dev/null || true; pids=()
"$B/fploc-replay" --graph "$FPLOC_ROOT/graphs/import.pbtxt" --log "$T/played.lcm" --json > "$T/replay2.json" 2>/dev/null
check "$T/replay2.json" "j['channels_fed']=={'OS1_SCAN':1,'OS1_IMU':10}"

SHIP="$(ls "$D"/recordings/ship-interior/*.bag 2>/dev/null | head -1 || true)"
if [ -n "$SHIP" ]; then
  "$B/fploc-import" "$SHIP" --out "$T/ship.lcm" --tum-out "$T/odom.tum" --json > "$T/ship.json"
  check "$T/ship.json" "j['written']['LASER_SCAN_GUARDIAN_LASER_TILT_FRONT']==421 and j['written']['LASER_SCAN']==418 and j['written']['(tum /guardian/odom)']==839 and j['written']['WHEEL_ODOM']==839"
  # LASER_SCAN is the level laser: tf tilts the front one 0-57 deg (a tilting unit); the back one is level, turned
  # round, 0.43 m behind the robot frame (the odometry's base_footprint).
  check "$T/ship.json" "j['lasers']['/guardian/laser_tilt_front']['level']==False and j['lasers']['/guardian/laser_tilt_front']['tilt_max_deg']>50"
  check "$T/ship.json" "(lambda b: b['level'] and b['channel']=='LASER_SCAN' and b['base_frame']=='base_footprint' and abs(b['x_m']+0.432)<0.01 and abs(abs(b['yaw_deg'])-180)<0.5)(j['lasers']['/guardian/laser_horizontal_back'])"
  # --channel picks which laser is LASER_SCAN; the other one moves to its suffixed name instead of sharing it.
  "$B/fploc-import" "$SHIP" --out "$T/ship2.lcm" --channel /guardian/laser_horizontal_back=LASER_SCAN --json --quiet > "$T/ship2.json"
  check "$T/ship2.json" "j['written']['LASER_SCAN']==418 and j['written']['LASER_SCAN_GUARDIAN_LASER_TILT_FRONT']==421"
  # The level laser renamed: LASER_SCAN is the other (tilting) one, with a warning (not an error).
  "$B/fploc-import" "$SHIP" --out "$T/ship3.lcm" --channel /guardian/laser_horizontal_back=BACK --json --quiet > "$T/ship3.json"
  check "$T/ship3.json" "j['written']['BACK']==418 and j['written']['LASER_SCAN']==421 and j['errors']==[] and any('LASER_SCAN (/guardian/laser_tilt_front)' in w for w in j['warnings']) and 'laser_choice' not in j"
  # --topics leaves tf out of the log, not out of the mounts.
  "$B/fploc-import" "$SHIP" --out "$T/ship4.lcm" --topics /guardian/laser_horizontal_back,/guardian/odom --start 2 --json --quiet > "$T/ship4.json"
  check "$T/ship4.json" "(lambda b: b['mount_found'] and b['level'] and b['channel']=='LASER_SCAN' and abs(b['x_m']+0.432)<0.01)(j['lasers']['/guardian/laser_horizontal_back'])"
  [ "$(wc -l < "$T/odom.tum")" -ge 800 ] || { echo "odom.tum too short"; exit 1; }
  # README's recipe for a 2D laser: graphs/lidar2d.pbtxt on the map_server map, --out EST.tum. Its four pose
  # loggers all wrote EST.tum (overwriting each other's bytes: a torn last line); now EST.tum is the pipeline's
  # pose (FPLOC_POSE) and the others write EST.NODE.tum beside it.
  MAP="$(ls "$D"/recordings/ship-interior/*.yaml | head -1)"
  "$B/fploc-import" "$SHIP" --end 6 --out "$T/ship6.lcm" > "$T/ship6.txt"
  # The text summary's count column lines up whatever the channel names' length (LASER_SCAN_GUARDIAN_... broke it).
  python3 - "$T/ship6.txt" <<'PY'
import re, sys
rows = [l.rstrip("\n") for l in open(sys.argv[1]) if re.match(r"^  [A-Z][A-Z0-9_/]* +[0-9]+$", l)]
assert len(rows) >= 3 and len({len(r) for r in rows}) == 1, rows
print("ship6.txt: count column ok,", len(rows), "channels")
PY
  "$B/fploc-replay" --graph "$FPLOC_ROOT/graphs/lidar2d.pbtxt" --log "$T/ship6.lcm" --out "$T/est.tum" \
    --set matcher.plan.file="$MAP" --set optimizer.plan.file="$MAP" --set grid2d.plan.file="$MAP" \
    --set amcl.plan.file="$MAP" --set matcher.initial_pose.x=0.5 --set matcher.initial_pose.y=0.5 \
    --json > "$T/est.json" 2> "$T/est.err"
  grep -q "wo_logger -> $T/est.tum" "$T/est.err" || { cat "$T/est.err"; exit 1; }
  # grid2d says each change of its status with the reason (it lost track silently: telemetry errors 0, nothing on
  # stderr). With no start pose it localizes globally: the map (a 1.8 x 5.2 m corner) explains too little of any
  # scan for a place to be taken, so it stays LOST, says why, and counts no error (a search, not a failure).
  grep -q "^\[grid2d\] scan 0: LOST: global localization" "$T/est.err" || { cat "$T/est.err"; echo "grid2d: its first status not said"; exit 1; }
  # Its telemetry's detail then follows the search (time searched, places, the leader).
  check "$T/est.json" "[(n['errors'] == 0 and n['detail'].startswith('global localization: ') and ' searched (budget ' in n['detail']) for n in j['nodes'] if n['name']=='grid2d']==[True]"
  # Started at a pose (the import's printed --set grid2d.initial_pose.*): it tracks, loses the map, and says LOST
  # as an error with the reason.
  "$B/fploc-replay" --graph "$FPLOC_ROOT/graphs/lidar2d.pbtxt" --log "$T/ship6.lcm" --out "$T/est0.tum" \
    --set grid2d.plan.file="$MAP" --set matcher.plan.file="$MAP" --set optimizer.plan.file="$MAP" \
    --set amcl.plan.file="$MAP" --set grid2d.initial_pose.x=0 --json > "$T/est0.json" 2> "$T/est0.err"
  grep -q "^\[grid2d\] error: LOST at scan [0-9]*: no map fit trusted for [0-9]* scan(s)" "$T/est0.err" \
    || { cat "$T/est0.err"; echo "grid2d: LOST not said"; exit 1; }
  check "$T/est0.json" "[(n['errors'] >= 1 and n['last_error'].startswith('LOST at scan') and n['detail'].startswith('scan ')) for n in j['nodes'] if n['name']=='grid2d']==[True]"
  python3 - "$T" <<'PY'
import sys
d = sys.argv[1]
# grid2d without a start pose never locks on this corner: no estimate, so its TUM is empty (its search's placeholder
# poses, status 3, are not logged); started at a pose (est0) it writes its poses.
assert not open(f"{d}/est.grid_logger.tum").read(), "est.grid_logger.tum: placeholder poses of the global search logged"
for f in ("est.tum", "est.sfr_logger.tum", "est0.grid_logger.tum", "est.amcl_logger.tum"):
    rows = [l.split() for l in open(f"{d}/{f}")]
    assert rows and all(len(r) == 8 for r in rows), f"{f}: {len(rows)} rows, not all of 8 columns"
    t = [float(r[0]) for r in rows]
    assert t == sorted(t), f"{f}: times not increasing"
    print(f"{f}: ok", len(rows), "poses")
PY
  "$B/fploc-import" "$SHIP" --tum-out "$T/tf.tum" --tf-parent odom --tf-child base_footprint --start 10 --end 20 --quiet > /dev/null
  python3 - "$T/tf.tum" <<'PY'
import sys
rows = [list(map(float, l.split())) for l in open(sys.argv[1])]
assert len(rows) > 50, len(rows)
t = [r[0] for r in rows]
assert t == sorted(t) and t[-1] - t[0] < 10.5, (t[0], t[-1])
assert all(abs(sum(q * q for q in r[4:8]) - 1) < 1e-6 for r in rows)
print("tf.tum: ok", len(rows), "poses")
PY
  # Truncated: exit 1, one error with the byte offset, and a valid log of what came before.
  head -c 700000 "$SHIP" > "$T/cut.bag"
  set +e
  "$B/fploc-import" "$T/cut.bag" --out "$T/cut.lcm" --quiet > "$T/cut.txt" 2> "$T/cut.err"
  rc=$?
  set -e
  [ "$rc" = 1 ] || { echo "truncated bag: exit $rc, expected 1"; exit 1; }
  grep -q "cut.bag: record at byte [0-9]*: .*truncated" "$T/cut.err" || { echo "no byte offset in: $(cat "$T/cut.err")"; exit 1; }
  [ "$(grep -c . "$T/cut.err")" = 1 ] || { echo "more than one error line"; cat "$T/cut.err"; exit 1; }
  "$B/fploc-import" "$T/cut.bag" --list --json > "$T/cutlist.json" 2>/dev/null || true
  check "$T/cutlist.json" "j['topics']['/guardian/laser_tilt_front']['count']>100 and 'record at byte' in j['error']"
fi
# Bags written by an independent writer (Python; lz4 chunks from the lz4 tool).
for c in none bz2 lz4; do
  [ "$c" = lz4 ] && ! command -v lz4 > /dev/null && { echo "no lz4 tool: lz4 bag skipped"; continue; }
  python3 "$FPLOC_ROOT/tests/import/make_bag.py" "$T/py_$c.bag" "$c"
  # Its /os/metadata is not a full sensor metadata: those 3 messages are skipped, exit 3.
  rc=0; "$B/fploc-import" "$T/py_$c.bag" --out "$T/py_$c.lcm" --tum-out "$T/py.tum" --json > "$T/py_$c.json" 2>/dev/null || rc=$?
  [ "$rc" = 3 ] || { echo "py_$c.bag: exit $rc, expected 3 (metadata messages skipped)"; exit 1; }
  check "$T/py_$c.json" "j['not_decoded']['/os/metadata']['count']==3 and j['written']['POINT_CLOUD']==3 and j['replay_graph']=='graphs/replay-clouds.pbtxt' and j['clouds']['/points']['mode']=='clouds' and j['written']['LASER_SCAN']==3 and j['written']['OS1_IMU']==3 and j['written']['OS1_IMU_PACKETS']==3 and j['written']['(tum /odom)']==3 and j['clouds']['/points']['kept']==24 and j['clouds']['/points']['stray_points']==0 and j['clouds']['/points']['clouds_with_stray_points']==0"
done
# MCAP from the MCAP project's writer (zstd chunks): PointCloud2 (Velodyne + Hesai layouts), Imu,
# LaserScan -> LCM; tf -> TUM.
if [ -d "$FPLOC_ROOT/tests/import/node_modules/@mcap/core" ] && command -v node > /dev/null; then
  (cd "$FPLOC_ROOT/tests/import" && node write_mcap.js "$T/w.mcap" zstd chunked)
  "$B/fploc-import" "$T/w.mcap" --out "$T/w.lcm" --tum-out "$T/w.tum" --tf-parent odom --tf-child base_link --json > "$T/w.json"
  # Default: the clouds as they are (point_cloud2_t), converted on replay by the cloud-to-scan node.
  check "$T/w.json" "j['format']=='mcap' and j['written']['POINT_CLOUD']==3 and j['written']['POINT_CLOUD_HESAI_POINTS']==3 and j['written']['OS1_IMU']==20 and j['written']['LASER_SCAN']==3 and j['clouds']['/hesai_points']['ring_source']=='elevation' and j['replay_graph']=='graphs/replay-clouds.pbtxt' and j['errors']==[]"
  [ "$(wc -l < "$T/w.tum")" = 10 ] || { echo "w.tum: expected 10 poses"; exit 1; }
  # Each layout (Velodyne: ring field; Hesai: rings from the elevations): the node's scan_t on replay are
  # byte for byte those `--decode` writes at import time. Velodyne from uncompressed chunks (the points go
  # from the mapped file to the log in place), Hesai from zstd chunks (copied out of the decompressed chunk).
  (cd "$FPLOC_ROOT/tests/import" && node write_mcap.js "$T/w0.mcap" none chunked)
  for topic in /velodyne_points /hesai_points; do
    n="${topic#/}"
    src="$T/w.mcap"
    [ "$topic" = /velodyne_points ] && src="$T/w0.mcap"
    "$B/fploc-import" "$src" --topics "$topic,/imu" --out "$T/c_$n.lcm" --quiet > /dev/null
    "$B/fploc-import" "$src" --topics "$topic,/imu" --decode --out "$T/d_$n.lcm" --quiet > /dev/null
    "$B/fploc-replay" --graph "$FPLOC_ROOT/graphs/replay-clouds.pbtxt" --log "$T/c_$n.lcm" --json --out "$T/c_$n.tum" \
      --record "$T/c_${n}_rec.lcm" --record-channels 'OS1_SCAN' > "$T/c_$n.json" 2> "$T/c_$n.err"
    check "$T/c_$n.json" "j['channels_fed']=={'POINT_CLOUD':3,'OS1_IMU':20} and [n['messages_out'] for n in j['nodes'] if n['name'] in ('cloud_to_scan','segmenter')]==[3,3] and all(n['errors']==0 for n in j['nodes'] if n['name']=='cloud_to_scan')"
    PYTHONPATH="$FPLOC_ROOT/tools/pylib" python3 - "$T/d_$n.lcm" "$T/c_${n}_rec.lcm" "$topic" <<'PY'
import sys, lcm_log
x = [d for c, d in lcm_log.events(sys.argv[1]) if c == 'OS1_SCAN']
y = [d for c, d in lcm_log.events(sys.argv[2]) if c == 'OS1_SCAN']
assert len(x) == 3 and x == y, f"{sys.argv[3]}: --decode gives {len(x)} scans, the node on the clouds {len(y)} (or different bytes)"
print(sys.argv[3] + ": --decode == cloud-to-scan node on replay: ok", len(x), "scans")
PY
  done
  "$B/fploc-import" "$T/w.mcap" --decode --out "$T/wd.lcm" --json > "$T/wd.json"
  check "$T/wd.json" "j['written']['OS1_SCAN']==3 and j['written']['OS1_SCAN_HESAI_POINTS']==3 and j['clouds']['/velodyne_points']['mode']=='scans' and j['replay_graph']=='graphs/replay.pbtxt' and j['errors']==[]"
  "$B/fploc-replay" --graph "$FPLOC_ROOT/graphs/import.pbtxt" --log "$T/wd.lcm" --json > "$T/wr.json" 2>/dev/null
  check "$T/wr.json" "j['channels_fed']['OS1_SCAN']==3 and [n['messages_out'] for n in j['nodes'] if n['name']=='segmenter']==[3]"
else
  echo "tests/import/node_modules absent: MCAP part skipped (scripts/setup-web.sh installs it)"
fi
echo "import e2e: ok"
