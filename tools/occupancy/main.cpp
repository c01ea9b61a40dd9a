// fploc occupancy MAP.yaml [--tolerance CELLS] [--out PLAN.json|.csv] [--compare PLAN] [--json]
//                 [--png OUT.png [--scale N] [--tum T.tum [--label NAME] ...] [--crop-margin M [--crop-to tracks]]
//                  [--pose X,Y,YAW [--scan LOG.lcm [--at SECONDS] [--scan-channel CH] [--mount X,Y,YAW] [--upside-down]]]]
// A ROS map_server occupancy map (YAML + PGM/PNG) vectorised into a plan (fploc/floorplan/occupancy.h):
// prints the grid, the vectorisation's error (boundary cell centres to their segments) and, with --compare,
// the two-way distance between the vectorised plan and another plan (e.g. the one `fploc map export-pgm` was
// run on: the round trip). --pose with --scan: one laser scan of a log drawn at a candidate start pose (and the share
// of its returns near an occupied cell printed), to check a guess of the start pose by eye.
#include <CLI/CLI.hpp>


#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include <fploc/laser_scan_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include "fploc/runtime/log_reader.h"

#include "fploc/core/text_out.h"
#include "fploc/floorplan/distance_field.h"
#include "fploc/laser2d/grid_localizer.h"
#include "fploc/floorplan/io.h"
#include "fploc/floorplan/occupancy.h"
#include "fploc/floorplan/png.h"
#include "fploc/runtime/cli_messages.h"

