#include "fploc/recording/cloud_to_scan.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>

namespace fploc::rec {
namespace {

struct Getter {
  int off = -1;
  uint8_t type = 0;
  bool swap = false;
  bool ok() const { return off >= 0; }
  [[gnu::always_inline]] inline double operator()(const uint8_t* p) const {
    p += off;
    if (!swap) switch (type) {  // the usual little-endian case without the byte shuffle
        case 2: return double(p[0]);
        case 4: { uint16_t v; std::memcpy(&v, p, 2); return v; }
        case 6: { uint32_t v; std::memcpy(&v, p, 4); return v; }
        case 7: { float v; std::memcpy(&v, p, 4); return v; }
        case 8: { double v; std::memcpy(&v, p, 8); return v; }
        default: break;
      }
    uint8_t b[8];
    const int n = type <= 2 ? 1 : type <= 4 ? 2 : type <= 7 ? 4 : 8;
    if (swap) for (int k = 0; k < n; ++k) b[k] = p[n - 1 - k];
    else std::memcpy(b, p, size_t(n));
    switch (type) {
      case 1: return double(int8_t(b[0]));
      case 2: return double(b[0]);
      case 3: { int16_t v; std::memcpy(&v, b, 2); return v; }
      case 4: { uint16_t v; std::memcpy(&v, b, 2); return v; }
      case 5: { int32_t v; std::memcpy(&v, b, 4); return v; }
      case 6: { uint32_t v; std::memcpy(&v, b, 4); return v; }
      case 7: { float v; std::memcpy(&v, b, 4); return v; }
      case 8: { double v; std::memcpy(&v, b, 8); return v; }
    }
    return 0;
  }
};

// atan2 to ~1e-5 rad (a minimax polynomial for atan on [0, 1]): column binning needs ~1e-4.
inline float fast_atan2(float y, float x) {
  const float ax = std::abs(x), ay = std::abs(y);
  const float mx = std::max(ax, ay), mn = std::min(ax, ay);
  if (mx == 0.f) return 0.f;
  const float a = mn / mx, q = a * a;
  float r = ((-0.0464964749f * q + 0.15931422f) * q - 0.327622764f) * q * a + a;
  if (ay > ax) r = 1.57079637f - r;
  if (x < 0.f) r = 3.14159274f - r;
  return y < 0.f ? -r : r;
}

inline bool is_f32le(const Getter& g) { return g.type == 7 && !g.swap; }
inline float f32(const uint8_t* p, int off) {
  float v;
  std::memcpy(&v, p + off, 4);
  return v;
}

// std::lround for x >= 0 (half away from zero) without the libm call; exact: x - trunc(x) is exact.
inline int64_t round_nonneg(double x) {
  const int64_t i = int64_t(x);
  return i + (x - double(i) >= 0.5);
}
// std::floor for |x| < 2^62 without the libm call (exact).
inline int64_t floor_i64(double x) {
  const int64_t i = int64_t(x);
  return i - (x < double(i));
}

int type_size(uint8_t t) { return t == 0 || t > 8 ? 0 : t <= 2 ? 1 : t <= 4 ? 2 : t <= 7 ? 4 : 8; }

}  // namespace

bool cloud_to_scan(const PointCloud2& c, const CloudOptions& opt, Scan& out, CloudStats* st, std::string* err) {
  CloudStats local;
  CloudStats& s = st ? *st : local;
  s = CloudStats{};
  auto field = [&](std::initializer_list<const char*> names, std::string* which = nullptr) {
    for (const char* n : names)
      for (const auto& f : c.fields)
        if (f.name == n && type_size(f.datatype) > 0 && f.offset + type_size(f.datatype) <= c.point_step) {
          if (which) *which = n;
          return Getter{int(f.offset), f.datatype, c.is_bigendian};
        }
    return Getter{};
  };
  const Getter gx = field({"x"}), gy = field({"y"}), gz = field({"z"});
  if (!gx.ok() || !gy.ok() || !gz.ok()) return *err = "PointCloud2 without x/y/z fields inside point_step", false;
  std::string ring_name, time_name;
  const Getter gi = field({"intensity", "reflectivity", "signal"});
  const Getter gr = field({"ring", "channel", "line"}, &ring_name);
  const Getter gt = field({"t", "time", "timestamp", "offset_time", "time_offset"}, &time_name);
  const uint64_t npts = uint64_t(c.width) * c.height;
  if (c.point_step == 0 || npts == 0) return *err = "PointCloud2 is empty", false;
  if (c.height > 1 && uint64_t(c.row_step) < uint64_t(c.width) * c.point_step) return *err = "PointCloud2 row_step < width * point_step", false;
  const uint64_t row_step = c.height > 1 ? c.row_step : uint64_t(c.width) * c.point_step;
  if ((unsigned __int128)row_step * (c.height - 1) + (unsigned __int128)c.width * c.point_step > c.data_size)
    return *err = "PointCloud2 data (" + std::to_string(c.data_size) + " B) shorter than height/width/point_step say", false;
  s.points = npts;

  struct P {
    float az, el, sn;  // azimuth, elevation (approximate: for clustering), sin(elevation) (exact)
    uint32_t r_mm;
    int ring;
    uint32_t row, col;  // where it is in the cloud
    float inten;
    double t;
  };
  static thread_local std::vector<P> pts;  // reused: a cloud at 10-20 Hz should not cost page faults
  pts.clear();
  pts.reserve(npts);
  const double stamp_s = c.header.stamp_ns * 1e-9;
  const bool xyz_f32 = is_f32le(gx) && is_f32le(gy) && is_f32le(gz);
  const bool need_el = !(gr.ok() && opt.rings == 0);  // elevation bins rings only without a ring field
  const bool t_rel_ns = time_name == "t" || time_name == "offset_time";
  for (uint32_t row = 0; row < c.height; ++row) {
    const uint8_t* base = c.data + row * row_step;
    for (uint32_t k = 0; k < c.width; ++k) {
      const uint8_t* p = base + uint64_t(k) * c.point_step;
      double x, y, z;
      if (xyz_f32) x = f32(p, gx.off), y = f32(p, gy.off), z = f32(p, gz.off);
      else x = gx(p), y = gy(p), z = gz(p);
      const double r = std::sqrt(x * x + y * y + z * z);
      if (!std::isfinite(r) || r < 1e-3 || r > 2000.0) {
        ++s.no_return;
        ++(!std::isfinite(r) ? s.not_finite : r < 1e-3 ? s.zero_range : s.too_far);
        continue;
      }
      P q;
      q.row = row, q.col = k;
      q.az = fast_atan2(float(y), float(x));
      q.el = need_el ? fast_atan2(float(z), float(std::sqrt(x * x + y * y))) : 0.f;
      q.sn = float(z / r);
      q.r_mm = uint32_t(r * 1000.0 + 0.5);
      const double ring = gr.ok() ? gr(p) : 0.0;
      if (!(ring >= 0.0 && ring <= 1023.0)) return *err = "ring value " + std::to_string(ring) + " out of range", false;
      q.ring = int(ring);
      const double inten = gi.ok() ? gi(p) : 0.0;
      q.inten = std::isfinite(inten) ? float(std::clamp(inten, 0.0, 65535.0)) : 0.f;
      double t = stamp_s;
      if (gt.ok()) {
        const double v = gt(p);
        if (t_rel_ns) t = stamp_s + v * 1e-9;
        else if (v > 1e15) t = v * 1e-9;  // absolute ns (Livox)
        else if (v > 1e8) t = v;          // absolute s (Hesai, Robosense)
        else t = stamp_s + v;             // relative s (Velodyne)
      }
      q.t = std::isfinite(t) && std::abs(t) < 1e11 ? t : stamp_s;  // garbage times: the header stamp
      pts.push_back(q);
    }
  }
  if (pts.empty()) return *err = "PointCloud2 has no finite point", false;
  s.time_source = gt.ok() ? "field '" + time_name + "'" : "header stamp";

  // Rings -> rows (top beam first).
  static thread_local std::vector<int> ring_of;
  ring_of.assign(pts.size(), 0);
  int nrings = 0;
  std::vector<double> alt;
  if (gr.ok() && opt.rings == 0) {
    s.ring_source = "field '" + ring_name + "'";
    // An organised cloud (most rows each the row of one ring value): a point whose ring value has no row of its own
    // (one bad value, a ring the driver mislabelled) is a point of its row's ring, the row being its beam.
    if (c.height > 1 && c.height <= 1024) {
      std::vector<uint32_t> cnt(size_t(1024) * c.height, 0), tot(1024, 0);
      for (const auto& q : pts) ++cnt[size_t(q.ring) * c.height + q.row], ++tot[size_t(q.ring)];
      std::vector<int> owner(c.height, -1);
      for (int ring = 0; ring < 1024; ++ring) {
        if (!tot[size_t(ring)]) continue;
        const uint32_t* row = &cnt[size_t(ring) * c.height];
        const uint32_t best = uint32_t(std::max_element(row, row + c.height) - row);
        if (2 * uint64_t(row[best]) < tot[size_t(ring)]) continue;  // no row holds half of it
        int& o = owner[best];
        if (o < 0 || cnt[size_t(o) * c.height + best] < row[best]) o = ring;
      }
      std::vector<uint8_t> has_row(1024, 0);
      uint32_t rows_owned = 0;
      for (int o : owner)
        if (o >= 0) has_row[size_t(o)] = 1, ++rows_owned;
      if (2 * rows_owned > c.height)
        for (auto& q : pts)
          if (!has_row[size_t(q.ring)] && owner[q.row] >= 0) q.ring = owner[q.row], ++s.relabelled_points;
    }
    std::vector<std::pair<double, int>> acc(1024, {0.0, 0});
    for (const auto& q : pts) {
      auto& a = acc[size_t(q.ring)];
      a.first += q.sn;
      ++a.second;
    }
    std::vector<std::pair<double, int>> order;  // (mean elevation, ring value)
    for (int ring = 0; ring < 1024; ++ring)
      if (acc[size_t(ring)].second)
        order.push_back({std::asin(std::clamp(acc[size_t(ring)].first / acc[size_t(ring)].second, -1.0, 1.0)), ring});
    std::sort(order.begin(), order.end(), [](auto& a, auto& b) { return a.first > b.first; });
    std::vector<int> row(1024, 0);
    for (size_t i = 0; i < order.size(); ++i) {
      row[size_t(order[i].second)] = int(i);
      alt.push_back(order[i].first * 180.0 / M_PI);
    }
    for (size_t i = 0; i < pts.size(); ++i) ring_of[i] = row[size_t(pts[i].ring)];
    nrings = int(order.size());
  } else {
    s.ring_source = "elevation";
    std::vector<float> el(pts.size());
    for (size_t i = 0; i < pts.size(); ++i) el[i] = pts[i].el;
    std::sort(el.begin(), el.end());
    std::vector<std::pair<float, size_t>> gaps;  // (gap, index after it)
    for (size_t i = 1; i < el.size(); ++i) gaps.push_back({el[i] - el[i - 1], i});
    std::vector<size_t> cuts;
    if (opt.rings > 0) {
      const size_t k = std::min(gaps.size(), size_t(opt.rings - 1));
      std::partial_sort(gaps.begin(), gaps.begin() + k, gaps.end(), [](auto& a, auto& b) { return a.first > b.first; });
      for (size_t i = 0; i < k; ++i) cuts.push_back(gaps[i].second);
    } else {
      const float g = float(opt.gap_deg * M_PI / 180.0);
      for (const auto& [gap, i] : gaps)
        if (gap > g) cuts.push_back(i);
    }
    std::sort(cuts.begin(), cuts.end());
    if (cuts.size() + 1 > 512) return *err = "no ring structure in the point elevations (give the ring count)", false;
    // Boundaries (elevations) between rings, ascending; ring from the bottom.
    std::vector<float> bounds;
    for (size_t i : cuts) bounds.push_back(0.5f * (el[i - 1] + el[i]));
    nrings = int(bounds.size()) + 1;
    std::vector<double> sum(size_t(nrings), 0.0);
    std::vector<int> cnt(size_t(nrings), 0);
    for (size_t i = 0; i < pts.size(); ++i) {
      const int from_bottom = int(std::upper_bound(bounds.begin(), bounds.end(), pts[i].el) - bounds.begin());
      ring_of[i] = nrings - 1 - from_bottom;
      sum[size_t(ring_of[i])] += pts[i].sn;
      ++cnt[size_t(ring_of[i])];
    }
    for (int r = 0; r < nrings; ++r)
      alt.push_back(cnt[size_t(r)] ? std::asin(std::clamp(sum[size_t(r)] / cnt[size_t(r)], -1.0, 1.0)) * 180.0 / M_PI : 0.0);
  }

  // Each ring's row in an organised cloud: the row holding at least half of its points, unless another ring holds
  // more there. Rows that are rings for most of the cloud make it organised (W its width).
  std::vector<int64_t> ring_row(size_t(nrings), -1);
  uint32_t rows_owned = 0;
  if (c.height > 1 && c.height <= 1024) {
    std::vector<uint32_t> cnt(size_t(nrings) * c.height, 0), tot(size_t(nrings), 0);
    for (size_t i = 0; i < pts.size(); ++i) ++cnt[size_t(ring_of[i]) * c.height + pts[i].row], ++tot[size_t(ring_of[i])];
    std::vector<int> owner(c.height, -1);
    for (int u = 0; u < nrings; ++u) {
      if (!tot[size_t(u)]) continue;
      const uint32_t* row = &cnt[size_t(u) * c.height];
      const uint32_t best = uint32_t(std::max_element(row, row + c.height) - row);
      if (2 * uint64_t(row[best]) < tot[size_t(u)]) continue;
      int& o = owner[best];
      if (o < 0 || cnt[size_t(o) * c.height + best] < row[best]) o = u;
    }
    for (uint32_t r = 0; r < c.height; ++r)
      if (owner[r] >= 0) ring_row[size_t(owner[r])] = r, ++rows_owned;
  }
  const bool rows_are_rings = c.height > 1 && 2 * rows_owned > c.height;
  int W = opt.columns;
  if (W <= 0) {
    if (c.height > 1 && (int(c.height) == nrings || rows_are_rings)) {
      W = int(c.width);
    } else {
      std::vector<int> per(size_t(nrings), 0);
      for (int r : ring_of) ++per[size_t(r)];
      W = *std::max_element(per.begin(), per.end());
    }
  }
  W = std::clamp(W, 8, 16384);

  // An organised cloud (a ring per row, W its width): each point's column in the cloud, shifted per ring by the
  // rounded median of (azimuth column - cloud column), is its pixel, one point per pixel. Binning by azimuth instead
  // puts two neighbours of a ring whose azimuths straddle a column edge (a beam azimuth offset near half a column, a
  // motion-compensated cloud) into one pixel. A ring whose points all lie within a column of its shift is taken
  // whole; otherwise only its points within a column of the shift are, and the others (off their ring's row, more
  // than a column off) are binned by azimuth: stray points. A ring without a row of its own, or with more than half
  // of its points stray, is binned by azimuth whole. One bad ring or point does not demote the cloud.
  const double col = 2.0 * M_PI / W;
  auto az_col = [&](const P& q) {  // the point's column (not rounded) in the Ouster convention
    const double a = q.az < 0 ? q.az + 2.0 * M_PI : q.az;
    return (2.0 * M_PI - a) / col;
  };
  auto wrap = [&](double d) {  // into [-W/2, W/2)
    d = std::fmod(d, double(W));
    if (d < -0.5 * W) d += W;
    if (d >= 0.5 * W) d -= W;
    return d;
  };
  std::vector<int> shift(size_t(nrings), 0);
  std::vector<double> ring_az_deg(size_t(nrings), 0.0), off(size_t(nrings), 0.0);
  static thread_local std::vector<uint8_t> by_col;  // 1: the point's pixel from its column in the cloud
  by_col.assign(pts.size(), 0);
  bool organised = c.height > 1 && W == int(c.width) && (int(c.height) == nrings || rows_are_rings);
  if (organised) {
    std::vector<std::vector<uint32_t>> members(static_cast<size_t>(nrings));  // the points in their ring's row
    for (size_t i = 0; i < pts.size(); ++i) {
      const int u = ring_of[i];
      if (ring_row[size_t(u)] == int64_t(pts[i].row)) members[size_t(u)].push_back(uint32_t(i));
    }
    std::vector<double> d, v;
    int rings_by_col = 0;
    for (int u = 0; u < nrings; ++u) {
      const auto& m = members[size_t(u)];
      if (m.empty()) continue;
      d.clear();
      for (uint32_t i : m) d.push_back(wrap(az_col(pts[i]) - pts[i].col));
      const double d0 = d[0];
      for (auto& x : d) x = wrap(x - d0);
      v = d;
      std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
      const double med = v[v.size() / 2];
      double lo = 1e300, hi = -1e300;
      for (double x : d) lo = std::min(lo, x - med), hi = std::max(hi, x - med);
      const bool whole = hi - lo <= 2.0;  // every point within a column of one shift
      double sum = 0;
      size_t kept = 0;
      for (size_t j = 0; j < m.size(); ++j)
        if (whole || std::abs(d[j] - med) <= 1.0) sum += d[j] - med, ++kept;
      if (2 * kept <= m.size()) continue;  // mostly stray: the ring by azimuth
      for (size_t j = 0; j < m.size(); ++j)
        if (whole || std::abs(d[j] - med) <= 1.0) by_col[m[j]] = 1;
      ++rings_by_col;
      const double mean = med + sum / double(kept);
      shift[size_t(u)] = int(std::lround(d0 + med));
      off[size_t(u)] = wrap(d0 + mean - shift[size_t(u)]);  // the ring's mean offset from its pixels (columns)
      ring_az_deg[size_t(u)] = off[size_t(u)] * col * 180.0 / M_PI;
    }
    organised = rings_by_col > 0;
    if (organised) {
      std::vector<uint8_t> ring_by_col(size_t(nrings), 0);
      for (size_t i = 0; i < pts.size(); ++i) {
        if (by_col[i]) ring_by_col[size_t(ring_of[i])] = 1;
        else ++s.stray_points;
      }
      for (int u = 0; u < nrings; ++u) s.azimuth_rings += !ring_by_col[size_t(u)];
    } else {
      std::fill(by_col.begin(), by_col.end(), 0);
    }
  }
  s.column_source = organised ? "organised" : "azimuth";

  out.resize(nrings, W);
  out.column_utime.assign(size_t(W), INT64_MAX);
  out.beams = BeamIntrinsics{};
  out.beams.altitude_deg = alt;
  out.beams.azimuth_deg = organised ? ring_az_deg : std::vector<double>(size_t(nrings), 0.0);
  out.beams.pixel_shift_by_row.assign(size_t(nrings), 0);
  out.beams.beam_offset_mm = 0.0;
  out.beams.lidar_to_sensor = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  out.missing_columns = 0;
  out.status = ScanStatus::kOk;
  double t0 = 1e300, max_err = s.max_azimuth_error_deg;  // (a local: kept in a register)
  for (size_t i = 0; i < pts.size(); ++i) {
    const P& q = pts[i];
    const double fv = az_col(q);
    int v;
    if (by_col[i]) {
      const int u = ring_of[i];
      v = int((int64_t(q.col) + shift[size_t(u)]) % W);
      if (v < 0) v += W;
      // Its azimuth against the pixel's in the model (the column's angle and the ring's beam azimuth).
      max_err = std::max(max_err, std::abs(wrap(fv - v) - off[size_t(u)]) * col * 180.0 / M_PI);
    } else {
      // By azimuth: the pixel whose azimuth in the model (with the ring's beam azimuth) is nearest.
      const double fa = fv - off[size_t(ring_of[i])];
      const int64_t fr = fa >= 0.0 && fa < 1e15 ? round_nonneg(fa) : std::llround(fa);
      v = int(fr % W);
      if (v < 0) v += W;
      max_err = std::max(max_err, std::abs(fa - double(fr)) * col * 180.0 / M_PI);
    }
    const size_t k = size_t(ring_of[i]) * W + v;
    if (out.range_mm[k] != 0) {
      ++s.collisions;
      if (out.range_mm[k] <= q.r_mm) continue;  // keep the nearer return
    } else {
      ++s.kept;
    }
    out.range_mm[k] = q.r_mm;
    out.signal[k] = uint16_t(std::clamp(q.inten, 0.f, 65535.f));
    out.reflectivity[k] = uint8_t(std::clamp(q.inten, 0.f, 255.f));
    const int64_t tu = floor_i64(q.t * 1e6 + 0.5);  // |q.t| < 1e11 s
    out.column_utime[size_t(v)] = std::min(out.column_utime[size_t(v)], tu);
    t0 = std::min(t0, q.t);
  }
  s.max_azimuth_error_deg = max_err;
  const int64_t stamp_us = c.header.stamp_ns / 1000;
  for (auto& t : out.column_utime)
    if (t == INT64_MAX) t = stamp_us;
  out.utime = gt.ok() ? int64_t(std::llround(t0 * 1e6)) : stamp_us;
  return true;
}

}  // namespace fploc::rec
