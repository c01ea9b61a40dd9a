#include "fploc/recording/ros_msgs.h"

#include <cstring>

#include "wire.h"

namespace fploc::rec {
namespace {

bool done(const Wire& w, const char* type, std::string* err) {
  if (w.ok()) return true;
  if (err) *err = std::string(type) + ": field '" + w.failed_field() + "' runs past the end of the message";
  return false;
}

void header(Wire& w, Header& h) {
  if (!w.cdr()) {
    w.field("header.seq");
    w.get<uint32_t>();
  }
  w.field("header.stamp");
  const int64_t sec = w.cdr() ? int64_t(w.get<int32_t>()) : int64_t(w.get<uint32_t>());
  const uint32_t nsec = w.get<uint32_t>();
  h.stamp_ns = sec * 1000000000 + nsec;
  w.field("header.frame_id");
  h.frame_id = w.str();
}

template <size_t N>
void doubles(Wire& w, std::array<double, N>& a) {
  for (auto& v : a) v = w.get<double>();
}
void skip_doubles(Wire& w, int n) {
  for (int i = 0; i < n; ++i) w.get<double>();
}

void transform(Wire& w, Transform& t) {
  header(w, t.header);
  w.field("child_frame_id");
  t.child_frame_id = w.str();
  w.field("transform");
  doubles(w, t.t);
  doubles(w, t.q);
}

}  // namespace

bool decode(const uint8_t* d, size_t n, Encoding e, PointCloud2& c, std::string* err) {
  Wire w(d, n, e);
  header(w, c.header);
  w.field("height");
  c.height = w.get<uint32_t>();
  w.field("width");
  c.width = w.get<uint32_t>();
  w.field("fields");
  const uint32_t nf = w.count(9);
  c.fields.clear();
  for (uint32_t i = 0; i < nf && w.ok(); ++i) {
    PointField f;
    f.name = w.str();
    f.offset = w.get<uint32_t>();
    f.datatype = w.get<uint8_t>();
    f.count = w.get<uint32_t>();
    c.fields.push_back(std::move(f));
  }
  w.field("is_bigendian");
  c.is_bigendian = w.get<uint8_t>() != 0;
  w.field("point_step");
  c.point_step = w.get<uint32_t>();
  w.field("row_step");
  c.row_step = w.get<uint32_t>();
  w.field("data");
  const uint32_t nd = w.count(1);
  c.data = w.bytes(nd);
  c.data_size = nd;
  w.field("is_dense");
  c.is_dense = w.get<uint8_t>() != 0;
  return done(w, "sensor_msgs/PointCloud2", err);
}

bool decode(const uint8_t* d, size_t n, Encoding e, Imu& m, std::string* err) {
  Wire w(d, n, e);
  header(w, m.header);
  w.field("orientation");
  doubles(w, m.orientation);
  skip_doubles(w, 9);
  w.field("angular_velocity");
  doubles(w, m.angular_velocity);
  skip_doubles(w, 9);
  w.field("linear_acceleration");
  doubles(w, m.linear_acceleration);
  skip_doubles(w, 9);
  return done(w, "sensor_msgs/Imu", err);
}

bool decode(const uint8_t* d, size_t n, Encoding e, LaserScanView& m, std::string* err) {
  Wire w(d, n, e);
  header(w, m.header);
  w.field("angles");
  m.angle_min = w.get<float>();
  m.angle_max = w.get<float>();
  m.angle_increment = w.get<float>();
  m.time_increment = w.get<float>();
  m.scan_time = w.get<float>();
  m.range_min = w.get<float>();
  m.range_max = w.get<float>();
  w.field("ranges");
  m.num_ranges = w.count(4);
  m.ranges = w.float_bytes(m.num_ranges);
  w.field("intensities");
  m.num_intensities = w.count(4);
  m.intensities = w.float_bytes(m.num_intensities);
  m.big_endian = w.big_endian();
  if (!w.ok()) m.num_ranges = m.num_intensities = 0, m.ranges = m.intensities = nullptr;
  return done(w, "sensor_msgs/LaserScan", err);
}

namespace {
// c floats from the message's bytes, swapped when the message is big-endian.
void copy_floats(const uint8_t* p, uint32_t c, bool swap, std::vector<float>& out) {
  out.resize(c);
  if (c) std::memcpy(out.data(), p, size_t(c) * 4);
  if (swap)
    for (auto& f : out) {
      uint32_t u;
      std::memcpy(&u, &f, 4);
      u = __builtin_bswap32(u);
      std::memcpy(&f, &u, 4);
    }
}
}  // namespace

bool decode(const uint8_t* d, size_t n, Encoding e, LaserScan& m, std::string* err) {
  LaserScanView v;
  const bool ok = decode(d, n, e, v, err);
  m.header = std::move(v.header);
  m.angle_min = v.angle_min, m.angle_max = v.angle_max, m.angle_increment = v.angle_increment;
  m.time_increment = v.time_increment, m.scan_time = v.scan_time, m.range_min = v.range_min, m.range_max = v.range_max;
  copy_floats(v.ranges, v.num_ranges, v.big_endian, m.ranges);
  copy_floats(v.intensities, v.num_intensities, v.big_endian, m.intensities);
  return ok;
}

bool decode(const uint8_t* d, size_t n, Encoding e, Odometry& m, std::string* err) {
  Wire w(d, n, e);
  header(w, m.pose.header);
  w.field("child_frame_id");
  m.pose.child_frame_id = w.str();
  w.field("pose.pose");
  doubles(w, m.pose.t);
  doubles(w, m.pose.q);
  w.field("pose.covariance");
  skip_doubles(w, 36);
  w.field("twist");
  skip_doubles(w, 6 + 36);
  return done(w, "nav_msgs/Odometry", err);
}

bool decode_tf(const uint8_t* d, size_t n, Encoding e, std::vector<Transform>& out, std::string* err) {
  Wire w(d, n, e);
  w.field("transforms");
  const uint32_t k = w.count(4 + 4 + 4 + 4 + 7 * 8);
  out.resize(k);
  for (uint32_t i = 0; i < k && w.ok(); ++i) transform(w, out[i]);
  return done(w, "tf2_msgs/TFMessage", err);
}

bool decode_bytes(const uint8_t* d, size_t n, Encoding e, const uint8_t** data, size_t* size, std::string* err) {
  Wire w(d, n, e);
  w.field("buf");
  const uint32_t k = w.count(1);
  *data = w.bytes(k);
  *size = k;
  return done(w, "uint8[] buf", err);
}

bool decode_string(const uint8_t* d, size_t n, Encoding e, std::string& out, std::string* err) {
  Wire w(d, n, e);
  w.field("data");
  out = w.str();
  return done(w, "std_msgs/String", err);
}

}  // namespace fploc::rec
