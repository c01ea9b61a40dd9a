// fploc occupancy MAP.yaml [--tolerance CELLS] [--out PLAN.json|.csv] [--compare PLAN] [--json]
//                 [--png OUT.png [--scale N] [--tum T.tum [--label NAME] ...] [--crop-margin M [--crop-to tracks]]]
// A ROS map_server occupancy map (YAML + PGM/PNG) vectorised into a plan (fploc/floorplan/occupancy.h):
// prints the grid, the vectorisation's error (boundary cell centres to their segments) and, with --compare,
// the two-way distance between the vectorised plan and another plan (e.g. the one `fploc map export-pgm` was
// run on: the round trip).
#include <CLI/CLI.hpp>


#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "fploc/core/text_out.h"
#include "fploc/floorplan/io.h"
#include "fploc/floorplan/occupancy.h"
#include "fploc/floorplan/png.h"

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
               double crop_margin_m, bool crop_to_tracks) {
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
    if (!crop_to_tracks || tracks.empty())
      for (int j = 0; j < g.height; ++j)
        for (int i = 0; i < g.width; ++i)
          if (g.at(i, j) > 100 * g.occupied_thresh) grow(double(i) * scale, double(g.height - 1 - j) * scale);
    // Trajectory points off the grid frame nothing (they are not in the picture).
    size_t on_grid = 0, points = 0;
    for (const auto& t : tracks)
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
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"occupancy map (map_server YAML + PGM/PNG) -> vectorised plan"};
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
  CLI11_PARSE(app, argc, argv);
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
  if (png_out.empty() && (!labels.empty() || !tums.empty() || crop_margin >= 0)) {
    std::cerr << "fploc occupancy: --tum, --label and --crop-margin draw on the picture: give --png OUT.png\n";
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
      write_png(png_out, g, plan, tracks, labels, scale, crop_margin, crop_to == "tracks");
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
