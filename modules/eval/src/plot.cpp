#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "fploc/eval/eval.h"

namespace fploc::eval {

namespace {
std::string esc(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '<') o += "&lt;";
    else if (c == '>') o += "&gt;";
    else if (c == '&') o += "&amp;";
    else o += c;
  }
  return o;
}
}  // namespace

std::string plot_svg(const Trajectory& gt, const Trajectory& est, const std::string& title,
                     const Eigen::Isometry3d& S) {
  std::vector<Eigen::Vector2d> a, b;
  for (const auto& p : gt) a.push_back(p.p.head<2>());
  for (const auto& p : est) b.push_back((S * p.p).head<2>());
  double x0 = std::numeric_limits<double>::max(), y0 = x0, x1 = -x0, y1 = -x0;
  for (const auto* v : {&a, &b})
    for (const auto& p : *v) {
      x0 = std::min(x0, p.x());
      x1 = std::max(x1, p.x());
      y0 = std::min(y0, p.y());
      y1 = std::max(y1, p.y());
    }
  if (x0 > x1) x0 = y0 = -1, x1 = y1 = 1;
  // Equal scale on both axes, 800 px wide; the height follows the trajectory's aspect (at most 800 px,
  // at least 200 px), so an elongated building does not leave half the picture empty.
  const double span_x = std::max(x1 - x0, 1e-3), span_y = std::max(y1 - y0, 1e-3);
  const double span = std::max(span_x, span_y);
  const double W = 800, M = 50;
  const double sc = std::min((W - 2 * M) / span_x, (800 - 2 * M) / span_y);
  const double H = std::max(200.0, 2 * M + span_y * sc);
  auto X = [&](double x) { return M + (x - x0) * sc; };
  auto Y = [&](double y) { return H - M - (y - y0) * sc; };
  std::ostringstream s;
  char buf[128];
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H + 40 << "\" viewBox=\"0 0 "
    << W << " " << H + 40 << "\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  // 1 m grid (or coarser for large plots).
  double step = 1;
  while (span / step > 20) step *= 5;
  s << "<g stroke=\"#e4e4e4\" stroke-width=\"1\">\n";
  const double gx1 = x0 + (W - 2 * M) / sc, gy1 = y0 + (H - 2 * M) / sc;  // the drawable area
  for (double gx = std::floor(x0 / step) * step; gx <= gx1 + 1e-9; gx += step)
    if (X(gx) >= M - 1) {
      std::snprintf(buf, sizeof buf, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n", X(gx), Y(y0),
                    X(gx), Y(gy1));
      s << buf;
    }
  for (double gy = std::floor(y0 / step) * step; gy <= gy1 + 1e-9; gy += step)
    if (Y(gy) <= H - M + 1) {
      std::snprintf(buf, sizeof buf, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n", X(x0), Y(gy),
                    X(gx1), Y(gy));
      s << buf;
    }
  s << "</g>\n";
  auto path = [&](const std::vector<Eigen::Vector2d>& v, const char* color, const char* name, double width) {
    if (v.empty()) return;
    s << "<polyline fill=\"none\" stroke=\"" << color << "\" stroke-width=\"" << width << "\" points=\"";
    for (const auto& p : v) {
      std::snprintf(buf, sizeof buf, "%.2f,%.2f ", X(p.x()), Y(p.y()));
      s << buf;
    }
    s << "\"><title>" << name << "</title></polyline>\n";
    std::snprintf(buf, sizeof buf, "<circle cx=\"%.2f\" cy=\"%.2f\" r=\"4\" fill=\"%s\"/>\n", X(v.front().x()),
                  Y(v.front().y()), color);
    s << buf;
  };
  path(a, "#222222", "ground truth", 2.5);
  path(b, "#d62728", "estimate", 1.5);
  std::snprintf(buf, sizeof buf, "grid %.0f m", step);
  s << "<text x=\"" << M << "\" y=\"30\" font-family=\"sans-serif\" font-size=\"16\">" << esc(title) << "</text>\n"
    << "<text x=\"" << M << "\" y=\"" << H + 20
    << "\" font-family=\"sans-serif\" font-size=\"13\"><tspan fill=\"#222222\">&#9632; ground truth</tspan>"
       "  <tspan fill=\"#d62728\">&#9632; estimate</tspan>  <tspan fill=\"#888\">"
    << buf << "</tspan></text>\n</svg>\n";
  return s.str();
}

}  // namespace fploc::eval
