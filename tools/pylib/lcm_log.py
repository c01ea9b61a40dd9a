"""Reading LCM log files (the lcm-logger format) without the LCM Python bindings, which Debian does not
package: each event is a 28-byte big-endian header (sync word 0xEDA1DA01, event number, timestamp in
microseconds, channel length, data length), the channel name and the encoded message."""
import struct

SYNC = 0xEDA1DA01


def events(path, with_time=False):
    """Yields (channel, data) — or (utime, channel, data) with with_time — for every event of the log;
    a bad sync word raises naming the file and the byte offset."""
    d = open(path, 'rb').read()
    o = 0
    while o + 28 <= len(d):
        sync, _, utime, cl, dl = struct.unpack('>IQQII', d[o:o + 28])
        if sync != SYNC:
            raise ValueError(f"{path}: bad sync word at byte {o}")
        o += 28
        ch = d[o:o + cl].decode()
        o += cl
        yield (utime, ch, d[o:o + dl]) if with_time else (ch, d[o:o + dl])
        o += dl


def decode_pose_t(buf):
    """fploc.pose_t (messages/pose_t.lcm) -> dict: utime, status, final, p (x y z), q (x y z w), cov (36),
    x, y, z, and floor_index/floor when the message carries them (older logs do not)."""
    o = 8  # fingerprint
    utime, _seq, status, _kf, final = struct.unpack(">qqbbb", buf[o:o + 19])
    o += 19
    v = struct.unpack(">43d", buf[o:o + 43 * 8])
    o += 43 * 8
    out = {"utime": utime, "status": status, "final": bool(final), "p": v[0:3], "q": v[3:7], "cov": v[7:43],
           "x": v[0], "y": v[1], "z": v[2]}
    if o + 6 <= len(buf):
        (floor_index,) = struct.unpack(">h", buf[o:o + 2])
        (n,) = struct.unpack(">i", buf[o + 2:o + 6])
        out["floor_index"] = floor_index
        out["floor"] = buf[o + 6:o + 6 + n - 1].decode()
    return out
