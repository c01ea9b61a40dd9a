#!/usr/bin/env bash
# fploc import of ROS 2 rosbag2 sqlite3 bags (.db3; no network: plain test). The messages are those of an MCAP file
# written by write_mcap.js (@mcap/core; CDR by @foxglove/cdr), put into .db3 files by mcap_to_db3.py (Python's
# sqlite3; rows inserted out of time order, topic ids differing per split file): the import of the bag folder (one
# file, three split files, zstd 'message' compression) and of the single .db3 gives the LCM log and the TUM file of
# the MCAP's import, byte for byte (also with --topics/--start/--end). Bad input: one error naming the file and what
# is wrong, exit 1, the messages before a cut kept.
set -uo pipefail
I="${FPLOC_BUILD_DIR:?}/bin/fploc-import"
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
T="$(mktemp -d)"; trap 'rm -rf "$T"' EXIT
source "$HERE/../support/import_checks.sh"

if [ -d "$HERE/node_modules/@mcap/core" ] && command -v node > /dev/null; then
  (cd "$HERE" && node write_mcap.js "$T/u.mcap" none unchunked && node write_mcap.js "$T/z.mcap" zstd chunked) || fail "write_mcap.js"
  python3 "$HERE/mcap_to_db3.py" "$T/u.mcap" "$T/one" > /dev/null || fail "mcap_to_db3.py one"
  python3 "$HERE/mcap_to_db3.py" "$T/u.mcap" "$T/split" --split 3 > /dev/null || fail "mcap_to_db3.py split"
  python3 "$HERE/mcap_to_db3.py" "$T/u.mcap" "$T/msgz" --compress-message > /dev/null || fail "mcap_to_db3.py msgz"
  python3 "$HERE/mcap_to_db3.py" "$T/u.mcap" "$T/ord" --in-order > /dev/null || fail "mcap_to_db3.py ord"
  tf=(--tum-out --tf-parent odom --tf-child base_link)
  run mcap 0 "$T/z.mcap" --out "$T/mcap.lcm" --tum-out "$T/mcap.tum" --tf-parent odom --tf-child base_link --json
  for b in one split msgz one/one_0.db3; do
    n="${b//\//_}"
    run "$n" 0 "$T/$b" --out "$T/$n.lcm" --tum-out "$T/$n.tum" --tf-parent odom --tf-child base_link --json
    cmp -s "$T/mcap.lcm" "$T/$n.lcm" || fail "$b: its LCM log differs from the MCAP's import"
    cmp -s "$T/mcap.tum" "$T/$n.tum" || fail "$b: its TUM file differs from the MCAP's import"
    jcheck "$n" "j['format']=='rosbag2 sqlite3' and j['written']['POINT_CLOUD']==3 and j['written']['OS1_IMU']==20 and j['written']['LASER_SCAN']==3 and j['written']['WHEEL_ODOM']==10 and j['replay_graph']=='graphs/replay-clouds.pbtxt' and j['errors']==[]"
  done
  PYTHONPATH="$HERE/../../tools/pylib" python3 - "$T/mcap.lcm" "$T/split.lcm" <<'PY' || fail "events differ"
