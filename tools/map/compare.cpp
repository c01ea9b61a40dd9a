// fploc map compare: how much of plan A lies on plan B (e.g. an IFC model's walls against the DXF
// drawing of the same building). A's elements are sampled every `step` metres; the share of A's
// length whose nearest B element is within `tolerance` is reported, after an optional rigid 2D
// alignment of A onto B:
//   none  A as it is;
//   auto  starts from the identity and from the four right-angle rotations about the bounding-box
//         centres (translation: centre of A's box onto centre of B's), refines each by trimmed ICP
//         (point-to-closest-point on B's elements, inliers within 0.5 m then 0.1 m, closed-form 2D
//         rigid fit), and keeps the one with the largest share.
// --out writes an SVG overlay (B grey, A coloured: green within tolerance, red beyond).
#include <Eigen/Geometry>
#include <cmath>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "fploc/annf/annf.h"
#include "fploc/core/text_out.h"
#include "fploc/floorplan/png.h"
#include "map_tool.h"

namespace fploc {
namespace {

struct Sample {
  Eigen::Vector2d p;
  double w;  // length it stands for
};

std::vector<Sample> sample(const FloorPlan& plan, double step) {
  std::vector<Sample> s;
  for (const auto& e : plan.elements) {
    if (e.kind == ElementKind::kSegment) {
      const double len = (e.b - e.a).norm();
      const int n = std::max(1, int(std::ceil(len / step)));
      for (int i = 0; i < n; ++i) s.push_back({e.a + (e.b - e.a) * ((i + 0.5) / n), len / n});
    } else {
      const double a0 = e.kind == ElementKind::kCircle ? 0 : e.a0, a1 = e.kind == ElementKind::kCircle ? 2 * M_PI : e.a1;
      const double len = e.r * (a1 - a0);
      const int n = std::max(1, int(std::ceil(len / step)));
      for (int i = 0; i < n; ++i) {
        const double t = a0 + (a1 - a0) * ((i + 0.5) / n);
        s.push_back({e.c + e.r * Eigen::Vector2d(std::cos(t), std::sin(t)), len / n});
      }
    }
  }
  return s;
}

using Rigid = Eigen::Isometry2d;

double share_within(const std::vector<Sample>& s, const annf::Annf& b, const Rigid& T, double tol) {
  double in = 0, all = 0;
  for (const auto& x : s) {
    double d;
    b.nearest(T * x.p, &d);
    all += x.w;
    if (d <= tol) in += x.w;
  }
  return all > 0 ? in / all : 0;
}

Rigid icp(const std::vector<Sample>& s, const annf::Annf& b, Rigid T) {
  for (double gate : {0.5, 0.1}) {
    for (int it = 0; it < 30; ++it) {
      Eigen::Vector2d ma(0, 0), mb(0, 0);
      double W = 0;
      std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> pairs;
      for (const auto& x : s) {
        const Eigen::Vector2d p = T * x.p;
        double d;
        Eigen::Vector2d q;
        b.nearest(p, &d, &q);
        if (d > gate) continue;
        pairs.push_back({p, q});
        ma += x.w * p;
        mb += x.w * q;
        W += x.w;
      }
      if (pairs.size() < 10) return T;
      ma /= W;
      mb /= W;
      double sxx = 0, sxy = 0;
      for (const auto& [p, q] : pairs) {
        const Eigen::Vector2d a = p - ma, c = q - mb;
        sxx += a.dot(c);
        sxy += a.x() * c.y() - a.y() * c.x();
      }
      const double th = std::atan2(sxy, sxx);
      Rigid step = Rigid::Identity();
      step.linear() = Eigen::Rotation2Dd(th).toRotationMatrix();
      step.translation() = mb - step.linear() * ma;
      T = step * T;
      if (std::abs(th) < 1e-7 && step.translation().norm() < 1e-6) break;
    }
  }
  return T;
}

}  // namespace

int cmd_compare(const FloorPlan& a, const FloorPlan& b, const CompareArgs& args, bool as_json) {
  if (!(args.tolerance > 0) || !(args.step > 0)) throw std::runtime_error("--tolerance and --step must be > 0");
  annf::AnnfOptions o;
  o.mode = annf::AnnfMode::kExact;
  o.max_depth = 9;
  o.margin = 5.0;
  const annf::Annf fb = annf::Annf::build(b, o);
  const std::vector<Sample> s = sample(a, args.step);
  double total = 0;
  for (const auto& x : s) total += x.w;
  Rigid best = Rigid::Identity();
  if (!args.transform.empty()) {
    double x, y, yaw;
    char c1, c2;
    std::istringstream ts(args.transform);
    if (!(ts >> x >> c1 >> y >> c2 >> yaw) || c1 != ',' || c2 != ',')
      throw std::runtime_error("--transform: expected x,y,yaw_deg, got '" + args.transform + "'");
    best.linear() = Eigen::Rotation2Dd(yaw * M_PI / 180).toRotationMatrix();
    best.translation() = Eigen::Vector2d(x, y);
  }
  double best_share = share_within(s, fb, best, args.tolerance);
  const double identity_share = best_share;
  std::string how = "none";
  if (args.align == "auto") {
    const Box2 ba = a.bounds(), bb = b.bounds();
    const Eigen::Vector2d ca = (ba.min + ba.max) / 2, cb = (bb.min + bb.max) / 2;
    std::vector<std::pair<std::string, Rigid>> starts = {{args.transform.empty() ? "identity" : "--transform", best}};
    for (int k = 0; k < 4; ++k) {
      Rigid T = Rigid::Identity();
      T.linear() = Eigen::Rotation2Dd(k * M_PI / 2).toRotationMatrix();
      T.translation() = cb - T.linear() * ca;
      starts.push_back({"box centres, rotation " + std::to_string(90 * k) + " deg", T});
    }
    best_share = -1;
    for (const auto& [name, T0] : starts) {
      const Rigid T = icp(s, fb, T0);
      const double sh = share_within(s, fb, T, args.tolerance);
      if (sh > best_share) {
        best_share = sh;
        best = T;
        how = "ICP from " + name;
      }
    }
  } else if (args.align != "none") {
    throw std::runtime_error("--align must be none or auto");
  }
  const double yaw = std::atan2(best.linear()(1, 0), best.linear()(0, 0)) * 180 / M_PI;
  nlohmann::json j = {{"a", a.source},
                      {"b", b.source},
                      {"a_elements", a.elements.size()},
                      {"b_elements", b.elements.size()},
                      {"a_length_m", total},
                      {"tolerance_m", args.tolerance},
                      {"share_unaligned", identity_share},
                      {"alignment", how},
                      {"tx_m", best.translation().x()},
                      {"ty_m", best.translation().y()},
                      {"yaw_deg", yaw},
                      {"share", best_share}};
  if (as_json)
    std::cout << fploc::json_text(j, 1) << "\n";
  else
    std::cout << "A " << a.source << " (" << a.elements.size() << " elements, " << total << " m) against B " << b.source
              << " (" << b.elements.size() << " elements)\n"
              << "alignment: " << how << ": x " << best.translation().x() << " m, y " << best.translation().y()
              << " m, yaw " << yaw << " deg\n"
              << "share of A's length within " << args.tolerance << " m of B: " << 100 * best_share
              << " % (without alignment: " << 100 * identity_share << " %)\n";
  if (!args.out.empty()) {
    Box2 box = b.bounds();
    for (const auto& x : s) box.extend(best * x.p);
    const double pad = 1.0;
    box.min -= Eigen::Vector2d(pad, pad);
    box.max += Eigen::Vector2d(pad, pad);
    const bool png = args.out.size() > 4 && args.out.substr(args.out.size() - 4) == ".png";
    const int W = 2000, H = int(std::ceil(W * box.size().y() / box.size().x()));
    const double sc = W / box.size().x();
    auto X = [&](const Eigen::Vector2d& p) { return (p.x() - box.min.x()) * sc; };
    auto Y = [&](const Eigen::Vector2d& p) { return H - (p.y() - box.min.y()) * sc; };
    std::vector<uint8_t> img(png ? size_t(W) * H * 3 : 0, 255);
    std::ostringstream svg;
    svg << "<svg xmlns='http://www.w3.org/2000/svg' width='" << W << "' height='" << H << "'>\n"
        << "<rect width='100%' height='100%' fill='white'/>\n";
    auto dot = [&](const Eigen::Vector2d& p, int r, uint8_t cr, uint8_t cg, uint8_t cb, const char* css) {
      if (!png) {
        svg << "<circle cx='" << X(p) << "' cy='" << Y(p) << "' r='" << r << "' fill='" << css << "'/>\n";
        return;
      }
      const int ci = int(X(p)), cj = int(Y(p));
      for (int j = cj - r + 1; j < cj + r; ++j)
        for (int i = ci - r + 1; i < ci + r; ++i)
          if (i >= 0 && j >= 0 && i < W && j < H) {
            uint8_t* c = &img[(size_t(j) * W + i) * 3];
            c[0] = cr;
            c[1] = cg;
            c[2] = cb;
          }
    };
    for (const auto& x : sample(b, 0.5 / sc)) dot(x.p, 1, 150, 150, 150, "#999");
    for (const auto& x : s) {
      const Eigen::Vector2d p = best * x.p;
      double d;
      fb.nearest(p, &d);
      if (d <= args.tolerance)
        dot(p, 2, 0, 170, 0, "#0a0");
      else
        dot(p, 2, 230, 0, 0, "#e00");
    }
    if (png) {
      write_rgb_png(args.out, W, H, img);
    } else {
      std::ofstream f(args.out);
      if (!f) throw std::runtime_error(args.out + ": cannot write");
      f << svg.str() << "</svg>\n";
    }
  }
  return 0;
}

}  // namespace fploc
