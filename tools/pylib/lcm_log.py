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
