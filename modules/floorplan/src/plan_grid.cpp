// Plan coordinates on pictures: a grid in metres with labels in the margins (fploc/floorplan/png.h).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "fploc/floorplan/png.h"

namespace fploc {

std::string PlanGrid::label(double v) const {
  const double k = std::round(v / step_m);
  const int decimals = step_m >= 1 ? 0 : int(std::ceil(-std::log10(step_m) - 1e-9));
  char b[32];
  std::snprintf(b, sizeof b, "%.*f", decimals, k * step_m + 0.0);
  std::string s = b;
  if (s.find('.') != std::string::npos) {  // "1.50" -> "1.5", "2.0" -> "2"
    s.erase(s.find_last_not_of('0') + 1);
    if (s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  return s;
}

PlanGrid plan_grid(double min_x, double min_y, double max_x, double max_y, double px_per_m, int font_px) {
  PlanGrid g;
  g.font_px = font_px;
  const double span = std::max({max_x - min_x, max_y - min_y, 1e-3});
  // The widest label of a step over the box: its values at the box's ends (the longest numbers).
  auto widest = [&](const PlanGrid& t, double lo, double hi) {
    int w = 0;
    for (double v = std::ceil(lo / t.step_m) * t.step_m; v <= hi + 1e-9 * span; v += t.step_m)
      w = std::max(w, text_width(t.label(v), font_px));
    return w;
  };
  for (double p = std::pow(10.0, std::floor(std::log10(span / 1000))); p < 1e9; p *= 10) {
    bool done = false;
    for (double k : {1.0, 2.0, 5.0}) {
      g.step_m = k * p;
      if (span / g.step_m > 200) continue;
      const int wx = widest(g, min_x, max_x);
      if (g.step_m * px_per_m >= std::max(5.0 * font_px, wx + 2.0 * font_px)) {
        done = true;
        break;
      }
    }
    if (done) break;
  }
  const int tick = std::max(3, font_px / 3);
  g.left_px = std::max(widest(g, min_y, max_y), text_width("m", font_px)) + tick + font_px / 2 + 2;
  g.bottom_px = font_px + tick + font_px / 2;
  return g;
}

void PlanArea::to_m(double c, double r, double* x, double* y) const {
  const double det = ux * vy - vx * uy, dc = c - ox, dr = r - oy;
  *x = (vy * dc - vx * dr) / det, *y = (-uy * dc + ux * dr) / det;
}

namespace {

// The area's extent in plan metres (its corners mapped back).
void area_box(const PlanArea& a, double* x0, double* y0, double* x1, double* y1) {
  *x0 = *y0 = 1e300, *x1 = *y1 = -1e300;
  for (double c : {double(a.x0), double(a.x1)})
    for (double r : {double(a.y0), double(a.y1)}) {
      double x, y;
      a.to_m(c, r, &x, &y);
      *x0 = std::min(*x0, x), *y0 = std::min(*y0, y), *x1 = std::max(*x1, x), *y1 = std::max(*y1, y);
    }
}

// Each grid line of one axis (along = 0: the lines x = v; 1: y = v) inside the area, sampled every half pixel:
// fn(v, column, row) per sample that falls inside.
template <class Fn>
void for_each_line(const PlanArea& a, const PlanGrid& g, int along, Fn fn) {
  double x0, y0, x1, y1;
  area_box(a, &x0, &y0, &x1, &y1);
  const double lo = along == 0 ? x0 : y0, hi = along == 0 ? x1 : y1;
  const double s0 = along == 0 ? y0 : x0, s1 = along == 0 ? y1 : x1;
  const double ppm = std::max(std::hypot(a.ux, a.uy), std::hypot(a.vx, a.vy));
  const double ds = 0.5 / ppm;
  if ((hi - lo) / g.step_m > 1000 || (s1 - s0) / ds > 1e7) return;
  for (double k = std::ceil(lo / g.step_m); k * g.step_m <= hi; k += 1) {
    const double v = k * g.step_m;
    for (double s = s0; s <= s1; s += ds) {
      double c, r;
      a.to_px(along == 0 ? v : s, along == 0 ? s : v, &c, &r);
      const int ci = int(std::floor(c)), ri = int(std::floor(r));
      if (ci >= a.x0 && ci < a.x1 && ri >= a.y0 && ri < a.y1) fn(v, ci, ri);
    }
  }
}

}  // namespace

void draw_plan_grid_lines(RgbImage& img, const PlanArea& a, const PlanGrid& g) {
  const int W = a.x1 - a.x0, H = a.y1 - a.y0;
  if (W <= 0 || H <= 0) return;
  std::vector<uint8_t> mask(size_t(W) * H, 0);  // 1 grid line, 2 an axis: each pixel blended once
  for (int along : {0, 1})
    for_each_line(a, g, along, [&](double v, int c, int r) {
      uint8_t& m = mask[size_t(r - a.y0) * W + (c - a.x0)];
      m = std::max<uint8_t>(m, std::abs(v) < 1e-9 * g.step_m ? 2 : 1);
    });
  // The origin: a ring of 5 px.
  double oc, orow;
  a.to_px(0, 0, &oc, &orow);
  for (int r = int(orow) - 7; r <= int(orow) + 7; ++r)
    for (int c = int(oc) - 7; c <= int(oc) + 7; ++c) {
      const double d = std::hypot(c + 0.5 - oc, r + 0.5 - orow);
      if (c >= a.x0 && c < a.x1 && r >= a.y0 && r < a.y1 && d >= 4 && d <= 6) mask[size_t(r - a.y0) * W + (c - a.x0)] = 3;
    }
  static const uint8_t line[3] = {60, 90, 150};
  for (int r = 0; r < H; ++r)
    for (int c = 0; c < W; ++c)
      if (const uint8_t m = mask[size_t(r) * W + c])
        img.fill_rect(a.x0 + c, a.y0 + r, a.x0 + c + 1, a.y0 + r + 1, line, m == 1 ? 0.2 : m == 2 ? 0.5 : 0.9);
}

void draw_plan_grid_labels(RgbImage& img, const PlanArea& a, const PlanGrid& g) {
  static const uint8_t ink[3] = {40, 40, 40};
  const int fs = g.font_px, tick = std::max(3, fs / 3);
  // Where each line leaves the area: the bottom-most sample of an x line, the left-most of a y line.
  struct End {
    double v;
    int c, r;
  };
  std::vector<End> xs, ys;
  for_each_line(a, g, 0, [&](double v, int c, int r) {
    if (xs.empty() || xs.back().v != v) xs.push_back({v, c, r});
    else if (r > xs.back().r) xs.back() = {v, c, r};
  });
  for_each_line(a, g, 1, [&](double v, int c, int r) {
    if (ys.empty() || ys.back().v != v) ys.push_back({v, c, r});
    else if (c < ys.back().c) ys.back() = {v, c, r};
  });
  // The unit, in the corner between the margins; the x labels' right end so far (left to right): overlapping ones
  // are left out.
  const int unit_w = text_width("m", fs), unit_x = std::max(0, a.x0 - tick - 2 - unit_w);
  draw_text(img, unit_x, a.y1 + tick + fs, "m", fs, ink);
  int right = unit_x + unit_w;
  std::sort(xs.begin(), xs.end(), [](const End& p, const End& q) { return p.c < q.c; });
  for (const End& e : xs) {
    if (e.r < a.y1 - 2) continue;  // leaves through another edge (a rotated map)
    const std::string t = g.label(e.v);
    const int w = text_width(t, fs), l = std::clamp(e.c - w / 2, 0, img.w - w);
    if (l < right + fs / 2) continue;
    img.fill_rect(e.c, a.y1, e.c + 1, a.y1 + tick, ink);
    draw_text(img, l, a.y1 + tick + fs, t, fs, ink);
    right = l + w;
  }
  int top = 1000000;  // the y labels' top so far (bottom to top)
  std::sort(ys.begin(), ys.end(), [](const End& p, const End& q) { return p.r > q.r; });
  for (const End& e : ys) {
    if (e.c > a.x0 + 1) continue;
    const std::string t = g.label(e.v);
    const int w = text_width(t, fs), base = std::clamp(e.r + fs * 7 / 20, fs, img.h);
    if (base > top - fs / 3) continue;
    img.fill_rect(a.x0 - tick, e.r, a.x0, e.r + 1, ink);
    draw_text(img, a.x0 - tick - 2 - w, base, t, fs, ink);
    top = base - fs;
  }
}

}  // namespace fploc
