#!/usr/bin/env python3
# Small recordings with one defect each, for import_damaged_test.sh (written here, independently of fploc's writers).
#   make_damaged.py DIR   writes:
#   topic_e9.bag   an Imu topic whose name holds the byte 0xE9 (not UTF-8), 3 messages, one uncompressed chunk
#   topic_esc.bag  an Imu topic named b'/imu\x1b[2J\xe9' (a terminal escape, a byte that is not UTF-8), 2 messages
#   comp.mcap      one uncompressed chunk of 2 Imu messages, then a chunk whose compression name is b'\xff\xfe'
#   laser.bag      /scan_front, /scan_back (LaserScan), /odom (Odometry), /tf (odom -> base_link, base_link -> laser)
#                  at 100..104 s, one uncompressed chunk
#   len.bag        3 Imu messages in one uncompressed chunk whose data length is damaged (0xFFFFFFF0), in a whole file:
#                  the bag header's index_pos points at the index (connection records) after the chunk
#   cutcomp.bag    an uncompressed chunk of 2 Imu messages, then a chunk whose compression name is b'\xff\xfe', the
#                  file cut inside that chunk
#   cutcomp.mcap   comp.mcap cut inside its second chunk (the one with the damaged compression name)
import os, struct, sys

def field(n, v): b = n.encode() + b'=' + v; return struct.pack('<I', len(b)) + b
def rec(h, d): return struct.pack('<I', len(h)) + h + struct.pack('<I', len(d)) + d
def s(x): x = x if isinstance(x, bytes) else x.encode(); return struct.pack('<I', len(x)) + x
def hdr1(t, frame): return struct.pack('<III', 7, t, 5) + s(frame)
def imu(t): return hdr1(t, 'imu') + struct.pack('<4d', 0, 0, 0, 1) + b'\0' * 72 + struct.pack('<3d', .1, .2, .3) + b'\0' * 72 + struct.pack('<3d', 0, 0, 9.8) + b'\0' * 72
def scan(t): return hdr1(t, 'laser') + struct.pack('<7f', -1, 1, 0.2, 0, 0.1, 0.1, 30) + struct.pack('<I', 10) + struct.pack('<10f', *[1.0] * 10) + struct.pack('<I', 0)
def odom(t): return hdr1(t, 'odom') + s('base_link') + struct.pack('<7d', 1, 2, 0, 0, 0, 0, 1) + b'\0' * (36 * 8) + b'\0' * (42 * 8)
def tf(t): return struct.pack('<I', 2) + hdr1(t, 'odom') + s('base_link') + struct.pack('<7d', t - 100, 0, 0, 0, 0, 0, 1) + \
    hdr1(t, 'base_link') + s('laser') + struct.pack('<7d', 0.1, 0, 0, 0, 0, 0, 1)

def bag(path, conns, rounds, index=False, damage_len=False, second=None, cut=None):
    """conns: [(topic bytes, type, fn)]; one uncompressed chunk. index: the connection records again after the chunk
    as the index, the header's index_pos pointing at them; damage_len: the chunk's data length 0xFFFFFFF0; second:
    a compression name for a second chunk (one more round, its records as they are); cut: the file cut that many
    bytes into the second chunk's data."""
    def conn_recs():
        return b''.join(rec(field('op', b'\x07') + field('conn', struct.pack('<I', i)) + field('topic', topic),
                            field('topic', topic) + field('type', ty.encode()) + field('md5sum', b'*'))
                        for i, (topic, ty, fn) in enumerate(conns))
    def msgs(ks):
        return b''.join(rec(field('op', b'\x02') + field('conn', struct.pack('<I', i)) + field('time', struct.pack('<II', 100 + k, i)), fn(100 + k))
                        for k in ks for i, (topic, ty, fn) in enumerate(conns))
    chunk = conn_recs() + msgs(range(rounds))
    def header(index_pos):
        return b'#ROSBAG V2.0\n' + rec(field('op', b'\x03') + field('index_pos', struct.pack('<Q', index_pos)) +
                                       field('conn_count', struct.pack('<I', 0)) + field('chunk_count', struct.pack('<I', 0)), b' ' * 16)
    chunk_rec = rec(field('op', b'\x05') + field('compression', b'none') + field('size', struct.pack('<I', len(chunk))), chunk)
    if damage_len:
        hl = struct.unpack('<I', chunk_rec[:4])[0]
        chunk_rec = chunk_rec[:4 + hl] + struct.pack('<I', 0xFFFFFFF0) + chunk_rec[8 + hl:]
    out = header(0) + chunk_rec
    if second is not None:
        data = msgs([rounds])
        at = len(out)
        out += rec(field('op', b'\x05') + field('compression', second) + field('size', struct.pack('<I', len(data))), data)
        if cut is not None:
            out = out[:len(out) - len(data) + cut]
    if index:
        out = header(len(out)) + out[len(header(0)):] + conn_recs()
    open(path, 'wb').write(out)

