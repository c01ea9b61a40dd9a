#include "fploc/carmen/carmen.h"

#include <zlib.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <stdexcept>
#include <string_view>

namespace fploc::carmen {
namespace {

[[noreturn]] void fail(const std::string& m) { throw std::runtime_error(m); }

std::vector<std::string_view> split(std::string_view s) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t' || s[i] == '\r')) ++i;
    const size_t b = i;
    while (i < s.size() && s[i] != ' ' && s[i] != '\t' && s[i] != '\r') ++i;
    if (i > b) out.push_back(s.substr(b, i - b));
  }
  return out;
}

struct Fields {
  const std::vector<std::string_view>& t;
  const std::string& where;  // "SOURCE:LINE: RECORD"
  double num(size_t k, const char* name) const {
    if (k >= t.size()) fail(where + ": field " + std::to_string(k) + " (" + name + "): missing (line has " + std::to_string(t.size()) + " fields)");
    double v = 0;
    const char* b = t[k].data();
    const char* e = b + t[k].size();
    if (b < e && *b == '+') ++b;
    auto r = std::from_chars(b, e, v);
    if (r.ec != std::errc() || r.ptr != e || !std::isfinite(v))
      fail(where + ": field " + std::to_string(k) + " (" + name + "): expected a number, got '" + std::string(t[k]) + "'");
    return v;
  }
};

}  // namespace

std::string read_maybe_gz(const std::string& path, std::string* damage) {
  if (!std::filesystem::exists(path)) fail(path + ": no such file");
  gzFile f = gzopen(path.c_str(), "rb");  // reads plain files too
  if (!f) fail(path + ": cannot open");
  std::string out;
  char buf[1 << 16];
  for (;;) {
    const int n = gzread(f, buf, sizeof buf);
    if (n < 0) {
      int err = 0;
      const std::string msg = gzerror(f, &err);
      gzclose(f);
      const std::string what = path + ": byte " + std::to_string(out.size()) + " (decompressed): " + msg;
      if (!damage) fail(what);
      *damage = what;
      return out;
    }
    if (n == 0) break;
    out.append(buf, size_t(n));
    if (out.size() > (size_t(4) << 30)) {
      gzclose(f);
      fail(path + ": larger than 4 GB decompressed");
    }
  }
  // zlib reports a stream cut short ("unexpected end of file") only here: without this a cut .log.gz read as a
  // shorter log.
  if (const int z = gzclose(f); z != Z_OK) {
    const std::string what = path + ": compressed data end early after " + std::to_string(out.size()) + " B decompressed (file truncated?)";
    if (!damage) fail(what);
    *damage = what;
  }
  return out;
}

