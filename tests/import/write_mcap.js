// Writes an MCAP file with the MCAP project's own writer (@mcap/core) and CDR from @foxglove/cdr: an
// independent producer for fploc import's tests.
//   node write_mcap.js OUT.mcap none|zstd|lz4 chunked|unchunked [small]
// Content (ROS 2 types, CDR): /velodyne_points  sensor_msgs/msg/PointCloud2, 3 VLP-16-like clouds of a
// box room (x -4..6, y -2.5..3.5, z -1.5..2 m; fields x y z intensity ring time, Velodyne layout),
// /hesai_points  the same clouds without a ring field and absolute float64 "timestamp" (Hesai layout),
// /imu sensor_msgs/msg/Imu (20), /scan sensor_msgs/msg/LaserScan (3), /odom nav_msgs/msg/Odometry (10),
// /tf tf2_msgs/msg/TFMessage (10, odom -> base_link).
"use strict";
const fs = require("fs");
const { McapWriter } = require("@mcap/core");
const { CdrWriter } = require("@foxglove/cdr");
const zstd = require("@foxglove/wasm-zstd");
const lz4js = require("lz4js");

const [out, compression, chunking, size] = process.argv.slice(2);
const COLS = size === "small" ? 24 : 1800;  // "small": fuzzing seeds
const T0 = 1700000000n * 1000000000n;

class FileWritable {
  constructor(path) { this.fd = fs.openSync(path, "w"); this.pos = 0n; }
  async write(buf) { fs.writeSync(this.fd, buf); this.pos += BigInt(buf.byteLength); }
  position() { return this.pos; }
  close() { fs.closeSync(this.fd); }
}

function header(w, tNs, frame) {
  w.int32(Number(tNs / 1000000000n));
  w.uint32(Number(tNs % 1000000000n));
  w.string(frame);
}

const BOX = { x: [-4, 6], y: [-2.5, 3.5], z: [-1.5, 2.0] };
function rayBox(d) {
  let t = Infinity;
  for (const [k, i] of [["x", 0], ["y", 1], ["z", 2]]) {
    if (d[i] > 1e-9) t = Math.min(t, BOX[k][1] / d[i]);
    else if (d[i] < -1e-9) t = Math.min(t, BOX[k][0] / d[i]);
  }
  return t;
}

function cloud(tNs, rev, withRing) {
  const rings = 16, cols = COLS;
  const step = withRing ? 22 : 24;  // x y z intensity (f32) ring (u16) time (f32) | x y z intensity timestamp (f64)
  const data = new Uint8Array(rings * cols * step);
  const view = new DataView(data.buffer);
  let n = 0;
  for (let c = 0; c < cols; ++c) {
    const az = (c * 0.2 + 0.07 * rev) * Math.PI / 180;
    for (let r = 0; r < rings; ++r) {
      const el = (-15 + 2 * r) * Math.PI / 180;
      const d = [Math.cos(el) * Math.cos(az), Math.cos(el) * Math.sin(az), Math.sin(el)];
      const t = rayBox(d);
      const o = n * step;
      view.setFloat32(o, t * d[0], true);
      view.setFloat32(o + 4, t * d[1], true);
      view.setFloat32(o + 8, t * d[2], true);
      view.setFloat32(o + 12, (r * 13 + c) % 200, true);
      const dt = (c / cols) * 0.1;
      if (withRing) {
        view.setUint16(o + 16, r, true);
        view.setFloat32(o + 18, dt, true);
      } else {
        view.setFloat64(o + 16, Number(tNs) * 1e-9 + dt, true);
      }
      ++n;
    }
  }
  const fields = withRing
    ? [["x", 0, 7], ["y", 4, 7], ["z", 8, 7], ["intensity", 12, 7], ["ring", 16, 4], ["time", 18, 7]]
    : [["x", 0, 7], ["y", 4, 7], ["z", 8, 7], ["intensity", 12, 7], ["timestamp", 16, 8]];
  const w = new CdrWriter({ size: data.length + 1024 });
  header(w, tNs, withRing ? "velodyne" : "hesai_lidar");
  w.uint32(1);            // height
  w.uint32(rings * cols); // width
  w.sequenceLength(fields.length);
  for (const [name, off, type] of fields) { w.string(name); w.uint32(off); w.uint8(type); w.uint32(1); }
  w.uint8(0);             // is_bigendian
  w.uint32(step);
  w.uint32(step * rings * cols);
  w.uint8Array(data, true);
  w.uint8(1);             // is_dense
  return w.data;
}

