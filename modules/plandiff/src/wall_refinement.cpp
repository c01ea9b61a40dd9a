#include "fploc/plandiff/wall_refinement.h"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace fploc::plandiff {

WallRefinement::WallRefinement(size_t elements)
    : H_(Eigen::MatrixXd::Zero(2 * long(elements), 2 * long(elements))),
      g_(Eigen::VectorXd::Zero(2 * long(elements))),
      frames_(elements, 0) {}

void WallRefinement::add_scan(const std::vector<Observation>& obs) {
  Eigen::Matrix3d Hbb = Eigen::Matrix3d::Zero();
  Eigen::Vector3d gb = Eigen::Vector3d::Zero();
  for (const auto& o : obs) Hbb += o.c * o.c.transpose(), gb += o.c * o.offset;
  Eigen::LDLT<Eigen::Matrix3d> ldlt(Hbb);
  const Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(Hbb).eigenvalues();
  if (obs.size() < 4 || !(ev.minCoeff() > 1e-6 * std::max(1.0, ev.maxCoeff()))) return;
  std::vector<Eigen::Vector3d> Ki(obs.size());  // Hbb^-1 c_k
  for (size_t k = 0; k < obs.size(); ++k) Ki[k] = ldlt.solve(obs[k].c);
  const Eigen::Vector3d bg = ldlt.solve(gb);
  for (size_t k = 0; k < obs.size(); ++k) {
    const long ia = 2 * obs[k].element, ib = ia + 1;
    const double wa = 1 - obs[k].t, wb = obs[k].t;
    g_[ia] += wa * (obs[k].offset - obs[k].c.dot(bg));
    g_[ib] += wb * (obs[k].offset - obs[k].c.dot(bg));
    for (size_t l = 0; l < obs.size(); ++l) {
      const long ja = 2 * obs[l].element, jb = ja + 1;
      const double v = (k == l ? 1.0 : 0.0) - obs[k].c.dot(Ki[l]);
      const double xa = 1 - obs[l].t, xb = obs[l].t;
      H_(ia, ja) += wa * v * xa;
      H_(ia, jb) += wa * v * xb;
      H_(ib, ja) += wb * v * xa;
      H_(ib, jb) += wb * v * xb;
    }
    ++frames_[size_t(obs[k].element)];
  }
}

std::vector<RefinedSegment> WallRefinement::result(const Options& o) const {
  // (H / sigma_obs^2 + I / sigma_prior^2) x = g / sigma_obs^2.
  const double lam = std::pow(o.obs_sigma_m / o.prior_m, 2);
  Eigen::MatrixXd H = H_;
  H.diagonal().array() += lam;
  const Eigen::VectorXd x = H.ldlt().solve(g_);
  std::vector<RefinedSegment> out;
  for (size_t i = 0; i < frames_.size(); ++i) {
    const long a = 2 * long(i), b = a + 1;
    if (frames_[i] < o.min_frames || !std::isfinite(x[a]) || !std::isfinite(x[b])) continue;
    // Both ends observed well enough (the data's own information on each, scans' errors eliminated), else
    // the mean offset (a wall seen near one end only), else nothing.
    if (o.ends && H_(a, a) >= o.min_info && H_(b, b) >= o.min_info) {
      out.push_back({int(i), x[a], x[b], frames_[i]});
    } else if (H_(a, a) + H_(b, b) + 2 * H_(a, b) >= 4 * o.min_info) {
      const double m = 0.5 * (x[a] + x[b]);
      out.push_back({int(i), m, m, frames_[i]});
    }
  }
  return out;
}

}  // namespace fploc::plandiff
