#include "fploc/eval/uncertainty.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace fploc::eval {

namespace {
double yaw_of(const Eigen::Matrix3d& R) { return std::atan2(R(1, 0), R(0, 0)); }
double wrap(double a) { return std::atan2(std::sin(a), std::cos(a)); }
}  // namespace

std::string uncertainty_line(const PoseUncertainty& u) {
  char b[320];
  const auto& c = u.cov;
  std::snprintf(b, sizeof b, "%.6f %d %.9g %.9g %.9g %.9g %.9g %.9g", u.t, u.status, c(0, 0), c(0, 1), c(0, 2), c(1, 1),
                c(1, 2), c(2, 2));
  return b;
}

std::vector<PoseUncertainty> read_uncertainty(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot open");
  std::vector<PoseUncertainty> out;
  std::string line;
  for (int n = 1; std::getline(f, line); ++n) {
    const auto p = line.find_first_not_of(" \t\r");
    if (p == std::string::npos || line[p] == '#') continue;
    std::istringstream ss(line);
    PoseUncertainty u;
    double v[6];
    if (!(ss >> u.t >> u.status >> v[0] >> v[1] >> v[2] >> v[3] >> v[4] >> v[5]))
      throw std::runtime_error(path + ":" + std::to_string(n) + ": expected 't status xx xy xyaw yy yyaw yawyaw'");
    std::string extra;
    if (ss >> extra) throw std::runtime_error(path + ":" + std::to_string(n) + ": more than 8 fields");
    if (u.status < 0 || u.status > 2) throw std::runtime_error(path + ":" + std::to_string(n) + ": status must be 0, 1 or 2");
    if (!std::isfinite(u.t)) throw std::runtime_error(path + ":" + std::to_string(n) + ": non-finite time");
    u.cov << v[0], v[1], v[2], v[1], v[3], v[4], v[2], v[4], v[5];
    out.push_back(u);
  }
  std::sort(out.begin(), out.end(), [](const PoseUncertainty& a, const PoseUncertainty& b) { return a.t < b.t; });
  return out;
}

Consistency consistency(const Trajectory& gt, const Trajectory& est, const Pairs& pairs,
                        const std::vector<PoseUncertainty>& u, double false_ok_m, const Eigen::Isometry3d& S, double max_dt) {
  Consistency c;
  c.false_ok_m = false_ok_m;
  std::vector<double> n3, nx, ny, nyaw;
  for (const auto& [i, j] : pairs) {
    const double t = est[j].t;
    auto it = std::lower_bound(u.begin(), u.end(), t, [](const PoseUncertainty& a, double tt) { return a.t < tt; });
    const PoseUncertainty* best = nullptr;
    for (auto k : {it, it == u.begin() ? it : it - 1})
      if (k != u.end() && std::abs(k->t - t) <= max_dt && (!best || std::abs(k->t - t) < std::abs(best->t - t))) best = &*k;
    if (!best) continue;
    ++c.poses;
    const Eigen::Isometry3d E = S * est[j].iso();
    const Eigen::Vector3d d = gt[i].p - E.translation();
    const Eigen::Vector3d e(d.x(), d.y(), wrap(yaw_of(gt[i].iso().linear()) - yaw_of(E.linear())));
    if (best->status == 0) {
      ++c.ok;
      if (e.head<2>().norm() > false_ok_m) ++c.false_ok;
    }
    const Eigen::Matrix3d P = 0.5 * (best->cov + best->cov.transpose());
    Eigen::LLT<Eigen::Matrix3d> llt(P);
    if (!P.allFinite() || llt.info() != Eigen::Success || !(P.diagonal().minCoeff() > 0)) continue;
    ++c.nees_poses;
    n3.push_back(e.dot(llt.solve(e)));
    nx.push_back(e.x() * e.x() / P(0, 0));
    ny.push_back(e.y() * e.y() / P(1, 1));
    nyaw.push_back(e.z() * e.z() / P(2, 2));
  }
  c.nees = summarize(n3);
  c.nees_x = summarize(nx);
  c.nees_y = summarize(ny);
  c.nees_yaw = summarize(nyaw);
  c.false_ok_share = c.poses ? double(c.false_ok) / double(c.poses) : 0.0;
  return c;
}

}  // namespace fploc::eval