function imu(tNs, i) {
  const w = new CdrWriter();
  header(w, tNs, "imu");
  for (const v of [0, 0, 0, 1]) w.float64(v);
  for (let k = 0; k < 9; ++k) w.float64(0);
  for (const v of [0.01 * i, -0.02, 0.03]) w.float64(v);
  for (let k = 0; k < 9; ++k) w.float64(0);
  for (const v of [0.1, -0.2, 9.81]) w.float64(v);
  for (let k = 0; k < 9; ++k) w.float64(0);
  return w.data;
}

function scan(tNs) {
  const w = new CdrWriter();
  header(w, tNs, "laser");
  for (const v of [-Math.PI / 2, Math.PI / 2, Math.PI / 180, 1e-4, 0.1, 0.05, 30]) w.float32(v);
  const ranges = [];
  for (let i = 0; i <= 180; ++i) ranges.push(1 + i * 0.01);
  w.float32Array(ranges, true);
  w.float32Array(ranges.map((r) => r * 100), true);
  return w.data;
}

function pose(w, i) {
  for (const v of [0.5 * i, 0.25 * i, 0]) w.float64(v);
  const yaw = 0.1 * i;
  for (const v of [0, 0, Math.sin(yaw / 2), Math.cos(yaw / 2)]) w.float64(v);
}

function odom(tNs, i) {
  const w = new CdrWriter();
  header(w, tNs, "odom");
  w.string("base_link");
  pose(w, i);
  for (let k = 0; k < 36; ++k) w.float64(0);
  for (let k = 0; k < 6 + 36; ++k) w.float64(0);
  return w.data;
}

function tf(tNs, i) {
  const w = new CdrWriter();
  w.sequenceLength(1);
  header(w, tNs, "odom");
  w.string("base_link");
  pose(w, i);
  return w.data;
}

async function main() {
  await zstd.isLoaded;
  const file = new FileWritable(out);
  const opts = { writable: file, useChunks: chunking === "chunked", chunkSize: 256 * 1024 };
  if (compression === "zstd") opts.compressChunk = (d) => ({ compression: "zstd", compressedData: zstd.compress(d, 3) });
  if (compression === "lz4") opts.compressChunk = (d) => ({ compression: "lz4", compressedData: lz4js.compress(d) });
  const writer = new McapWriter(opts);
  await writer.start({ profile: "ros2", library: "fploc-test (@mcap/core)" });
  const enc = new TextEncoder();
  const schema = async (name) => writer.registerSchema({ name, encoding: "ros2msg", data: enc.encode("# " + name) });
  const channel = async (topic, schemaId) => writer.registerChannel({ topic, schemaId, messageEncoding: "cdr", metadata: new Map() });
  const pc = await schema("sensor_msgs/msg/PointCloud2");
  const chVel = await channel("/velodyne_points", pc);
  const chHes = await channel("/hesai_points", pc);
  const chImu = await channel("/imu", await schema("sensor_msgs/msg/Imu"));
  const chScan = await channel("/scan", await schema("sensor_msgs/msg/LaserScan"));
  const chOdom = await channel("/odom", await schema("nav_msgs/msg/Odometry"));
  const chTf = await channel("/tf", await schema("tf2_msgs/msg/TFMessage"));
  let seq = 0;
  const add = async (channelId, tNs, data) =>
    writer.addMessage({ channelId, sequence: seq++, logTime: tNs, publishTime: tNs, data });
  for (let i = 0; i < 20; ++i) {
    const t = T0 + BigInt(i) * 50000000n;  // 20 Hz
    if (i % 5 === 0) {
      const rev = i / 5;
      if (rev < 3) {
        await add(chVel, t, cloud(t, rev, true));
        await add(chHes, t, cloud(t, rev, false));
        await add(chScan, t, scan(t));
      }
    }
    await add(chImu, t, imu(t, i));
    if (i % 2 === 0) {
      await add(chOdom, t, odom(t, i / 2));
      await add(chTf, t, tf(t, i / 2));
    }
  }
  await writer.end();
  file.close();
}
main().catch((e) => { console.error(e); process.exit(1); });
