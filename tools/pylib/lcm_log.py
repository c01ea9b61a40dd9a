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


def write_events(path, events_with_time):
    """Writes (utime, channel, data) events as an LCM log (event numbers from 0, in the order given)."""
    with open(path, "wb") as f:
        for n, (utime, ch, d) in enumerate(events_with_time):
            c = ch.encode()
            f.write(struct.pack(">IqqII", SYNC, n, utime, len(c), len(d)) + c + d)


def delay_channel(src, dst, channel, delay_us):
    """Copies the log src to dst with every event of `channel` moved delay_us later in the event order (its
    log time + delay; ties keep the source order): e.g. an IMU that arrives after the scans, as live on a busy
    machine. Returns the number of events."""
    ev = [(t + (delay_us if ch == channel else 0), k, ch, d) for k, (t, ch, d) in enumerate(events(src, with_time=True))]
    ev.sort(key=lambda e: (e[0], e[1]))
    write_events(dst, ((t, ch, d) for t, _, ch, d in ev))
    return len(ev)


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
