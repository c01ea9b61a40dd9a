// fploc map render (SVG / PNG like the paper's Fig. 2) and export-pgm (ROS map_server PGM + YAML).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>

#include "fploc/annf/annf.h"
#include "fploc/core/text_out.h"
#include "fploc/floorplan/png.h"
#include "map_tool.h"

namespace fploc {
namespace {

std::string lower_ext(const std::string& p) {
  std::string e = std::filesystem::path(p).extension().string();
  for (auto& c : e) c = char(std::tolower((unsigned char)c));
  return e;
}

// A stable pastel colour per element id.
void colour(uint32_t id, uint8_t rgb[3]) {
  uint32_t h = id * 2654435761u;
  const double hue = (h % 360) / 60.0, s = 0.45, v = 0.95;
  const double c = v * s, x = c * (1 - std::abs(std::fmod(hue, 2.0) - 1)), m = v - c;
  double r = 0, g = 0, b = 0;
  switch (int(hue)) {
    case 0: r = c, g = x; break;
    case 1: r = x, g = c; break;
    case 2: g = c, b = x; break;
    case 3: g = x, b = c; break;
    case 4: r = x, b = c; break;
    default: r = c, b = x; break;
  }
  rgb[0] = uint8_t((r + m) * 255);
  rgb[1] = uint8_t((g + m) * 255);
  rgb[2] = uint8_t((b + m) * 255);
}

// A plan element's line colour: the plan-change layers of `fploc map diff` (FPLOC-MISSING red, FPLOC-MOVED orange,
// FPLOC-NEW green, FPLOC-LOW cyan: low structure, not a wall), every other layer black.
struct LayerStyle {
  const char* prefix;
  const char* svg;
  uint8_t rgb[3];
  const char* label;
};
const LayerStyle kDiffLayers[] = {{"FPLOC-MISSING", "#d62728", {214, 39, 40}, "in the plan, not seen"},
                                  {"FPLOC-MOVED", "#ff7f0e", {255, 127, 14}, "seen offset"},
                                  {"FPLOC-NEW", "#2ca02c", {44, 160, 44}, "seen, not in the plan"},
                                  {"FPLOC-LOW", "#17becf", {23, 190, 207}, "seen only low (furniture), not a wall"}};
const LayerStyle* style_of(const FloorPlan& plan, const Element& e) {
  if (e.layer < 0 || e.layer >= int(plan.layers.size())) return nullptr;
  for (const auto& st : kDiffLayers)
    if (plan.layers[size_t(e.layer)].rfind(st.prefix, 0) == 0) return &st;
  return nullptr;
}

// A building floor's stairs, ramps and lifts: a translucent area in the kind's colour with its outline (a lift also
// with the crossed box of architectural drawings), and a legend line each.
struct ConnectionStyle {
  const char* svg;
  uint8_t rgb[3];
};
const ConnectionStyle& style_of(ConnectionKind k) {
  static const ConnectionStyle kStairs{"#9467bd", {148, 103, 189}}, kRamp{"#8c564b", {140, 86, 75}},
      kLift{"#17becf", {23, 190, 207}};
  return k == ConnectionKind::kRamp ? kRamp : k == ConnectionKind::kLift ? kLift : kStairs;
}
std::string legend_text(const FloorConnection& c, const std::string& floor) {
  std::string kind = to_string(c.kind);
  for (auto& ch : kind) ch = char(std::toupper((unsigned char)ch));
  return kind + " '" + c.name + "' to " + (c.from_floor == floor ? c.to_floor : c.from_floor);
}
bool point_in_polygon(const std::vector<Eigen::Vector2d>& poly, const Eigen::Vector2d& p) {
  bool in = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++)
    if ((poly[i].y() > p.y()) != (poly[j].y() > p.y()) &&
        p.x() < (poly[j].x() - poly[i].x()) * (p.y() - poly[i].y()) / (poly[j].y() - poly[i].y()) + poly[i].x())
      in = !in;
  return in;
}
// The drawing's extent: the plan and the connections' areas.
Box2 drawn_bounds(const FloorPlan& plan, const std::vector<FloorConnection>& conns) {
  Box2 b = plan.bounds();
  for (const auto& c : conns)
    for (const auto& p : c.polygon) b.extend(p);
  return b;
}

// A scale bar's length: 1, 2 or 5 times a power of ten, about a fifth of the width.
double scale_bar_m(double width_m) {
  const double target = width_m / 5, p = std::pow(10.0, std::floor(std::log10(target)));
  for (double k : {5.0, 2.0, 1.0})
    if (k * p <= target) return k * p;
  return p;
}

void write_svg(const FloorPlan& plan, const annf::Annf* f, const std::string& out, int width,
               const std::vector<FloorConnection>& conns, const std::string& floor) {
  const Box2 b = drawn_bounds(plan, conns);
  const double pad = 0.02 * b.size().maxCoeff() + 0.1;
  const double W = b.size().x() + 2 * pad, H0 = b.size().y() + 2 * pad;
  std::ofstream s(out);
  if (!s) throw std::runtime_error(out + ": cannot write");
  const double sw = b.size().maxCoeff() / 1500.0;
  // The legend (plan-change layers, connections) goes in a band above the plan: drawn over it, it hid the plan's
  // top-left walls.
  int diff_count[std::size(kDiffLayers)] = {};
  for (const auto& e : plan.elements)
    if (const LayerStyle* st = style_of(plan, e)) ++diff_count[st - kDiffLayers];
  int legend_lines = int(conns.size());
  for (const int n : diff_count) legend_lines += n > 0;
  const double fs = std::min(W, H0) / 60;
  const double band = legend_lines > 0 ? 1.4 * fs * legend_lines + fs : 0.0;
  // Plan coordinates: a light grid in metres under the plan, labelled in margins left of (y) and below (x) it
  // (fploc/floorplan/png.h's rule for the step, at the picture's scale).
  const double ppm = width / W;  // about: the margins widen the view a little
  const PlanGrid grid = plan_grid(b.min.x() - pad, b.min.y() - pad, b.max.x() + pad, b.max.y() + pad, ppm,
                                  std::max(1, int(std::lround(0.8 * fs * ppm))));
  const double gfs = 0.8 * fs, left = grid.left_px / ppm, below = grid.bottom_px / ppm;
  const double H = H0 + band + below, top = -(b.max.y() + pad) - band;  // the view's top edge (SVG y, downwards)
  const double VW = W + left, vx0 = b.min.x() - pad - left;
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << int(width * H / VW)
    << "\" viewBox=\"" << vx0 << " " << top << " " << VW << " " << H << "\">\n"
    << "<g transform=\"scale(1,-1)\">\n<g stroke=\"#00000030\" stroke-width=\"" << sw * 0.5 << "\">\n";
  if (f) f->for_each_leaf([&](const Box2& box, int, const uint32_t* ids, int n) {
    if (box.max.x() < b.min.x() - pad || box.min.x() > b.max.x() + pad || box.max.y() < b.min.y() - pad ||
        box.min.y() > b.max.y() + pad)
      return;
    uint8_t c[3] = {235, 235, 235};
    if (n > 0) colour(ids[0], c);
    char buf[64];
    std::snprintf(buf, sizeof buf, "#%02x%02x%02x", c[0], c[1], c[2]);
    s << "<rect x=\"" << box.min.x() << "\" y=\"" << box.min.y() << "\" width=\"" << box.size().x() << "\" height=\""
      << box.size().y() << "\" fill=\"" << buf << "\"/>\n";
  });
  s << "</g>\n";
  // The grid (x = 0 and y = 0 darker, the origin ringed when in view).
  const double gx0 = b.min.x() - pad, gx1 = b.max.x() + pad, gy0 = b.min.y() - pad, gy1 = b.max.y() + pad;
  std::vector<double> gxs, gys;
  for (double k = std::ceil(gx0 / grid.step_m); k * grid.step_m <= gx1; k += 1) gxs.push_back(k * grid.step_m + 0.0);
  for (double k = std::ceil(gy0 / grid.step_m); k * grid.step_m <= gy1; k += 1) gys.push_back(k * grid.step_m + 0.0);
  const auto axis = [&](double v) { return std::abs(v) < 1e-9 * grid.step_m; };
  s << "<g class=\"grid\" stroke=\"#3c5a96\" stroke-width=\"" << sw << "\">\n";
  for (double x : gxs)
    s << "<line x1=\"" << x << "\" y1=\"" << gy0 << "\" x2=\"" << x << "\" y2=\"" << gy1 << "\" stroke-opacity=\""
      << (axis(x) ? 0.5 : 0.2) << "\"/>\n";
  for (double y : gys)
    s << "<line x1=\"" << gx0 << "\" y1=\"" << y << "\" x2=\"" << gx1 << "\" y2=\"" << y << "\" stroke-opacity=\""
      << (axis(y) ? 0.5 : 0.2) << "\"/>\n";
  if (gx0 <= 0 && 0 <= gx1 && gy0 <= 0 && 0 <= gy1)
    s << "<circle cx=\"0\" cy=\"0\" r=\"" << 5 / ppm << "\" fill=\"none\" stroke-opacity=\"0.9\" stroke-width=\"" << 2 / ppm
      << "\"/>\n";
  s << "</g>\n<g fill=\"none\" stroke=\"#000\" stroke-width=\"" << sw * 2 << "\">\n";
  for (const auto& e : plan.elements) {
    const LayerStyle* st = style_of(plan, e);
    if (st) {
      s << "<g stroke=\"" << st->svg << "\" stroke-width=\"" << sw * 4 << "\">";
    }
    if (e.kind == ElementKind::kSegment) {
      s << "<line x1=\"" << e.a.x() << "\" y1=\"" << e.a.y() << "\" x2=\"" << e.b.x() << "\" y2=\"" << e.b.y() << "\"/>\n";
    } else if (e.kind == ElementKind::kCircle) {
      s << "<circle cx=\"" << e.c.x() << "\" cy=\"" << e.c.y() << "\" r=\"" << e.r << "\"/>\n";
    } else {
      const Eigen::Vector2d p0 = e.c + e.r * Eigen::Vector2d(std::cos(e.a0), std::sin(e.a0));
      const Eigen::Vector2d p1 = e.c + e.r * Eigen::Vector2d(std::cos(e.a1), std::sin(e.a1));
      const int large = (e.a1 - e.a0) > M_PI ? 1 : 0;
      s << "<path d=\"M " << p0.x() << " " << p0.y() << " A " << e.r << " " << e.r << " 0 " << large << " 1 " << p1.x()
        << " " << p1.y() << "\"/>\n";
    }
    if (st) s << "</g>\n";
  }
  s << "</g>\n";
  // Stairs, ramps and lifts over the plan.
  for (const auto& c : conns) {
    const ConnectionStyle& st = style_of(c.kind);
    s << "<polygon points=\"";
    for (const auto& p : c.polygon) s << p.x() << "," << p.y() << " ";
    s << "\" fill=\"" << st.svg << "\" fill-opacity=\"0.3\" stroke=\"" << st.svg << "\" stroke-width=\"" << sw * 3
      << "\"><title>" << fploc::xml_text(legend_text(c, floor)) << "</title></polygon>\n";
    if (c.kind == ConnectionKind::kLift && c.polygon.size() == 4)
      for (int k = 0; k < 2; ++k)
        s << "<line x1=\"" << c.polygon[k].x() << "\" y1=\"" << c.polygon[k].y() << "\" x2=\"" << c.polygon[k + 2].x() << "\" y2=\""
          << c.polygon[k + 2].y() << "\" stroke=\"" << st.svg << "\" stroke-width=\"" << sw * 1.5 << "\"/>\n";
  }
  s << "</g>\n";
  // Scale bar (bottom left) and, for a plan-change drawing or a floor with stairs, ramps or lifts, the legend of its
  // layers and connections (in the band above the plan); upright text.
  const double bar = scale_bar_m(b.size().x());
  const double x0 = b.min.x() - pad + fs, ybar = -(b.min.y() - pad) - fs;
  s << "<g font-family=\"sans-serif\" font-size=\"" << fs << "\">\n<line x1=\"" << x0 << "\" y1=\"" << ybar << "\" x2=\""
    << x0 + bar << "\" y2=\"" << ybar << "\" stroke=\"#000\" stroke-width=\"" << fs / 4 << "\"/>\n<text x=\"" << x0
    << "\" y=\"" << ybar - fs / 2 << "\">" << bar << " m</text>\n";
  // Tick labels in the margins (upright): x below the plan, y left of it, "m" in the corner; the scale bar's corner
  // keeps no x label under it.
  const double tick = std::max(3.0, gfs * ppm / 3) / ppm, ybottom = -gy0;
  s << "<g class=\"grid-labels\" font-size=\"" << gfs << "\" fill=\"#282828\">\n";
  s << "<text x=\"" << gx0 - tick - 0.1 * gfs << "\" y=\"" << ybottom + tick + gfs << "\" text-anchor=\"end\">m</text>\n";
  double right = gx0 - tick;
  for (double x : gxs) {
    const std::string t = grid.label(x);
    const double half = 0.3 * gfs * double(t.size());
    if (x - half < right + 0.5 * gfs) continue;
    s << "<line x1=\"" << x << "\" y1=\"" << ybottom << "\" x2=\"" << x << "\" y2=\"" << ybottom + tick
      << "\" stroke=\"#282828\" stroke-width=\"" << sw << "\"/><text x=\"" << x << "\" y=\"" << ybottom + tick + gfs
      << "\" text-anchor=\"middle\">" << t << "</text>\n";
    right = x + half;
  }
  double topmost = ybottom + tick;
  for (double y : gys) {
    const double base = -y + 0.35 * gfs;
    if (base > topmost - 1.2 * gfs) continue;
    s << "<line x1=\"" << gx0 - tick << "\" y1=\"" << -y << "\" x2=\"" << gx0 << "\" y2=\"" << -y
      << "\" stroke=\"#282828\" stroke-width=\"" << sw << "\"/><text x=\"" << gx0 - tick - 0.1 * gfs << "\" y=\"" << base
      << "\" text-anchor=\"end\">" << grid.label(y) << "</text>\n";
    topmost = base - 0.7 * gfs;
  }
  s << "</g>\n";
  double yl = top + 1.5 * fs;
  if (legend_lines > 0)  // a white ground for the legend
    s << "<rect x=\"" << x0 - fs / 2 << "\" y=\"" << yl - 1.2 * fs << "\" width=\"" << 22 * fs << "\" height=\""
      << 1.4 * fs * legend_lines + 0.4 * fs << "\" fill=\"#ffffffd0\"/>\n";
  for (size_t k = 0; k < std::size(kDiffLayers); ++k)  // FPLOC-LOW too (it was left out)
    if (diff_count[k] > 0) {
      s << "<line x1=\"" << x0 << "\" y1=\"" << yl - fs / 3 << "\" x2=\"" << x0 + 1.5 * fs << "\" y2=\"" << yl - fs / 3
        << "\" stroke=\"" << kDiffLayers[k].svg << "\" stroke-width=\"" << fs / 3 << "\"/><text x=\"" << x0 + 2 * fs << "\" y=\"" << yl
        << "\">" << kDiffLayers[k].prefix << " (" << diff_count[k] << "): " << kDiffLayers[k].label << "</text>\n";
      yl += 1.4 * fs;
    }
  for (const auto& c : conns) {
    const ConnectionStyle& st = style_of(c.kind);
    s << "<rect x=\"" << x0 << "\" y=\"" << yl - 0.8 * fs << "\" width=\"" << 1.5 * fs << "\" height=\"" << 0.8 * fs << "\" fill=\""
      << st.svg << "\" fill-opacity=\"0.3\" stroke=\"" << st.svg << "\" stroke-width=\"" << fs / 8 << "\"/><text x=\"" << x0 + 2 * fs
      << "\" y=\"" << yl << "\">" << fploc::xml_text(legend_text(c, floor)) << "</text>\n";
    yl += 1.4 * fs;
  }
  s << "</g>\n</svg>\n";
  if (!s) throw std::runtime_error(out + ": write error");
}

void write_png(const FloorPlan& plan, const annf::Annf* f, const std::string& out, int width,
               const std::vector<FloorConnection>& conns, const std::string& floor) {
  const Box2 b = drawn_bounds(plan, conns);
  const double pad = 0.02 * b.size().maxCoeff() + 0.1;
  const double W = b.size().x() + 2 * pad, H = b.size().y() + 2 * pad;
  // Plan coordinates (fploc/floorplan/png.h): a light grid in metres under the plan, labelled in margins left of and
  // below it; the picture is `width` wide with them.
  const int fs = std::clamp(width / 60, 12, 24);
  const PlanGrid grid = plan_grid(b.min.x() - pad, b.min.y() - pad, b.max.x() + pad, b.max.y() + pad,
                                  std::max(16, width) / W, std::max(11, fs * 4 / 5));
  const int w = std::max(16, width - grid.left_px), h = std::max(16, int(std::ceil(w * H / W)));
  const double px = W / w;
  RgbImage plan_img(w, h);
  std::vector<uint8_t>& img = plan_img.px;
  PlanArea area;
  area.x1 = w, area.y1 = h;
  area.ux = 1 / px, area.vy = -1 / px, area.ox = -(b.min.x() - pad) / px, area.oy = (b.max.y() + pad) / px;
  if (f) {
    std::vector<int64_t> leaf_key(size_t(w) * h, -1);
    for (int j = 0; j < h; ++j)
      for (int i = 0; i < w; ++i) {
        const Eigen::Vector2d p(b.min.x() - pad + (i + 0.5) * px, b.max.y() + pad - (j + 0.5) * px);
        uint8_t* c = &img[(size_t(j) * w + i) * 3];
        int n;
        const uint32_t* ids = f->lookup(p, &n);
        if (ids && n > 0) {
          colour(ids[0], c);
          Box2 lb;
          if (f->leaf_box(p, &lb)) leaf_key[size_t(j) * w + i] = int64_t(std::llround(lb.min.x() * 1e4)) * 1000003 + std::llround(lb.min.y() * 1e4);
        } else {
          c[0] = c[1] = c[2] = 235;
        }
      }
    for (int j = 1; j < h; ++j)
      for (int i = 1; i < w; ++i) {
        const size_t k = size_t(j) * w + i;
        if (leaf_key[k] != leaf_key[k - 1] || leaf_key[k] != leaf_key[k - w])
          for (int q = 0; q < 3; ++q) img[k * 3 + q] = uint8_t(img[k * 3 + q] * 0.8);
      }
  }
  draw_plan_grid_lines(plan_img, area, grid);
  // The elements, sampled every quarter pixel along them (1.5 px wide; the plan-change layers 3 px, in colour).
  auto dot = [&](const Eigen::Vector2d& p, const uint8_t rgb[3], double r_px) {
    const double ci = (p.x() - (b.min.x() - pad)) / px - 0.5, cj = ((b.max.y() + pad) - p.y()) / px - 0.5;
    const int r = int(std::ceil(r_px));
    for (int j = int(std::floor(cj)) - r; j <= int(std::ceil(cj)) + r; ++j)
      for (int i = int(std::floor(ci)) - r; i <= int(std::ceil(ci)) + r; ++i)
        if (i >= 0 && j >= 0 && i < w && j < h && std::hypot(i - ci, j - cj) <= r_px)
          for (int q = 0; q < 3; ++q) img[(size_t(j) * w + i) * 3 + q] = rgb[q];
  };
  const uint8_t black[3] = {0, 0, 0};
  for (int pass = 0; pass < 2; ++pass)  // the plan-change layers over the others
    for (const auto& e : plan.elements) {
      const LayerStyle* st = style_of(plan, e);
      if ((st != nullptr) != (pass == 1)) continue;
      const uint8_t* rgb = st ? st->rgb : black;
      const double r_px = st ? 1.5 : 0.75;
      if (e.kind == ElementKind::kSegment) {
        const int n = std::max(1, int(std::ceil((e.b - e.a).norm() / (px / 4))));
        for (int k = 0; k <= n; ++k) dot(e.a + (e.b - e.a) * (double(k) / n), rgb, r_px);
      } else {
        const double a0 = e.kind == ElementKind::kCircle ? 0.0 : e.a0, a1 = e.kind == ElementKind::kCircle ? 2 * M_PI : e.a1;
        const int n = std::max(8, int(std::ceil(e.r * std::abs(a1 - a0) / (px / 4))));
        for (int k = 0; k <= n; ++k) {
          const double a = a0 + (a1 - a0) * double(k) / n;
          dot(e.c + e.r * Eigen::Vector2d(std::cos(a), std::sin(a)), rgb, r_px);
        }
      }
    }
  // Stairs, ramps and lifts: their area blended in the kind's colour, the outline 2 px (a lift's diagonals too).
  for (const auto& c : conns) {
    const ConnectionStyle& st = style_of(c.kind);
    for (int j = 0; j < h; ++j)
      for (int i = 0; i < w; ++i)
        if (point_in_polygon(c.polygon, Eigen::Vector2d(b.min.x() - pad + (i + 0.5) * px, b.max.y() + pad - (j + 0.5) * px)))
          for (int q = 0; q < 3; ++q) img[(size_t(j) * w + i) * 3 + q] = uint8_t(0.7 * img[(size_t(j) * w + i) * 3 + q] + 0.3 * st.rgb[q]);
    auto edge = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& e) {
      const int n = std::max(1, int(std::ceil((e - a).norm() / (px / 4))));
      for (int k = 0; k <= n; ++k) dot(a + (e - a) * (double(k) / n), st.rgb, 1.0);
    };
    for (size_t k = 0; k < c.polygon.size(); ++k) edge(c.polygon[k], c.polygon[(k + 1) % c.polygon.size()]);
    if (c.kind == ConnectionKind::kLift && c.polygon.size() == 4)
      for (int k = 0; k < 2; ++k) edge(c.polygon[size_t(k)], c.polygon[size_t(k) + 2]);
  }
  // Scale bar (bottom left), 1, 2 or 5 times a power of ten metres, its length written above it.
  const double bar = scale_bar_m(b.size().x());
  for (double x = 0; x <= bar; x += px / 4) dot(Eigen::Vector2d(b.min.x() - pad + 10 * px + x, b.min.y() - pad + 10 * px), black, 1.5);
  // Legend (in a band above the plan, as in the SVG: over the plan it hid the top-left walls): the plan-change
  // layers present and the floor's connections.
  std::vector<std::pair<const uint8_t*, std::string>> legend;
  int diff_count[std::size(kDiffLayers)] = {};
  for (const auto& e : plan.elements)
    if (const LayerStyle* st = style_of(plan, e)) ++diff_count[st - kDiffLayers];
  for (size_t k = 0; k < std::size(kDiffLayers); ++k)  // FPLOC-LOW too (it was left out)
    if (diff_count[k] > 0)
      legend.emplace_back(kDiffLayers[k].rgb, std::string(kDiffLayers[k].prefix) + " (" + std::to_string(diff_count[k]) +
                                                  "): " + kDiffLayers[k].label);
  for (const auto& c : conns) legend.emplace_back(style_of(c.kind).rgb, legend_text(c, floor));
  const int band = legend.empty() ? 0 : fs / 2 + int(legend.size()) * (fs * 3 / 2) + fs / 2;
  const int L = grid.left_px;
  RgbImage pic(L + w, band + h + grid.bottom_px);
  for (int j = 0; j < h; ++j)
    std::copy_n(img.begin() + std::ptrdiff_t(size_t(j) * w * 3), size_t(w) * 3,
                pic.px.begin() + std::ptrdiff_t((size_t(band + j) * pic.w + L) * 3));
  PlanArea shown = area;
  shown.x0 = L, shown.y0 = band, shown.x1 = L + w, shown.y1 = band + h;
  shown.ox += L, shown.oy += band;
  draw_plan_grid_labels(pic, shown, grid);
  char bar_text[32];
  std::snprintf(bar_text, sizeof bar_text, "%g m", bar);
  draw_text(pic, L + 10, band + h - 10 - fs / 2 - 2, bar_text, fs, black);
  if (!legend.empty()) {
    const int lh = fs * 3 / 2, sw = 2 * fs, x0 = fs / 2;
    int tw = 0;
    for (const auto& l : legend) tw = std::max(tw, text_width(l.second, fs));
    const uint8_t white[3] = {255, 255, 255};
    pic.fill_rect(x0 / 2, x0 / 2, x0 + sw + x0 + tw + x0, x0 + int(legend.size()) * lh + x0 / 2, white, 0.85);
    for (size_t k = 0; k < legend.size(); ++k) {
      const int y = x0 + int(k) * lh + lh / 2;
      pic.fill_rect(x0, y - fs / 3, x0 + sw, y + fs / 3, legend[k].first);
      draw_text(pic, x0 + sw + x0, y + fs * 2 / 5, legend[k].second, fs, black);
    }
  }
  pic.write_png(out);
  std::cerr << "fploc map render: " << pic.w << " x " << pic.h << " px, " << px << " m per pixel; scale bar (bottom left) " << bar
            << " m" << (band ? "; legend above the plan (" + std::to_string(band) + " px)" : std::string())
            << "; grid every " << grid.step_m << " m, labelled left (" << L << " px) and below (" << grid.bottom_px
            << " px)\n";
}

}  // namespace