import sys, lcm_log
x, y = list(lcm_log.events(sys.argv[1])), list(lcm_log.events(sys.argv[2]))
assert len(x) == 39 and x == y, (len(x), len(y))
print("split bag: the MCAP's", len(x), "events")
PY
  run list 0 "$T/split" --list --json
  jcheck list "j['format']=='rosbag2 sqlite3' and j['messages']==49 and j['topics']['/imu']=={'type':'sensor_msgs/Imu','count':20,'imported_as':'yes'} and abs(j['duration_s']-0.95)<1e-6"
  run mcap_r 0 "$T/z.mcap" --topics /imu,/scan --start 0.3 --end 0.8 --out "$T/mcap_r.lcm"
  run split_r 0 "$T/split" --topics /imu,/scan --start 0.3 --end 0.8 --out "$T/split_r.lcm"
  cmp -s "$T/mcap_r.lcm" "$T/split_r.lcm" || fail "--topics/--start/--end: the split bag's log differs from the MCAP's"
  grep -q -- "--graph graphs/lidar2d.pbtxt --log $T/split_r.lcm" "$T/split_r.out" || fail "split_r: no replay command"
  # A file cut short (rows in time order, as a recorder writes them): the messages before the cut, one error.
  head -c 2400000 "$T/ord/ord_0.db3" > "$T/cut.db3"
  run cut 1 "$T/cut.db3" --out "$T/cut.lcm" --json
  err cut "$T/cut.db3: reading the messages table after 15 of 49 messages: sqlite: database disk image is malformed; the file is cut short: 2400000 B of the 4034560 B its header gives"
  jcheck cut "j['messages_read']==15 and sum(j['written'].values())==12 and j['skipped_types']=={'tf2_msgs/TFMessage':3} and len(j['errors'])==1"
  PYTHONPATH="$HERE/../../tools/pylib" python3 - "$T/mcap.lcm" "$T/cut.lcm" <<'PY' || fail "cut: not the first events of the MCAP's log"
import sys, lcm_log
x, y = list(lcm_log.events(sys.argv[1])), list(lcm_log.events(sys.argv[2]))
assert len(y) == 12 and x[:12] == y, (len(x), len(y))
PY
  # A split file missing from the folder: the files before it are read, one error naming it.
  rm "$T/split/split_1.db3"
  run missing 1 "$T/split" --out "$T/missing.lcm" --json
  err missing "$T/split/split_1.db3: no such file (the bag's metadata.yaml lists it)"
  jcheck missing "j['messages_read']==17"
  # 'file' compression (zstd): said, with how to decompress.
  mkdir "$T/fz" && zstd -q "$T/one/one_0.db3" -o "$T/fz/fz_0.db3.zstd" &&
    sed 's/compression_format: ""/compression_format: "zstd"/; s/compression_mode: ""/compression_mode: "FILE"/; s/one_0.db3/fz_0.db3.zstd/' \
      "$T/one/metadata.yaml" > "$T/fz/metadata.yaml"
  run fz 1 "$T/fz" --list
  err fz "$T/fz: rosbag2 'file' compression (the whole .db3 compressed with zstd): decompress it first (\`zstd -d FILE.db3.zstd\`"
  run fzf 1 "$T/fz/fz_0.db3.zstd" --list
  err fzf "$T/fz/fz_0.db3.zstd: rosbag2 'file' compression"
else
  echo "tests/import/node_modules absent: the MCAP comparison skipped (scripts/setup-web.sh installs it)"
fi
# Not rosbag2: SQLite without the tables, a bare header, a folder without a bag.
python3 -c "import sqlite3, sys; d = sqlite3.connect(sys.argv[1]); d.execute('CREATE TABLE x(a)'); d.commit()" "$T/notab.db3"
run notab 1 "$T/notab.db3" --list
err notab "$T/notab.db3: an SQLite database without the tables 'topics' and 'messages': not a rosbag2 sqlite3 bag"
python3 -c "import sqlite3, sys; d = sqlite3.connect(sys.argv[1]); d.execute('CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT)'); d.execute('CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER, timestamp INTEGER, data BLOB)'); d.commit()" "$T/nocol.db3"
run nocol 1 "$T/nocol.db3" --list
err nocol "$T/nocol.db3: reading the topics table: sqlite: no such column: type"
printf 'SQLite format 3\0' > "$T/fake.db3"
run fake 1 "$T/fake.db3" --list
err fake "$T/fake.db3: 16 B: cut short inside the SQLite header (100 B)"
mkdir "$T/empty"
run empty 1 "$T/empty" --list
err empty "$T/empty: is a directory without metadata.yaml or .db3 files (not a rosbag2 bag folder)"
[ "$fails" = 0 ] && echo "import db3: ok" || { echo "import db3: $fails failure(s)"; exit 1; }