Log parse_log(const std::string& text, const std::string& source, std::string* damage) {
  Log log;
  size_t line_no = 0, pos = 0;
  long last_odom = -1;  // index into log.odom
  // The odometry chain: `chain_from` is the ODOM pose the next scan's increment is measured from (the last
  // record before the previous scan, or the re-anchoring record after it); `chain` the dead-reckoned pose.
  bool have_from = false, have_chain = false, after_flaser = false;
  Pose2d chain_from, chain;
  auto between = [](const Pose2d& a, const Pose2d& b) {
    const double c = std::cos(a.theta), s = std::sin(a.theta), dx = b.x - a.x, dy = b.y - a.y;
    return Pose2d{c * dx + s * dy, -s * dx + c * dy, std::remainder(b.theta - a.theta, 2 * M_PI)};
  };
  auto compose = [](const Pose2d& a, const Pose2d& d) {
    const double c = std::cos(a.theta), s = std::sin(a.theta);
    return Pose2d{a.x + c * d.x - s * d.y, a.y + s * d.x + c * d.y, std::remainder(a.theta + d.theta, 2 * M_PI)};
  };
  try {
    while (pos < text.size()) {
      size_t e = text.find('\n', pos);
      if (e == std::string::npos) e = text.size();
      const std::string_view line(text.data() + pos, e - pos);
      pos = e + 1;
      ++line_no;
      const auto t = split(line);
      if (t.empty() || t[0][0] == '#') continue;
      const std::string type(t[0]);
      const std::string where = source + ":" + std::to_string(line_no) + ": " + type;
      Fields f{t, where};
      if (type == "FLASER") {
        const double nd = f.num(1, "num_readings");
        if (nd < 1 || nd > 100000 || nd != std::floor(nd))
          fail(where + ": field 1 (num_readings): expected a count in [1, 100000], got '" + std::string(t[1]) + "'");
        const size_t n = size_t(nd);
        if (t.size() < n + 2 + 6 + 1)
          fail(where + ": " + std::to_string(t.size()) + " fields, expected at least " + std::to_string(n + 9) + " for " +
               std::to_string(n) + " readings");
        LaserRecord r;
        r.line = line_no;
        r.ranges.resize(n);
        for (size_t k = 0; k < n; ++k) {
          const double v = f.num(2 + k, "range");
          if (v < 0) fail(where + ": field " + std::to_string(2 + k) + " (range): negative");
          r.ranges[k] = float(v);
        }
        const size_t b = 2 + n;
        r.pose = {f.num(b, "x"), f.num(b + 1, "y"), f.num(b + 2, "theta")};
        r.odom = {f.num(b + 3, "odom_x"), f.num(b + 4, "odom_y"), f.num(b + 5, "odom_theta")};
        r.ipc_timestamp = f.num(b + 6, "ipc_timestamp");
        if (t.size() > b + 8) r.logger_timestamp = f.num(b + 8, "logger_timestamp");
        if (last_odom >= 0) {
          const Pose2d& o = log.odom[size_t(last_odom)].pose;
          chain = have_chain && have_from ? compose(chain, between(chain_from, o)) : o;
          have_chain = true;
          chain_from = o;
          have_from = true;
          r.wheel_odom = chain;
          r.have_wheel_odom = true;
        }
        log.scans.push_back(std::move(r));
        after_flaser = true;
        continue;
      } else if (type == "ODOM") {
        OdomRecord o;
        o.line = line_no;
        o.pose = {f.num(1, "x"), f.num(2, "y"), f.num(3, "theta")};
        o.tv = f.num(4, "tv");
        o.rv = f.num(5, "rv");
        o.accel = f.num(6, "accel");
        o.ipc_timestamp = f.num(7, "ipc_timestamp");
        const Pose2d& fp = log.scans.empty() ? o.pose : log.scans.back().pose;
        if (after_flaser && std::abs(o.pose.x - fp.x) < 1e-6 && std::abs(o.pose.y - fp.y) < 1e-6 &&
            std::abs(o.pose.theta - fp.theta) < 1e-6) {
          // Re-anchoring: the chain continues from here (the next increment is measured from this record).
          ++log.odom_reanchors;
          chain_from = o.pose;
          have_from = have_chain;
          after_flaser = false;
          continue;
        }
        log.odom.push_back(o);
        last_odom = long(log.odom.size()) - 1;
      } else {
        ++log.skipped[type];
      }
      after_flaser = false;
    }
  } catch (const std::runtime_error& ex) {
    // A bad record: without `damage` the error; with it, the records before it are the log.
    if (!damage || log.scans.empty()) throw;
    *damage = ex.what();
  }
  if (log.scans.empty()) fail(source + ": no FLASER records (is this a CARMEN log?)");
  return log;
}

double beam_increment(size_t n) { return n % 2 == 0 ? M_PI / double(n) : M_PI / double(std::max<size_t>(1, n - 1)); }

float no_return_range(const Log& log) {
  float mx = 0;
  size_t total = 0;
  for (const auto& s : log.scans)
    for (float r : s.ranges) mx = std::max(mx, r), ++total;
  size_t at = 0;
  for (const auto& s : log.scans)
    for (float r : s.ranges) at += r == mx;
  return total && at * 100 >= total ? mx : std::numeric_limits<float>::infinity();
}

std::vector<double> scan_times(const Log& log, std::string* note) {
  const size_t n = log.scans.size();
  std::vector<double> t(n);
  std::set<long long> distinct;
  for (size_t k = 0; k < n; ++k) {
    t[k] = log.scans[k].ipc_timestamp;
    distinct.insert(std::llround(t[k] * 1000));
  }
  if (distinct.size() * 2 < n) {
    const double span = n > 1 ? t.back() - t.front() : 0;
    const double dt = span > 0 ? span / double(n - 1) : 1.0;
    for (size_t k = 0; k < n; ++k) t[k] = t.front() + dt * double(k);
    if (note)
      *note = "timestamps resolve only " + std::to_string(distinct.size()) + " of " + std::to_string(n) +
              " scans: placed evenly, " + std::to_string(dt) + " s apart";
    return t;
  }
  size_t moved = 0;
  for (size_t k = 1; k < n; ++k)
    if (!(t[k] > t[k - 1] + 0.0005)) {
      t[k] = t[k - 1] + 0.001;
      ++moved;
    }
  if (note) *note = moved ? std::to_string(moved) + " out-of-order timestamps moved 1 ms after their predecessor" : "";
  return t;
}