namespace {
// Largest distance from points sampled every `step` along a's elements to plan b (brute force).
double max_distance(const fploc::FloorPlan& a, const fploc::FloorPlan& b, double step, double* mean) {
  double m = 0, s = 0;
  size_t n = 0;
  for (const auto& e : a.elements) {
    if (e.kind != fploc::ElementKind::kSegment) continue;
    const int k = std::max(1, int(std::ceil((e.b - e.a).norm() / step)));
    for (int q = 0; q <= k; ++q) {
      double d = 0;
      fploc::nearest_element_brute_force(b, e.a + (e.b - e.a) * (double(q) / k), &d);
      m = std::max(m, d);
      s += d;
      ++n;
    }
  }
  if (mean) *mean = n ? s / double(n) : 0.0;
  return m;
}
// TUM file -> (x, y) list (lines "t x y z qx qy qz qw", '#' comments).
std::vector<Eigen::Vector2d> read_tum_xy(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot open");
  std::vector<Eigen::Vector2d> out;
  std::string line;
  while (std::getline(f, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    double t, x, y;
    if (s >> t >> x >> y) out.emplace_back(x, y);
  }
  return out;
}

// A scale bar's length: 1, 2 or 5 times a power of ten metres, at most `max_m`.
double scale_bar_m(double max_m) {
  const double p = std::pow(10.0, std::floor(std::log10(max_m)));
  for (double k : {5.0, 2.0, 1.0})
    if (k * p <= max_m) return k * p;
  return p;
}

// PNG: the grid (occupied black, free white, unknown grey), the vectorised segments in red and any TUM
// trajectories on top (colours in order: green, blue, orange, magenta), `scale` pixels per cell. crop_margin_m
// >= 0: only the box around the occupied cells and the trajectories (crop_to_tracks: the trajectories alone), that
// much wider on each side (a log's map is mostly the free space its longest beams swept). A scale bar in metres
// (bottom left) and, with `labels` (one per trajectory), a legend of the trajectories' colours (top left). Plan
// coordinates: a light grid in metres (1, 2 or 5 x 10^k) under the map's lines, x = 0 and y = 0 darker, the origin
// ringed, labelled in margins left of (y) and below (x) the map.
void write_png(const std::string& out, const fploc::OccupancyGrid& g, const fploc::FloorPlan& plan,
               const std::vector<std::vector<Eigen::Vector2d>>& tracks, const std::vector<std::string>& labels, int scale,
               double crop_margin_m, bool crop_to_tracks, const fploc::Pose2* pose = nullptr,
               const std::vector<Eigen::Vector2d>& scan = {}) {
  const int W = g.width * scale, H = g.height * scale;
  fploc::RgbImage full(W, H);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const int v = g.at(x / scale, g.height - 1 - y / scale);
      const uint8_t c = v < 0 ? 200 : v > 100 * g.occupied_thresh ? 90 : uint8_t(255 - 2 * v);
      const uint8_t rgb[3] = {c, c, c};
      full.set(x, y, rgb);
    }
  const double c = std::cos(g.origin_yaw), s = std::sin(g.origin_yaw);
  auto px = [&](const Eigen::Vector2d& p) {  // world -> pixel (float)
    const Eigen::Vector2d d = p - Eigen::Vector2d(g.origin_x, g.origin_y);
    const double lx = c * d.x() + s * d.y(), ly = -s * d.x() + c * d.y();
    return Eigen::Vector2d(lx / g.resolution * scale, H - ly / g.resolution * scale);
  };
  auto line = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const uint8_t* col, int thick) {
    const Eigen::Vector2d pa = px(a), pb = px(b);
    const int n = std::max(1, int(std::ceil((pb - pa).norm())));
    for (int k = 0; k <= n; ++k) {
      const Eigen::Vector2d q = pa + (pb - pa) * (double(k) / n);
      full.fill_rect(int(q.x()) - thick, int(q.y()) - thick, int(q.x()) + thick + 1, int(q.y()) + thick + 1, col);
    }
  };
  static const uint8_t red[3] = {220, 0, 0}, black[3] = {0, 0, 0}, white[3] = {255, 255, 255};
  static const uint8_t cols[4][3] = {{0, 170, 0}, {0, 60, 255}, {255, 140, 0}, {200, 0, 200}};
  // The box in pixels: occupied cells (unless crop_to_tracks) and trajectory points, widened by the margin, clamped
  // to the image; the whole grid without a margin or with nothing to frame.
  int cx0 = 0, cy0 = 0, cx1 = W, cy1 = H;
  if (crop_margin_m >= 0) {
    double x0 = W, y0 = H, x1 = -1, y1 = -1;
    auto grow = [&](double x, double y) {
      x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
    };
    if (!crop_to_tracks || (tracks.empty() && !pose))
      for (int j = 0; j < g.height; ++j)
        for (int i = 0; i < g.width; ++i)
          if (g.at(i, j) > 100 * g.occupied_thresh) grow(double(i) * scale, double(g.height - 1 - j) * scale);
    // Trajectory points off the grid frame nothing (they are not in the picture).
    size_t on_grid = 0, points = 0;
    std::vector<std::vector<Eigen::Vector2d>> framed = tracks;  // the pose and its scan are framed as a trajectory
    if (pose) framed.push_back(scan), framed.back().emplace_back(pose->x, pose->y);
    for (const auto& t : framed)
      for (const auto& p : t) {
        ++points;
        const double x = px(p).x(), y = px(p).y();
        if (x >= 0 && y >= 0 && x < W && y < H) grow(x, y), ++on_grid;
      }
    if (crop_to_tracks && points > 0 && on_grid == 0)
      throw std::runtime_error("--crop-to tracks: none of the " + std::to_string(points) +
                               " trajectory points lies on the map (another frame, or another map?)");
    if (x1 >= 0) {
      const double m = crop_margin_m / g.resolution * scale;
      cx0 = std::max(0, int(x0 - m)), cy0 = std::max(0, int(y0 - m));
      cx1 = std::min(W, int(x1 + m) + scale), cy1 = std::min(H, int(y1 + m) + scale);
    }
  }
  // Plan coordinates (fploc/floorplan/png.h): a light grid in metres under the segments and trajectories, labelled
  // in margins left of and below the map.
  const int fs = std::clamp(std::min(cx1 - cx0, cy1 - cy0) / 30, 12, 28), pad = fs / 2;
  const double k = scale / g.resolution;
  fploc::PlanArea area;  // the full picture
  area.x1 = W, area.y1 = H;
  area.ux = k * c, area.vx = k * s, area.uy = k * s, area.vy = -k * c;
  area.ox = -k * (c * g.origin_x + s * g.origin_y), area.oy = H + k * (-s * g.origin_x + c * g.origin_y);
  double bx0 = 1e300, by0 = 1e300, bx1 = -1e300, by1 = -1e300;  // the crop in plan metres
  for (int cc : {cx0, cx1})
    for (int rr : {cy0, cy1}) {
      double x, y;
      area.to_m(cc, rr, &x, &y);
      bx0 = std::min(bx0, x), by0 = std::min(by0, y), bx1 = std::max(bx1, x), by1 = std::max(by1, y);
    }
  const fploc::PlanGrid grid = fploc::plan_grid(bx0, by0, bx1, by1, k, std::max(11, fs * 4 / 5));
  fploc::draw_plan_grid_lines(full, area, grid);
  for (const auto& e : plan.elements) line(e.a, e.b, red, 0);
  for (size_t t = 0; t < tracks.size(); ++t)
    for (size_t q = 1; q < tracks[t].size(); ++q) line(tracks[t][q - 1], tracks[t][q], cols[t % 4], 1);
  if (pose) {
    // The scan's returns (magenta dots) and the pose (a blue disc with a 0.3 m heading line) on top.
    static const uint8_t mag[3] = {230, 0, 200}, blue[3] = {0, 60, 255};
    const int r = std::max(1, scale / 2 + 1);
    for (const auto& p : scan) {
      const Eigen::Vector2d q = px(p);
      full.fill_rect(int(q.x()) - r, int(q.y()) - r, int(q.x()) + r + 1, int(q.y()) + r + 1, mag);
    }
    const Eigen::Vector2d at(pose->x, pose->y), q = px(at);
    const int d = std::max(3, int(std::lround(0.03 / g.resolution * scale)));
    full.fill_rect(int(q.x()) - d, int(q.y()) - d, int(q.x()) + d + 1, int(q.y()) + d + 1, blue);
    line(at, at + 0.4 * Eigen::Vector2d(std::cos(pose->yaw), std::sin(pose->yaw)), blue, std::max(1, d / 3));
  }
  const int L = grid.left_px, B = grid.bottom_px;
  fploc::RgbImage pic(cx1 - cx0 + L, cy1 - cy0 + B);
  for (int y = 0; y < cy1 - cy0; ++y)
    std::copy_n(full.px.begin() + (size_t(cy0 + y) * W + cx0) * 3, size_t(cx1 - cx0) * 3,
                pic.px.begin() + (size_t(y) * pic.w + L) * 3);
  fploc::PlanArea shown = area;  // the crop, moved right of the y labels' margin
  shown.x0 = L, shown.y0 = 0, shown.x1 = L + cx1 - cx0, shown.y1 = cy1 - cy0;
  shown.ox += L - cx0, shown.oy -= cy0;
  fploc::draw_plan_grid_labels(pic, shown, grid);
  // The map part of the picture (scale bar and legend are placed in it).
  struct Sub {
    fploc::RgbImage& im;
    int x0, w, h;
  } img{pic, L, cx1 - cx0, cy1 - cy0};
  // Scale bar (bottom left, on a white ground): 1, 2 or 5 x 10^k m, at most a third of the width.
  const double m_per_px = g.resolution / scale, bar_m = scale_bar_m(img.w / 3.0 * m_per_px);
  const int bar_px = int(std::lround(bar_m / m_per_px));
  char bar_text[32];
  std::snprintf(bar_text, sizeof bar_text, "%g m", bar_m);
  const int bx = img.x0 + pad, by = img.h - pad;
  pic.fill_rect(bx - pad / 2, by - 2 * fs - pad / 2, bx + std::max(bar_px, fploc::text_width(bar_text, fs)) + pad / 2,
                by + pad / 2, white, 0.85);
  pic.fill_rect(bx, by - fs / 4, bx + bar_px, by, black);
  for (int q : {0, bar_px - 2}) pic.fill_rect(bx + q, by - fs / 2, bx + q + 2, by, black);  // end ticks
  fploc::draw_text(pic, bx, by - fs / 2 - 3, bar_text, fs, black);
  // Legend (top left): a swatch and the name of each trajectory.
  if (!labels.empty()) {
    const size_t n = std::min(labels.size(), tracks.size());
    int tw = 0;
    for (size_t t = 0; t < n; ++t) tw = std::max(tw, fploc::text_width(labels[t], fs));
    const int lh = fs * 3 / 2, sw = 2 * fs, x0 = img.x0;
    pic.fill_rect(x0 + pad / 2, pad / 2, x0 + pad + sw + pad + tw + pad, pad + int(n) * lh + pad / 2, white, 0.85);
    for (size_t t = 0; t < n; ++t) {
      const int y = pad + int(t) * lh + lh / 2;
      pic.fill_rect(x0 + pad, y - 2, x0 + pad + sw, y + 2, cols[t % 4]);
      fploc::draw_text(pic, x0 + pad + sw + pad, y + fs * 2 / 5, labels[t], fs, black);
    }
  }
  pic.write_png(out);
  std::cerr << "fploc occupancy: " << out << ": " << pic.w << " x " << pic.h << " px, the map " << img.w << " x "
            << img.h << " px at " << L << ", 0 showing x " << bx0 + 0.0 << " .. " << bx1 + 0.0 << ", y " << by0 + 0.0 << " .. " << by1 + 0.0
            << " m; grid every " << grid.step_m << " m, labelled left (" << L << " px) and below (" << B << " px)\n";
}
// The grid grown with unknown cells (grey) to hold `pts` with `margin_m` around them: a scan drawn at a candidate
// pose reaches past a map of one corner (the picture shows where its returns fall, not only those on the map).
fploc::OccupancyGrid grown_to(const fploc::OccupancyGrid& g, const std::vector<Eigen::Vector2d>& pts, double margin_m) {
  const double c = std::cos(g.origin_yaw), s = std::sin(g.origin_yaw);
  int i0 = 0, j0 = 0, i1 = g.width, j1 = g.height;  // cell box [i0, i1) x [j0, j1)
  const int m = int(std::ceil(margin_m / g.resolution));
  for (const auto& p : pts) {
    const double dx = p.x() - g.origin_x, dy = p.y() - g.origin_y;
    const double ci = (c * dx + s * dy) / g.resolution, cj = (-s * dx + c * dy) / g.resolution;
    if (!std::isfinite(ci) || !std::isfinite(cj)) continue;
    i0 = std::min(i0, int(std::floor(ci)) - m), j0 = std::min(j0, int(std::floor(cj)) - m);
    i1 = std::max(i1, int(std::floor(ci)) + m + 1), j1 = std::max(j1, int(std::floor(cj)) + m + 1);
  }
  // At most 8000 cells a side (a return 80 m off at 1 cm cells): beyond that the picture is clipped.
  i0 = std::max(i0, -4000), j0 = std::max(j0, -4000), i1 = std::min(i1, g.width + 4000), j1 = std::min(j1, g.height + 4000);
  if (i0 == 0 && j0 == 0 && i1 == g.width && j1 == g.height) return g;
  fploc::OccupancyGrid out = g;
  out.width = i1 - i0, out.height = j1 - j0;
  out.data.assign(size_t(out.width) * size_t(out.height), int8_t(-1));
  for (int j = 0; j < g.height; ++j)
    for (int i = 0; i < g.width; ++i) out.data[size_t(j - j0) * out.width + size_t(i - i0)] = g.at(i, j);
  out.origin_x = g.origin_x + g.resolution * (c * i0 - s * j0);
  out.origin_y = g.origin_y + g.resolution * (s * i0 + c * j0);
  return out;
}