def mrec(op, body): return bytes([op]) + struct.pack('<Q', len(body)) + body
def mcap_comp(path):
    magic = b'\x89MCAP0\r\n'
    out = magic + mrec(0x01, s('ros1') + s('make_damaged'))
    inner = mrec(0x03, struct.pack('<H', 1) + s('sensor_msgs/Imu') + s('ros1msg') + s(''))
    inner += mrec(0x04, struct.pack('<HH', 1, 1) + s('/imu') + s('ros1') + struct.pack('<I', 0))
    for k in range(2):
        t = (100 + k) * 10**9
        inner += mrec(0x05, struct.pack('<HIQQ', 1, k, t, t) + imu(100 + k))
    def chunk(method, records):
        return mrec(0x06, struct.pack('<QQQI', 100 * 10**9, 101 * 10**9, len(records), 0) + s(method) + struct.pack('<Q', len(records)) + records)
    out += chunk(b'', inner)
    more = mrec(0x05, struct.pack('<HIQQ', 1, 2, 102 * 10**9, 102 * 10**9) + imu(102))
    at = len(out)
    out += chunk(b'\xff\xfe', more)
    out += mrec(0x0F, struct.pack('<I', 0)) + mrec(0x02, struct.pack('<QQI', 0, 0, 0)) + magic
    open(path, 'wb').write(out)
    return at

def mcap_cut(src, path):
    """src cut 40 bytes into the records of its second chunk (9 + 36 B of its header, its name, its records' length)."""
    data = open(src, 'rb').read()
    at = mcap_comp(src)
    name_len = struct.unpack('<I', data[at + 9 + 28:at + 9 + 32])[0]
    open(path, 'wb').write(data[:at + 9 + 32 + name_len + 8 + 40])

d = sys.argv[1]
bag(os.path.join(d, 'topic_e9.bag'), [(b'/imu\xe9', 'sensor_msgs/Imu', imu)], 3)
bag(os.path.join(d, 'topic_esc.bag'), [(b'/imu\x1b[2J\xe9', 'sensor_msgs/Imu', imu)], 2)
mcap_comp(os.path.join(d, 'comp.mcap'))
mcap_cut(os.path.join(d, 'comp.mcap'), os.path.join(d, 'cutcomp.mcap'))
bag(os.path.join(d, 'len.bag'), [(b'/imu', 'sensor_msgs/Imu', imu)], 3, index=True, damage_len=True)
bag(os.path.join(d, 'cutcomp.bag'), [(b'/imu', 'sensor_msgs/Imu', imu)], 2, second=b'\xff\xfe', cut=40)
bag(os.path.join(d, 'laser.bag'), [(b'/scan_front', 'sensor_msgs/LaserScan', scan), (b'/scan_back', 'sensor_msgs/LaserScan', scan),
                                   (b'/odom', 'nav_msgs/Odometry', odom), (b'/tf', 'tf2_msgs/TFMessage', tf)], 5)
