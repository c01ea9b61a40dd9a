#!/usr/bin/env python3
# Small recordings with one defect each, for import_damaged_test.sh (written here, independently of fploc's writers).
#   make_damaged.py DIR   writes:
#   topic_e9.bag   an Imu topic whose name holds the byte 0xE9 (not UTF-8), 3 messages, one uncompressed chunk
#   topic_esc.bag  an Imu topic named b'/imu\x1b[2J\xe9' (a terminal escape, a byte that is not UTF-8), 2 messages
#   comp.mcap      one uncompressed chunk of 2 Imu messages, then a chunk whose compression name is b'\xff\xfe'
#   laser.bag      /scan_front, /scan_back (LaserScan), /odom (Odometry), /tf (odom -> base_link, base_link -> laser)
#                  at 100..104 s, one uncompressed chunk
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

def bag(path, conns, rounds):
    """conns: [(topic bytes, type, fn)]; one uncompressed chunk, no index."""
    chunk = b''
    for i, (topic, ty, fn) in enumerate(conns):
        chunk += rec(field('op', b'\x07') + field('conn', struct.pack('<I', i)) + field('topic', topic),
                     field('topic', topic) + field('type', ty.encode()) + field('md5sum', b'*'))
    for k in range(rounds):
        for i, (topic, ty, fn) in enumerate(conns):
            chunk += rec(field('op', b'\x02') + field('conn', struct.pack('<I', i)) + field('time', struct.pack('<II', 100 + k, i)), fn(100 + k))
    out = b'#ROSBAG V2.0\n' + rec(field('op', b'\x03') + field('index_pos', struct.pack('<Q', 0)) + field('conn_count', struct.pack('<I', 0)) +
                                  field('chunk_count', struct.pack('<I', 0)), b' ' * 16)
    out += rec(field('op', b'\x05') + field('compression', b'none') + field('size', struct.pack('<I', len(chunk))), chunk)
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
    out += chunk(b'\xff\xfe', more)
    out += mrec(0x0F, struct.pack('<I', 0)) + mrec(0x02, struct.pack('<QQI', 0, 0, 0)) + magic
    open(path, 'wb').write(out)

d = sys.argv[1]
bag(os.path.join(d, 'topic_e9.bag'), [(b'/imu\xe9', 'sensor_msgs/Imu', imu)], 3)
bag(os.path.join(d, 'topic_esc.bag'), [(b'/imu\x1b[2J\xe9', 'sensor_msgs/Imu', imu)], 2)
mcap_comp(os.path.join(d, 'comp.mcap'))
bag(os.path.join(d, 'laser.bag'), [(b'/scan_front', 'sensor_msgs/LaserScan', scan), (b'/scan_back', 'sensor_msgs/LaserScan', scan),
                                   (b'/odom', 'nav_msgs/Odometry', odom), (b'/tf', 'tf2_msgs/TFMessage', tf)], 5)