Grid build_grid(const std::vector<const LaserRecord*>& scans, const GridConfig& cfg) {
  Grid g;
  g.resolution = cfg.resolution;
  if (scans.empty() || !(cfg.resolution > 0)) return g;
  // Extent: every beam end point (no-return beams up to max_free_m).
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  auto beam_end = [&](const LaserRecord& s, size_t i, double* ex, double* ey, bool* hit) {
    const double a = s.pose.theta - M_PI / 2 + double(i) * beam_increment(s.ranges.size());
    const double r = s.ranges[i];
    *hit = r < cfg.no_return && r >= cfg.min_range_m;
    const double d = *hit ? r : std::min<double>(cfg.max_free_m, r);
    *ex = s.pose.x + d * std::cos(a);
    *ey = s.pose.y + d * std::sin(a);
  };
  for (const auto* s : scans)
    for (size_t i = 0; i < s->ranges.size(); ++i) {
      double ex, ey;
      bool hit;
      beam_end(*s, i, &ex, &ey, &hit);
      x0 = std::min({x0, ex, s->pose.x});
      y0 = std::min({y0, ey, s->pose.y});
      x1 = std::max({x1, ex, s->pose.x});
      y1 = std::max({y1, ey, s->pose.y});
    }
  g.origin_x = std::floor((x0 - cfg.margin_m) / cfg.resolution) * cfg.resolution;
  g.origin_y = std::floor((y0 - cfg.margin_m) / cfg.resolution) * cfg.resolution;
  g.width = int(std::ceil((x1 + cfg.margin_m - g.origin_x) / cfg.resolution));
  g.height = int(std::ceil((y1 + cfg.margin_m - g.origin_y) / cfg.resolution));
  if (double(g.width) * g.height > 2e8) fail("occupancy grid too large (" + std::to_string(g.width) + " x " + std::to_string(g.height) + ")");
  std::vector<uint32_t> hits(size_t(g.width) * g.height, 0), miss(size_t(g.width) * g.height, 0);
  auto cell = [&](double x, double y, int* i, int* j) {
    *i = int(std::floor((x - g.origin_x) / g.resolution));
    *j = int(std::floor((y - g.origin_y) / g.resolution));
    return *i >= 0 && *j >= 0 && *i < g.width && *j < g.height;
  };
  for (const auto* s : scans)
    for (size_t k = 0; k < s->ranges.size(); ++k) {
      double ex, ey;
      bool hit;
      beam_end(*s, k, &ex, &ey, &hit);
      int ia, ja, ib, jb;
      if (!cell(s->pose.x, s->pose.y, &ia, &ja) || !cell(ex, ey, &ib, &jb)) continue;
      // Bresenham from the laser's cell to the end cell (exclusive).
      int di = std::abs(ib - ia), dj = -std::abs(jb - ja), si = ia < ib ? 1 : -1, sj = ja < jb ? 1 : -1, err = di + dj;
      int i = ia, j = ja;
      // A hit's own surface is not crossed: cells within hit_clearance_m of the end point are not marked free
      // (beams that graze a wall at a shallow angle would otherwise erase it).
      const double clear2 = hit ? cfg.hit_clearance_m * cfg.hit_clearance_m / (g.resolution * g.resolution) : -1.0;
      while (i != ib || j != jb) {
        if (double(i - ib) * (i - ib) + double(j - jb) * (j - jb) > clear2) ++miss[size_t(j) * g.width + i];
        const int e2 = 2 * err;
        if (e2 >= dj) err += dj, i += si;
        if (e2 <= di) err += di, j += sj;
      }
      if (hit) ++hits[size_t(jb) * g.width + ib];
      else ++miss[size_t(jb) * g.width + ib];
    }
  g.cells.assign(size_t(g.width) * g.height, -1);
  for (size_t c = 0; c < g.cells.size(); ++c) {
    const double h = hits[c], m = miss[c];
    if (h >= cfg.min_hits && h >= cfg.occupied_ratio * (h + m)) g.cells[c] = 100;
    else if (m > 0) g.cells[c] = 0;
  }
  return g;
}

void write_map_server(const Grid& g, const std::string& dir, const std::string& name) {
  std::filesystem::create_directories(dir);
  const std::string pgm = (std::filesystem::path(dir) / (name + ".pgm")).string();
  const std::string yaml = (std::filesystem::path(dir) / (name + ".yaml")).string();
  std::ofstream f(pgm, std::ios::binary);
  if (!f) fail(pgm + ": cannot write");
  f << "P5\n# fploc carmen occupancy grid\n" << g.width << " " << g.height << "\n255\n";
  std::string row(size_t(g.width), '\0');
  for (int r = 0; r < g.height; ++r) {
    const int j = g.height - 1 - r;
    for (int i = 0; i < g.width; ++i) {
      const int8_t v = g.cells[size_t(j) * g.width + i];
      row[size_t(i)] = char(v == 100 ? 0 : v == 0 ? 254 : 205);
    }
    f.write(row.data(), std::streamsize(row.size()));
  }
  if (!f) fail(pgm + ": write error");
  std::ofstream y(yaml);
  if (!y) fail(yaml + ": cannot write");
  y.precision(12);
  y << "image: " << name << ".pgm\nresolution: " << g.resolution << "\norigin: [" << g.origin_x << ", " << g.origin_y
    << ", 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n";
}

}  // namespace fploc::carmen