int cmd_render(const FloorPlan& plan, const RenderArgs& given) {
  const std::string ext = lower_ext(given.out);
  if (ext != ".svg" && ext != ".png") throw std::runtime_error(given.out + ": output must be .svg or .png");
  RenderArgs a = given;
  if (a.fields.empty()) {  // a plan-change drawing: its coloured lines alone (on the fields, green NEW sat on green cells)
    const bool diff = std::any_of(plan.elements.begin(), plan.elements.end(),
                                  [&](const Element& e) { return style_of(plan, e) != nullptr; });
    a.fields = diff && a.map.empty() ? "none" : "nearest";
    if (diff && a.map.empty())
      std::cerr << "fploc map render: a plan-change drawing (FPLOC-* layers): lines only (--fields nearest adds the "
                   "look-up's leaf fields)\n";
  }
  std::optional<annf::Annf> f;
  if (!a.map.empty()) {
    f = annf::Annf::load(a.map);
  } else if (a.fields != "none") {
    std::cerr << "fploc map render: building the look-up's leaf fields (depth " << a.depth << ") over "
              << plan.elements.size() << " elements (--fields none draws the lines only)\n";
    annf::AnnfOptions o;
    o.max_depth = a.depth;
    f = annf::Annf::build(plan, o);
  }
  const FloorPlan& drawn = f ? f->plan() : plan;
  const annf::Annf* fp = f && a.fields != "none" ? &*f : nullptr;
  if (ext == ".svg")
    write_svg(drawn, fp, a.out, a.width, a.connections, a.floor);
  else
    write_png(drawn, fp, a.out, a.width, a.connections, a.floor);
  std::cerr << "fploc map render: ";
  if (fp) std::cerr << fp->stats().leaves << " leaf fields, ";
  std::cerr << drawn.elements.size() << " elements";
  for (const auto& c : a.connections) std::cerr << ", " << legend_text(c, a.floor);
  std::cerr << " -> " << a.out << "\n";
  return 0;
}