// The first laser_scan_t on `channel` at or after `at_s` seconds from the log's first one, its returns placed at
// `pose` (laser at `mount` on the robot) in the map frame; j["scan"] says which scan it was and how many of its returns
// lie within 0.1 m of an occupied cell (a right pose puts most of them on the walls).
std::vector<Eigen::Vector2d> scan_at_pose(const std::string& log_path, const std::string& channel, double at_s,
                                          const fploc::Pose2& pose, const fploc::Pose2& mount, bool upside_down,
                                          const fploc::OccupancyGrid& g, nlohmann::json* j) {
  fploc::rt::LogReader log(log_path);  // guards against a cut or damaged event (liblcm would read past the file)
  if (!log.good()) throw std::runtime_error("--scan " + log_path + ": cannot read the LCM log");
  int64_t first = -1, count = 0;
  double last_s = 0;
  std::map<std::string, int64_t> channels;
  while (const lcm::LogEvent* ev = log.next()) {
    ++channels[ev->channel];
    if (ev->channel != channel) continue;
    fploc::laser_scan_t m;
    if (m.decode(ev->data, 0, ev->datalen) < 0) throw std::runtime_error("--scan " + log_path + ": a " + channel +
                                                                         " event is not a laser_scan_t");
    if (first < 0) first = m.utime;
    ++count;
    last_s = double(m.utime - first) * 1e-6;
    if (last_s < at_s) continue;
    const auto local = fploc::laser2d::scan_points(m.ranges, m.angle_min, m.angle_increment, std::max(0.0f, m.range_min),
                                                   m.range_max > 0 ? double(m.range_max) : 1e9, mount, upside_down);
    const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
    std::vector<Eigen::Vector2d> out;
    const fploc::DistanceField field(g, 1.0);
    int near = 0;
    for (const auto& p : local) {
      out.emplace_back(pose.x + c * p.x() - s * p.y(), pose.y + s * p.x() + c * p.y());
      if (field.nearest(out.back()) <= 0.1) ++near;
    }
    const int pct = out.empty() ? 0 : int(std::lround(100.0 * near / double(out.size())));
    char text[400];
    std::snprintf(text, sizeof text, "%s: scan %lld of %s at %.3f s (utime %lld), %zu returns drawn at %.3f, %.3f, %.4f rad: "
                  "%d of them (%d %%) within 0.1 m of an occupied cell", log_path.c_str(), (long long)(count - 1),
                  channel.c_str(), last_s, (long long)m.utime, out.size(), pose.x, pose.y, pose.yaw, near, pct);
    (*j)["scan"] = {{"log", log_path}, {"channel", channel}, {"index", count - 1}, {"t_s", last_s}, {"utime", m.utime},
                    {"returns", out.size()}, {"near_walls", near}, {"near_walls_share", out.empty() ? 0.0 : double(near) / double(out.size())},
                    {"pose", {pose.x, pose.y, pose.yaw}}, {"text", text}};
    return out;
  }
  if (count == 0) {
    if (!log.problem().empty()) throw std::runtime_error("--scan " + log.problem());
    std::string have;
    for (const auto& [c, k] : channels) have += (have.empty() ? "" : ", ") + c + " (" + std::to_string(k) + ")";
    throw std::runtime_error("--scan " + log_path + ": no " + channel + " event (the log holds " +
                             (have.empty() ? std::string("no event") : have) + "; --scan-channel CH)");
  }
  char msg[200];
  std::snprintf(msg, sizeof msg, ": --at %g s is after its last %s scan (at %.3f s)", at_s, channel.c_str(), last_s);
  throw std::runtime_error("--scan " + log_path + msg);
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"occupancy map (map_server YAML + PGM/PNG) -> vectorised plan"};
  fploc::rt::install_cli_messages(app, "fploc occupancy");
  std::string map, out, compare;
  double tol = 0.5;
  bool json = false;
  std::string png_out;
  int scale = 1;
  double crop_margin = -1;
  std::vector<std::string> tums, labels;
  std::string crop_to = "map";
  app.add_option("map", map, "map_server YAML")->required();
  app.add_option("--tolerance", tol, "Douglas-Peucker tolerance [cells] (0.5)");
  app.add_option("--out", out, "write the plan (.json or .csv)");
  app.add_option("--compare", compare, "another plan: two-way distances to the vectorised plan");
  app.add_flag("--json", json, "JSON on stdout");
  app.add_option("--png", png_out, "picture: grid, segments (red), --tum trajectories (green, blue, orange, magenta), a scale "
                 "bar and plan coordinates (a grid in metres labelled along the left and bottom edges)");
  app.add_option("--scale", scale, "PNG pixels per cell (1)")->check(CLI::Range(1, 16));
  app.add_option("--tum", tums, "trajectory (TUM) to draw on the PNG; repeatable");
  app.add_option("--label", labels, "PNG legend: the name of each --tum trajectory, in their order; repeatable (default: no legend)");
  app.add_option("--crop-margin", crop_margin,
                 "PNG: only the occupied cells and trajectories, this much [m] around them (default: the whole grid)");
  app.add_option("--crop-to", crop_to, "PNG with --crop-margin: frame the occupied cells and trajectories (map) or the "
                 "trajectories alone (tracks) (map)")->check(CLI::IsMember({"map", "tracks"}));
  std::string pose_s, scan_log, scan_channel = "LASER_SCAN", mount_s;
  double at_s = 0;
  bool upside_down = false;
  app.add_option("--pose", pose_s, "PNG: a candidate pose X,Y,YAW (m, m, rad; the graphs' initial_pose) drawn as a blue disc "
                 "with a heading line; with --scan, that scan's returns drawn from it (magenta)");
  app.add_option("--scan", scan_log, "PNG with --pose: the LCM log (e.g. fploc import's) to take one laser scan from");
  app.add_option("--at", at_s, "with --scan: the first scan at or after this many seconds from the log's first scan (0)");
  app.add_option("--scan-channel", scan_channel, "with --scan: the laser_scan_t channel (LASER_SCAN)");
  app.add_option("--mount", mount_s, "with --scan: the laser's mount X,Y,YAW on the robot (m, m, rad; as grid2d.mount_x_m, "
                 "mount_y_m and mount_yaw_deg in radians; fploc import prints it) (0,0,0)");
  app.add_flag("--upside-down", upside_down, "with --scan: the laser is mounted upside down (as grid2d.upside_down)");
  CLI11_PARSE(app, argc, argv);
  auto triple = [](const std::string& opt, const std::string& v, fploc::Pose2* out) {
    double a[3];
    char tail = 0;
    if (std::sscanf(v.c_str(), "%lf,%lf,%lf%c", &a[0], &a[1], &a[2], &tail) != 3 || !std::isfinite(a[0]) ||
        !std::isfinite(a[1]) || !std::isfinite(a[2])) {
      std::cerr << "fploc occupancy: " << opt << " '" << v << "': expected X,Y,YAW (three finite numbers, no spaces)\n";
      return false;
    }
    *out = {a[0], a[1], a[2]};
    return true;
  };
  fploc::Pose2 pose, mount;
  if (!pose_s.empty() && !triple("--pose", pose_s, &pose)) return 1;
  if (!mount_s.empty() && !triple("--mount", mount_s, &mount)) return 1;
  if (pose_s.empty() && (!scan_log.empty() || !mount_s.empty() || upside_down)) {
    std::cerr << "fploc occupancy: --scan, --mount and --upside-down draw a scan at a pose: give --pose X,Y,YAW\n";
    return 1;
  }
  if (!(std::isfinite(at_s) && at_s >= 0)) {
    std::cerr << "fploc occupancy: --at " << at_s << ": expected seconds >= 0\n";
    return 1;
  }
  // CLI11 takes "nan" and "inf" as numbers: a NaN tolerance vectorised the map into a few long wrong segments.
  if (!(std::isfinite(tol) && tol >= 0)) {
    std::cerr << "fploc occupancy: --tolerance " << tol << ": expected a number of cells >= 0\n";
    return 1;
  }
  if (!std::isfinite(crop_margin)) {
    std::cerr << "fploc occupancy: --crop-margin " << crop_margin << ": expected a finite number of metres\n";
    return 1;
  }
  if (crop_to != "map" && crop_margin < 0) {
    std::cerr << "fploc occupancy: --crop-to needs --crop-margin M\n";
    return 1;
  }
  if (png_out.empty() && (!labels.empty() || !tums.empty() || crop_margin >= 0 || !pose_s.empty())) {
    std::cerr << "fploc occupancy: --tum, --label, --crop-margin and --pose draw on the picture: give --png OUT.png\n";
    return 1;
  }
  if (labels.size() > tums.size()) {
    std::cerr << "fploc occupancy: " << labels.size() << " --label for " << tums.size() << " --tum\n";
    return 1;
  }
  try {
    const fploc::OccupancyGrid g = fploc::read_occupancy_map(map);
    fploc::VectoriseOptions o;
    o.tolerance_cells = tol;
    fploc::VectoriseStats st;
    fploc::FloorPlan plan = fploc::vectorise_occupancy(g, o, &st);
    fploc::require_occupied_cells(g, plan, map);  // it said "0 boundary cells -> 0 segments", exit 0
    plan.source = map;
    nlohmann::json j = {{"map", map}, {"width", g.width}, {"height", g.height}, {"resolution_m", g.resolution},
                        {"origin", {g.origin_x, g.origin_y, g.origin_yaw}}, {"occupied_cells", st.occupied_cells},
                        {"boundary_cells", st.boundary_cells}, {"chains", st.chains}, {"segments", st.segments},
                        {"tolerance_cells", tol}, {"max_error_m", st.max_error_m}, {"mean_error_m", st.mean_error_m}};
    if (!compare.empty()) {
      const fploc::FloorPlan ref = fploc::load_floor_plan(compare);
      double m1 = 0, m2 = 0;
      j["compare"] = compare;
      j["plan_to_map_max_m"] = max_distance(ref, plan, g.resolution / 2, &m1);
      j["plan_to_map_mean_m"] = m1;
      j["map_to_plan_max_m"] = max_distance(plan, ref, g.resolution / 2, &m2);
      j["map_to_plan_mean_m"] = m2;
    }
    if (!out.empty()) fploc::save_floor_plan(plan, out);
    if (!png_out.empty()) {
      std::vector<std::vector<Eigen::Vector2d>> tracks;
      for (const auto& t : tums) tracks.push_back(read_tum_xy(t));
      std::vector<Eigen::Vector2d> scan;
      if (!scan_log.empty()) {
        scan = scan_at_pose(scan_log, scan_channel, at_s, pose, mount, upside_down, g, &j);
        std::cerr << "fploc occupancy: " << j["scan"]["text"].get<std::string>() << "\n";
      }
      std::vector<Eigen::Vector2d> framed = scan;
      if (!pose_s.empty()) framed.emplace_back(pose.x, pose.y);
      write_png(png_out, framed.empty() ? g : grown_to(g, framed, 0.5), plan, tracks, labels, scale, crop_margin,
                crop_to == "tracks", pose_s.empty() ? nullptr : &pose, scan);
      if (!pose_s.empty()) {
        char set[256];
        std::snprintf(set, sizeof set, "--set grid2d.initial_pose.x=%g --set grid2d.initial_pose.y=%g --set grid2d.initial_pose.yaw=%g",
                      pose.x, pose.y, pose.yaw);
        std::cerr << "fploc occupancy: the pose as a start pose of graphs/lidar2d.pbtxt: " << set
                  << " (and matcher.initial_pose.*, amcl.initial_pose.* alike)\n";
      }
    }
    std::cerr << "fploc occupancy: " << g.width << " x " << g.height << " cells at " << g.resolution << " m, "
              << st.boundary_cells << " boundary cells -> " << st.segments << " segments (max error "
              << st.max_error_m * 1000 << " mm, mean " << st.mean_error_m * 1000 << " mm)" << (out.empty() ? "" : " -> " + out)
              << "\n";
    if (json) std::cout << fploc::json_text(j, 1) << "\n";
  } catch (const std::exception& e) {
    std::cerr << "fploc occupancy: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
