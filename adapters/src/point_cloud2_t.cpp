#include "fploc/adapters/point_cloud2_t.h"

#include <cstring>

namespace fploc::adapters {

void to_msg_header(const rec::PointCloud2& c, int64_t seq, const std::string& source, point_cloud2_t& m) {
  m.utime = c.header.stamp_ns / 1000;
  m.utime_ns = int32_t(c.header.stamp_ns - m.utime * 1000);
  m.seq = seq;
  m.frame = c.header.frame_id;
  m.source = source;
  m.height = int32_t(c.height);
  m.width = int32_t(c.width);
  m.num_fields = int32_t(c.fields.size());
  m.field_name.clear();
  m.field_offset.clear();
  m.field_datatype.clear();
  m.field_count.clear();
  for (const auto& f : c.fields) {
    m.field_name.push_back(f.name);
    m.field_offset.push_back(int32_t(f.offset));
    m.field_datatype.push_back(int8_t(f.datatype));
    m.field_count.push_back(int32_t(f.count));
  }
  m.is_bigendian = c.is_bigendian;
  m.is_dense = c.is_dense;
  m.point_step = int32_t(c.point_step);
  m.row_step = int32_t(c.row_step);
  m.size = 0;
  m.data.clear();
}

void to_msg(const rec::PointCloud2& c, int64_t seq, const std::string& source, point_cloud2_t& m) {
  to_msg_header(c, seq, source, m);
  m.size = int32_t(c.data_size);
  m.data.assign(c.data, c.data + c.data_size);
}

void encode_without_data(const rec::PointCloud2& c, int64_t seq, const std::string& source, std::vector<uint8_t>& out) {
  static thread_local point_cloud2_t m;  // keeps its string vectors' capacity from cloud to cloud
  to_msg_header(c, seq, source, m);
  out.resize(size_t(m.getEncodedSize()));
  m.encode(out.data(), 0, int(out.size()));
  // The data is the last field: its int32 count ends the header (big-endian, as LCM encodes it).
  const uint32_t n = __builtin_bswap32(uint32_t(c.data_size));
  std::memcpy(out.data() + out.size() - 4, &n, 4);
}

bool from_msg(const point_cloud2_t& m, rec::PointCloud2& c, std::string* err) {
  if (m.height < 0 || m.width < 0 || m.point_step < 0 || m.row_step < 0 || m.size != int32_t(m.data.size())) {
    if (err) *err = "point_cloud2_t from " + m.source + ": negative height/width/point_step/row_step or size != data";
    return false;
  }
  c.header.stamp_ns = m.utime * 1000 + m.utime_ns;
  c.header.frame_id = m.frame;
  c.height = uint32_t(m.height);
  c.width = uint32_t(m.width);
  c.fields.resize(size_t(m.num_fields));
  for (size_t i = 0; i < c.fields.size(); ++i) {
    if (m.field_offset[i] < 0 || m.field_count[i] < 0) {
      if (err) *err = "point_cloud2_t from " + m.source + ": field '" + m.field_name[i] + "' has a negative offset or count";
      return false;
    }
    c.fields[i] = {m.field_name[i], uint32_t(m.field_offset[i]), uint8_t(m.field_datatype[i]), uint32_t(m.field_count[i])};
  }
  c.is_bigendian = m.is_bigendian;
  c.is_dense = m.is_dense;
  c.point_step = uint32_t(m.point_step);
  c.row_step = uint32_t(m.row_step);
  c.data = m.data.data();
  c.data_size = m.data.size();
  return true;
}

}  // namespace fploc::adapters