int cmd_export_pgm(const FloorPlan& plan, const PgmArgs& a, bool as_json) {
  if (!(a.resolution > 0)) throw std::runtime_error("--resolution must be > 0");
  const Box2 b = plan.bounds();
  const double ox = b.min.x() - a.margin, oy = b.min.y() - a.margin;
  const double w_m = b.size().x() + 2 * a.margin, h_m = b.size().y() + 2 * a.margin;
  const double wd = std::ceil(w_m / a.resolution), hd = std::ceil(h_m / a.resolution);
  if (wd * hd > 4e8) throw std::runtime_error("map too large at this resolution");
  const int w = int(wd), h = int(hd);
  annf::AnnfOptions xo;
  xo.mode = annf::AnnfMode::kExact;
  xo.max_depth = 9;
  const annf::Annf exact = annf::Annf::build(plan, xo);
  // A pixel is occupied when an element passes through it (centre distance <= half diagonal) or is
  // within half the requested wall thickness.
  const double occ = std::max(a.resolution * std::sqrt(0.5), a.thickness / 2);
  std::vector<uint8_t> img(size_t(w) * h, 254);
  size_t occupied = 0;
  for (int row = 0; row < h; ++row) {
    const int j = h - 1 - row;  // top row first
    for (int i = 0; i < w; ++i) {
      double d;
      exact.nearest(Eigen::Vector2d(ox + (i + 0.5) * a.resolution, oy + (j + 0.5) * a.resolution), &d);
      if (d <= occ) {
        img[size_t(row) * w + i] = 0;
        ++occupied;
      }
    }
  }
  std::filesystem::create_directories(a.out);
  const std::string pgm = (std::filesystem::path(a.out) / (a.name + ".pgm")).string();
  const std::string yaml = (std::filesystem::path(a.out) / (a.name + ".yaml")).string();
  {
    std::ofstream f(pgm, std::ios::binary);
    if (!f) throw std::runtime_error(pgm + ": cannot write");
    f << "P5\n# fploc map export-pgm " << plan.source << "\n" << w << " " << h << "\n255\n";
    f.write(reinterpret_cast<const char*>(img.data()), std::streamsize(img.size()));
    if (!f) throw std::runtime_error(pgm + ": write error");
  }
  {
    std::ofstream f(yaml);
    if (!f) throw std::runtime_error(yaml + ": cannot write");
    f.precision(10);
    f << "image: " << a.name << ".pgm\nresolution: " << a.resolution << "\norigin: [" << ox << ", " << oy
      << ", 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.25\nmode: trinary\n";
  }
  std::cerr << "fploc map export-pgm: " << w << " x " << h << " pixels at " << a.resolution << " m, " << occupied
            << " occupied -> " << pgm << ", " << yaml << "\n";
  if (as_json)
    std::cout << fploc::json_text(nlohmann::json({{"pgm", pgm}, {"yaml", yaml}, {"width", w}, {"height", h},
                                                  {"resolution_m", a.resolution}, {"origin", {ox, oy, 0.0}}, {"occupied", occupied}}),
                                  1)
              << "\n";
  return 0;
}

}  // namespace fploc
