#!/usr/bin/env python3
"""Writes a ROS 2 rosbag2 sqlite3 bag (.db3, Python's standard sqlite3 module) holding the messages of an
unchunked MCAP file (write_mcap.js ... none unchunked: the CDR bytes come from @foxglove/cdr), for fploc import's tests.

    mcap_to_db3.py IN.mcap OUT_DIR [--split N] [--compress-message] [--in-order]

OUT_DIR becomes a rosbag2 bag folder: metadata.yaml and OUT_DIR/NAME_0.db3 ... NAME_{N-1}.db3, split by time as
rosbag2's recorder splits (the first N-th of the messages in the first file...). The schema is rosbag2's sqlite3
schema as Humble writes it (tables schema, metadata, topics with offered_qos_profiles, messages, index
timestamp_idx). To check that a reader orders by timestamp (then id), rows are inserted latest timestamp first
(messages of one timestamp in file order); each split file lists its topics in another order (other ids). --in-order: rows in time order, as a recorder inserts them (for files cut short).
--compress-message: each message's data compressed as one zstd frame (rosbag2's 'message' compression mode;
needs the `zstd` command; no checksum, as ZSTD_compress writes them) and metadata.yaml says so.
The MCAP file is parsed here (its records: opcode u8, length u64, body), not by fploc's reader."""
import os
import sqlite3
import struct
import subprocess
import sys


def read_mcap(path):
    d = open(path, "rb").read()
    assert d[:8] == b"\x89MCAP0\r\n", "not an MCAP file"
    i = 8
    schemas, channels, messages = {}, {}, []

    def s(b, o):  # u32-prefixed string
        n = struct.unpack_from("<I", b, o)[0]
        return b[o + 4:o + 4 + n].decode(), o + 4 + n

    while i + 9 <= len(d):
        op = d[i]
        n = struct.unpack_from("<Q", d, i + 1)[0]
        b = d[i + 9:i + 9 + n]
        i += 9 + n
        if op == 0x03:  # Schema: id u16, name, encoding, data
            sid = struct.unpack_from("<H", b, 0)[0]
            name, _ = s(b, 2)
            schemas[sid] = name
        elif op == 0x04:  # Channel: id u16, schema_id u16, topic, message_encoding, metadata
            cid, sid = struct.unpack_from("<HH", b, 0)
            topic, o = s(b, 4)
            enc, _ = s(b, o)
            channels[cid] = (topic, schemas[sid], enc)
        elif op == 0x05:  # Message: channel_id u16, sequence u32, log_time u64, publish_time u64, data
            cid, _seq, log_time, _pub = struct.unpack_from("<HIQQ", b, 0)
            messages.append((cid, log_time, b[22:]))
        elif op == 0x06:
            raise SystemExit("chunked MCAP: write it with `write_mcap.js OUT none unchunked`")
        elif op == 0x02:  # Footer
            break
    return channels, messages


def write_db3(path, channels, msgs, topic_order, zstd_data, in_order):
    if os.path.exists(path):
        os.remove(path)
    db = sqlite3.connect(path)
    db.executescript(
        "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);"
        "CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL, metadata TEXT NOT NULL);"
        "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
        "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);"
        "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL, data BLOB NOT NULL);"
        "CREATE INDEX timestamp_idx ON messages (timestamp ASC);"
        "INSERT INTO schema VALUES (3, 'humble');")
    ids = {}
    for k, cid in enumerate(topic_order):
        topic, typ, enc = channels[cid]
        ids[cid] = 10 * (k + 1)  # not 1..n: a reader must use the table's ids
        db.execute("INSERT INTO topics VALUES (?, ?, ?, ?, ?)", (ids[cid], topic, typ, enc, ""))
    # Latest timestamp first (messages of one timestamp in file order): ids out of time order.
    by_t = {}
    for cid, t, data in msgs:
        by_t.setdefault(t, []).append((cid, data))
    for t in sorted(by_t, reverse=not in_order):
        for cid, data in by_t[t]:
            if zstd_data:
                data = subprocess.run(["zstd", "-q", "-c", "-3", "--no-check", "--stream-size=%d" % len(data)], input=data, stdout=subprocess.PIPE, check=True).stdout
            db.execute("INSERT INTO messages (topic_id, timestamp, data) VALUES (?, ?, ?)", (ids[cid], t, data))
    db.commit()
    db.close()


def main():
    args = sys.argv[1:]
    split = 1
    zstd_data = "--compress-message" in args
    in_order = "--in-order" in args
    args = [a for a in args if a not in ("--compress-message", "--in-order")]
    if "--split" in args:
        k = args.index("--split")
        split = int(args[k + 1])
        del args[k:k + 2]
    src, out = args
    channels, msgs = read_mcap(src)
    if zstd_data:
        # A message a few bytes long (std_msgs/Bool: 4 B of CDR header, 1 B): its zstd frame is shorter than the
        # largest frame header (18 B); the import does not take the topic, but must read past it.
        flag = max(channels) + 1
        channels[flag] = ("/flag", "std_msgs/msg/Bool", "cdr")
        msgs.append((flag, msgs[0][1], bytes([0, 1, 0, 0, 1])))
    os.makedirs(out, exist_ok=True)
    name = os.path.basename(os.path.normpath(out))
    files = []
    per = (len(msgs) + split - 1) // split
    for k in range(split):
        part = msgs[k * per:(k + 1) * per]
        order = sorted(channels) if k % 2 == 0 else sorted(channels, reverse=True)
        f = f"{name}_{k}.db3"
        write_db3(os.path.join(out, f), channels, part, order, zstd_data, in_order)
        files.append(f)
    mode = "MESSAGE" if zstd_data else ""
    fmt = "zstd" if zstd_data else ""
    with open(os.path.join(out, "metadata.yaml"), "w") as y:
        y.write("rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n")
        y.write("  duration:\n    nanoseconds: %d\n" % (msgs[-1][1] - msgs[0][1]))
        y.write("  starting_time:\n    nanoseconds_since_epoch: %d\n" % msgs[0][1])
        y.write("  message_count: %d\n  topics_with_message_count:\n" % len(msgs))
        for cid, (topic, typ, enc) in sorted(channels.items()):
            y.write("    - topic_metadata:\n        name: %s\n        type: %s\n        serialization_format: %s\n"
                    "        offered_qos_profiles: \"\"\n      message_count: %d\n"
                    % (topic, typ, enc, sum(1 for m in msgs if m[0] == cid)))
        y.write('  compression_format: "%s"\n  compression_mode: "%s"\n  relative_file_paths:\n' % (fmt, mode))
        for f in files:
            y.write("    - %s\n" % f)
    print(out, len(msgs), "messages in", split, "file(s)")


if __name__ == "__main__":
    main()
