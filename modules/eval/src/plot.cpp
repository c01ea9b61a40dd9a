#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "fploc/core/text_out.h"
#include "fploc/eval/eval.h"

namespace fploc::eval {

namespace {
std::string esc(const std::string& s) { return xml_text(s); }

// The "jet" colour map (evo's default for the error colouring): 0 blue .. 0.5 green .. 1 red.
std::string jet(double v) {
  v = std::clamp(v, 0.0, 1.0);
  auto ch = [&](double c) { return int(std::lround(255 * std::clamp(1.5 - std::abs(4 * v - c), 0.0, 1.0))); };
  char b[16];
  std::snprintf(b, sizeof b, "#%02x%02x%02x", ch(3), ch(2), ch(1));
  return b;
}

// A "nice" tick step (1, 2, 5 x 10^k) giving about `n` ticks over `span`.
// An error for the colour bar, in the unit that suits it: "1.25 m", "6.7 cm", "0.0665 mm" (not "6.65e-05 m").
std::string length_text(double v) {
  char b[48];
  const double a = std::abs(v);
  if (a >= 1 || a == 0) std::snprintf(b, sizeof b, "%.3g m", v);
  else if (a >= 0.01) std::snprintf(b, sizeof b, "%.3g cm", v * 100);
  else std::snprintf(b, sizeof b, "%.3g mm", v * 1000);
  return b;
}

double nice_step(double span, int n) {
  const double raw = span / std::max(1, n);
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10 * p;
}

std::string num(double v) {
  char b[32];
  if (std::abs(v) < 1e-9) v = 0;
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}
}  // namespace

std::vector<double> pose_errors(const Trajectory& gt, const Trajectory& est, const Pairs& pairs, const Eigen::Isometry3d& S) {
  std::vector<double> e(est.size(), std::numeric_limits<double>::quiet_NaN());
  for (const auto& [i, j] : pairs) e[j] = (gt[i].p - S * est[j].p).norm();
  return e;
}

std::string plot_svg(const Trajectory& gt, const Trajectory& est, const std::string& title, const Eigen::Isometry3d& S,
                     const PlotOptions& o) {
  std::vector<Eigen::Vector2d> a, b;
  for (const auto& p : gt) a.push_back(p.p.head<2>());
  for (const auto& p : est) b.push_back((S * p.p).head<2>());
  double x0 = std::numeric_limits<double>::max(), y0 = x0, x1 = -x0, y1 = -x0;
  auto grow = [&](const Eigen::Vector2d& p) {
    if (!p.allFinite()) return;
    x0 = std::min(x0, p.x());
    x1 = std::max(x1, p.x());
    y0 = std::min(y0, p.y());
    y1 = std::max(y1, p.y());
  };
  for (const auto* v : {&a, &b})
    for (const auto& p : *v) grow(p);
  if (!o.frame_trajectories)
    for (const auto& l : o.plan)
      for (const auto& p : l) grow(p);
  if (x0 > x1) x0 = y0 = -1, x1 = y1 = 1;
  const double pad = o.frame_trajectories ? std::max(0.0, o.frame_margin_m) : 0.03 * std::max(x1 - x0, y1 - y0);
  x0 -= pad, y0 -= pad, x1 += pad, y1 += pad;
  // Equal scale on both axes; the plot area is at most 820 x 760 px.
  const double span_x = std::max(x1 - x0, 1e-3), span_y = std::max(y1 - y0, 1e-3);
  const double ML = 70, MR = 30, MT = 50, MB = 60;  // margins: axis labels left and below
  const bool colour = !o.est_error.empty();
  const double LW = colour ? 150 : 0;             // colour bar on the right
  const double sc = std::min(820 / span_x, 760 / span_y);
  const double PW = span_x * sc, PH = span_y * sc;
  // The legend below the plot (items as drawn further down: swatch, text, 40 px + 7.5 px a character each, then
  // the grid's step): the picture is at least as wide (a narrow plan cut its text off).
  const double step = nice_step(std::max(span_x, span_y), 12);
  const std::string grid_text = "grid " + num(step) + " m";
  double legend_w = 40 + 7.5 * 12 /* ground truth */ + 40 + 7.5 * double(colour ? 24 /* estimate (colour: error) */ : 8) +
                    7.5 * double(grid_text.size());
  if (!o.plan.empty()) legend_w += 40 + 7.5 * double(esc(o.plan_label).size());
  const double W = std::max(ML + PW + MR + LW, ML + legend_w + MR), H = MT + PH + MB + 30;
  auto X = [&](double x) { return ML + (x - x0) * sc; };
  auto Y = [&](double y) { return MT + PH - (y - y0) * sc; };
  std::ostringstream s;
  char buf[256];
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << num(std::round(W)) << "\" height=\"" << num(std::round(H))
    << "\" viewBox=\"0 0 " << num(std::round(W)) << " " << num(std::round(H))
    << "\" font-family=\"sans-serif\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  // Grid, ticks and tick labels in metres.
  s << "<g stroke=\"#ececec\" stroke-width=\"1\">\n";
  std::ostringstream labels;
  for (double gx = std::ceil(x0 / step) * step; gx <= x1 + 1e-9; gx += step) {
    std::snprintf(buf, sizeof buf, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n", X(gx), Y(y0), X(gx), Y(y1));
    s << buf;
    std::snprintf(buf, sizeof buf, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%s</text>\n", X(gx), Y(y0) + 18,
                  num(gx).c_str());
    labels << buf;
  }
  for (double gy = std::ceil(y0 / step) * step; gy <= y1 + 1e-9; gy += step) {
    std::snprintf(buf, sizeof buf, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n", X(x0), Y(gy), X(x1), Y(gy));
    s << buf;
    std::snprintf(buf, sizeof buf, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">%s</text>\n", X(x0) - 6, Y(gy) + 4,
                  num(gy).c_str());
    labels << buf;
  }
  s << "</g>\n";
  std::snprintf(buf, sizeof buf, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" stroke=\"#444\"/>\n",
                X(x0), Y(y1), PW, PH);
  s << buf << "<g font-size=\"12\" fill=\"#333\">\n" << labels.str() << "</g>\n";
  std::snprintf(buf, sizeof buf,
                "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" font-size=\"13\">x [m]</text>\n"
                "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" font-size=\"13\" transform=\"rotate(-90 %.1f %.1f)\">y [m]</text>\n",
                ML + PW / 2, MT + PH + 38, 22.0, MT + PH / 2, 22.0, MT + PH / 2);
  s << buf;
  // The plan.
  if (!o.plan.empty()) {
    // Clipped to the axes (a plan reaching beyond them when the frame is the trajectories').
    std::snprintf(buf, sizeof buf, "<clipPath id=\"axes\"><rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\"/></clipPath>\n",
                  X(x0), Y(y1), PW, PH);
    s << buf << "<g fill=\"none\" stroke=\"#9a9a9a\" stroke-width=\"1.6\" clip-path=\"url(#axes)\"><title>floor plan</title>\n";
    for (const auto& l : o.plan) {
      if (l.size() < 2) continue;
      s << "<polyline points=\"";
      for (const auto& p : l) {
        std::snprintf(buf, sizeof buf, "%.2f,%.2f ", X(p.x()), Y(p.y()));
        s << buf;
      }
      s << "\"/>\n";
    }
    s << "</g>\n";
  }
  auto path = [&](const std::vector<Eigen::Vector2d>& v, const char* color, const char* name, double width, const char* dash) {
    if (v.empty()) return;
    s << "<polyline fill=\"none\" stroke=\"" << color << "\" stroke-width=\"" << width << "\"" << dash << " points=\"";
    for (const auto& p : v) {
      std::snprintf(buf, sizeof buf, "%.2f,%.2f ", X(p.x()), Y(p.y()));
      s << buf;
    }
    s << "\"><title>" << name << "</title></polyline>\n";
  };
  path(a, "#222222", "ground truth", 1.5, " stroke-dasharray=\"6 4\"");
  double emin = 0, emax = 0;
  if (colour) {
    // The estimate as segments coloured by the error of their start pose (jet from min to max error).
    emin = std::numeric_limits<double>::max(), emax = -emin;
    for (double e : o.est_error)
      if (std::isfinite(e)) emin = std::min(emin, e), emax = std::max(emax, e);
    if (emin > emax) emin = emax = 0;
    const double range = std::max(emax - emin, 1e-12);
    s << "<g stroke-width=\"2.5\" stroke-linecap=\"round\"><title>estimate (colour: error)</title>\n";
    for (size_t i = 0; i + 1 < b.size(); ++i) {
      const double e = i < o.est_error.size() ? o.est_error[i] : std::numeric_limits<double>::quiet_NaN();
      const std::string c = std::isfinite(e) ? jet((e - emin) / range) : std::string("#bbbbbb");
      std::snprintf(buf, sizeof buf, "<line x1=\"%.2f\" y1=\"%.2f\" x2=\"%.2f\" y2=\"%.2f\" stroke=\"%s\"/>\n", X(b[i].x()),
                    Y(b[i].y()), X(b[i + 1].x()), Y(b[i + 1].y()), c.c_str());
      s << buf;
    }
    s << "</g>\n";
    // Colour bar.
    const double bx = ML + PW + MR + 20, by = MT + 20, bh = std::min(300.0, PH - 40);
    s << "<g>\n";
    for (int k = 0; k < 50; ++k) {
      std::snprintf(buf, sizeof buf, "<rect x=\"%.1f\" y=\"%.2f\" width=\"18\" height=\"%.2f\" fill=\"%s\"/>\n", bx,
                    by + bh * (49 - k) / 50.0, bh / 50.0 + 0.5, jet(k / 49.0).c_str());
      s << buf;
    }
    std::snprintf(buf, sizeof buf,
                  "<rect x=\"%.1f\" y=\"%.1f\" width=\"18\" height=\"%.1f\" fill=\"none\" stroke=\"#444\"/>\n"
                  "<text x=\"%.1f\" y=\"%.1f\" font-size=\"12\">%s</text>\n"
                  "<text x=\"%.1f\" y=\"%.1f\" font-size=\"12\">%s</text>\n"
                  "<text x=\"%.1f\" y=\"%.1f\" font-size=\"12\">error</text>\n",
                  bx, by, bh, bx + 24, by + 10, length_text(emax).c_str(), bx + 24, by + bh, length_text(emin).c_str(), bx, by - 8);
    s << buf << "</g>\n";
  } else {
    path(b, "#d62728", "estimate", 1.8, "");
  }
  // Start markers.
  if (!a.empty()) {
    std::snprintf(buf, sizeof buf, "<circle cx=\"%.2f\" cy=\"%.2f\" r=\"4\" fill=\"#222222\"><title>start</title></circle>\n",
                  X(a.front().x()), Y(a.front().y()));
    s << buf;
  }
  s << "<text x=\"" << ML << "\" y=\"30\" font-size=\"16\">" << esc(title) << "</text>\n";
  // Legend.
  const double ly = MT + PH + 52;
  s << "<g font-size=\"13\">\n";
  double lx = ML;
  auto item = [&](const std::string& sw, const std::string& text) {
    s << sw;
    std::snprintf(buf, sizeof buf, "<text x=\"%.1f\" y=\"%.1f\">%s</text>\n", lx + 30, ly + 4, text.c_str());
    s << buf;
    lx += 40 + 7.5 * double(text.size());
  };
  std::snprintf(buf, sizeof buf, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#222\" stroke-width=\"1.5\" stroke-dasharray=\"6 4\"/>", lx, ly, lx + 24, ly);
  item(buf, "ground truth");
  if (colour) {
    std::snprintf(buf, sizeof buf, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" stroke-width=\"3\"/>"
                  "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" stroke-width=\"3\"/>",
                  lx, ly, lx + 12, ly, jet(0.1).c_str(), lx + 12, ly, lx + 24, ly, jet(0.9).c_str());
    item(buf, "estimate (colour: error)");
  } else {
    std::snprintf(buf, sizeof buf, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#d62728\" stroke-width=\"2\"/>", lx, ly, lx + 24, ly);
    item(buf, "estimate");
  }
  if (!o.plan.empty()) {
    std::snprintf(buf, sizeof buf, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#9a9a9a\" stroke-width=\"1.6\"/>", lx, ly, lx + 24, ly);
    item(buf, esc(o.plan_label));
  }
  std::snprintf(buf, sizeof buf, "<text x=\"%.1f\" y=\"%.1f\" fill=\"#888\">%s</text>\n", lx, ly + 4, grid_text.c_str());
  s << buf << "</g>\n</svg>\n";
  return s.str();
}

}  // namespace fploc::eval
