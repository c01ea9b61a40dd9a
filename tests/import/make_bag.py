#!/usr/bin/env python3
# A ROS 1 bag 2.0 written independently of fploc's reader (Python; bz2 from Python's bz2 module, lz4
# frames from the `lz4` command line tool): one chunk holding connection records and 3 rounds of
# PointCloud2, LaserScan, Imu, tf, Odometry, ouster_ros IMU packets and a std_msgs/String, no index.
#   make_bag.py OUT.bag none|bz2|lz4
import struct, bz2, subprocess, sys, math
def field(name, val): b = name.encode() + b'=' + val; return struct.pack('<I', len(b)) + b
def rec(hdr, data): return struct.pack('<I', len(hdr)) + hdr + struct.pack('<I', len(data)) + data
def s(x): return struct.pack('<I', len(x)) + x.encode()
def hdr1(t, frame): return struct.pack('<III', 7, t, 5) + s(frame)
def cloud(t):
    pts = b''
    for r in range(4):
        for c in range(6):
            a = c * 1.0; e = (r - 2) * 0.1
            pts += struct.pack('<ffffHf', 3*math.cos(a), 3*math.sin(a), 3*math.sin(e), 7.0, r, c * 0.01)
    fields = [('x',0,7),('y',4,7),('z',8,7),('intensity',12,7),('ring',16,4),('time',18,7)]
    f = struct.pack('<I', len(fields)) + b''.join(s(n) + struct.pack('<IBI', o, ty, 1) for n,o,ty in fields)
    return hdr1(t, 'velo') + struct.pack('<II', 1, 24) + f + b'\0' + struct.pack('<II', 22, 22*24) + struct.pack('<I', len(pts)) + pts + b'\1'
def scan(t):
    r = [1.0 + i * 0.1 for i in range(10)]
    return hdr1(t, 'laser') + struct.pack('<7f', -1, 1, 0.2, 0, 0.1, 0.1, 30) + struct.pack('<I', 10) + struct.pack('<10f', *r) + struct.pack('<I', 0)
def imu(t): return hdr1(t, 'imu') + struct.pack('<4d', 0,0,0,1) + b'\0'*72 + struct.pack('<3d', .1,.2,.3) + b'\0'*72 + struct.pack('<3d', 0,0,9.8) + b'\0'*72
def tf(t): return struct.pack('<I', 1) + hdr1(t, 'odom') + s('base_link') + struct.pack('<7d', 1,2,0,0,0,0,1)
def odom(t): return hdr1(t, 'odom') + s('base_link') + struct.pack('<7d', 1,2,0,0,0,0,1) + b'\0'*(36*8) + b'\0'*(42*8)
def pkt(t): return struct.pack('<I', 48) + bytes(range(48))
def string(t): return s('{"lidar_mode": "512x10"}')
conns = [('/points','sensor_msgs/PointCloud2',cloud),('/scan','sensor_msgs/LaserScan',scan),('/imu','sensor_msgs/Imu',imu),
         ('/tf','tf2_msgs/TFMessage',tf),('/odom','nav_msgs/Odometry',odom),('/os/imu_packets','ouster_ros/PacketMsg',pkt),('/os/metadata','std_msgs/String',string)]
def write(path, comp):
    chunk = b''
    for i,(topic,ty,fn) in enumerate(conns):
        chunk += rec(field('op', b'\x07') + field('conn', struct.pack('<I', i)) + field('topic', topic.encode()),
                     field('topic', topic.encode()) + field('type', ty.encode()) + field('md5sum', b'*'))
    for k in range(3):
        for i,(topic,ty,fn) in enumerate(conns):
            chunk += rec(field('op', b'\x02') + field('conn', struct.pack('<I', i)) + field('time', struct.pack('<II', 100 + k, i)), fn(100 + k))
    data = chunk if comp == 'none' else bz2.compress(chunk) if comp == 'bz2' else subprocess.run(['lz4', '-c', '-q'], input=chunk, capture_output=True).stdout
    out = b'#ROSBAG V2.0\n' + rec(field('op', b'\x03') + field('index_pos', struct.pack('<Q', 0)) + field('conn_count', struct.pack('<I', 0)) + field('chunk_count', struct.pack('<I', 0)), b' ' * 16)
    out += rec(field('op', b'\x05') + field('compression', comp.encode()) + field('size', struct.pack('<I', len(chunk))), data)
    open(path, 'wb').write(out)
write(sys.argv[1], sys.argv[2])
