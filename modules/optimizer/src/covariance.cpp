#include "fploc/optimizer/covariance.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <vector>

#include "fploc/matcher/plan_terms.h"

namespace fploc::optimizer {

double robust_weight(const std::string& loss, double scale, double r) {
  if (loss == "none" || !(scale > 0)) return 1.0;
  const double s = r * r, a2 = scale * scale;
  if (loss == "huber") return s <= a2 ? 1.0 : scale / std::sqrt(s);
  return 1.0 / (1.0 + s / a2);  // cauchy
}

namespace {

struct Obs {
  Eigen::Vector3d j;   // d residual / d (x, y, yaw)
  double w;            // robust weight
  double d;            // residual (distance to the element)
  double r;            // signed offset along the element's normal (segments) / radial (circles)
  Eigen::Vector2d c;   // sensitivity of the residual to the element's two error parameters
};

struct ElementAcc {
  std::vector<Obs> obs;
};

}  // namespace

FrameUncertainty frame_uncertainty(const matcher::NearestLookup& lookup, const FeatureFrame& f, const Pose2& x,
                                   const CovarianceConfig& cfg) {
  FrameUncertainty out;
  out.covariance = Eigen::Matrix3d::Identity() * cfg.max_variance;
  matcher::AssignOptions ao;
  ao.gate_m = cfg.gate_m;
  ao.group_rule = cfg.group_rule;
  ao.stride = matcher::budget_stride(f.points.size(), 1, cfg.max_points);
  std::vector<matcher::Assignment> as;
  matcher::assign(lookup, f, x, ao, &as);
  const auto& g = lookup.geometry();
  const double c = std::cos(x.yaw), s = std::sin(x.yaw);
  std::unordered_map<int, ElementAcc> elems;
  Eigen::Vector2d q, qb;
  Eigen::Matrix2d J, Jb;
  for (const auto& a : as) {
    const Eigen::Vector2d& p = f.points[size_t(a.point)].p;
    const double rx = c * p.x() - s * p.y(), ry = s * p.x() + c * p.y();
    const Eigen::Vector2d pw(rx + x.x, ry + x.y);
    // The closest of the candidates (as the residual picks it), and which element it is.
    double best = std::numeric_limits<double>::infinity();
    int be = -1;
    for (int k = 0; k < a.n; ++k) {
      const double d = matcher::closest_of(g, &a.cand[k], 1, pw, &qb, &Jb);
      if (d < best) best = d, be = a.cand[k], q = qb, J = Jb;
    }
    if (be < 0 || !(best <= cfg.gate_m)) continue;
    const double d = best;
    Eigen::Vector2d n;
    if (d > 1e-12) n = (pw - q) / d;
    else if (J.trace() < 1.5) n = (J.col(0).squaredNorm() >= J.col(1).squaredNorm() ? J.col(0) : J.col(1)).normalized();
    else continue;  // on an end point: no direction
    Obs o;
    o.j = Eigen::Vector3d(n.x(), n.y(), n.x() * -ry + n.y() * rx);
    o.w = robust_weight(cfg.loss, cfg.loss_scale_m, d);
    o.d = d;
    const matcher::TargetGeom& e = g[size_t(be)];
    if (e.kind == ElementKind::kSegment && e.len > 0) {
      const Eigen::Vector2d ne(-e.u.y(), e.u.x());
      const double sgn = n.dot(ne);                 // +-1 in the interior
      const double t = std::clamp((q - e.a).dot(e.u) / e.len, 0.0, 1.0);
      o.r = (pw - q).dot(ne);
      // The element's ends displaced by da, db along ne move its line by (1-t) da + t db at q: the
      // residual d changes by -sgn * that.
      o.c = cfg.two_ends ? Eigen::Vector2d(-(1 - t) * sgn, -t * sgn) : Eigen::Vector2d(-sgn, 0.0);
    } else {
      // Circle / arc / point target: a translation (dx, dy) of the element changes d by -n . (dx, dy).
      const Eigen::Vector2d radial = e.kind == ElementKind::kSegment ? n : Eigen::Vector2d((q - e.c).normalized());
      o.r = (pw - q).dot(radial);
      o.c = -n;
    }
    elems[be].obs.push_back(o);
  }
  // Noise and element offsets from the residuals.
  double sw = 0, swr2 = 0;
  int npts = 0, nel = 0;
  struct ElemStat {
    double mean, n_eff, sw;
  };
  std::vector<std::pair<int, ElemStat>> stats;
  for (auto& [id, acc] : elems) {
    double w = 0, wr = 0, w2 = 0;
    for (const auto& o : acc.obs) w += o.w, wr += o.w * o.r, w2 += o.w * o.w;
    if (!(w > 0)) continue;
    const double m = wr / w;
    for (const auto& o : acc.obs) swr2 += o.w * (o.r - m) * (o.r - m);
    sw += w;
    npts += int(acc.obs.size());
    ++nel;
    stats.push_back({id, {m, w * w / w2, w}});
  }
  out.points = npts;
  out.elements = nel;
  if (npts < 3 || !(sw > 0)) return out;
  const double dof = std::max(1.0, double(npts - nel));
  const double s2 = std::max(cfg.min_noise_sigma_m * cfg.min_noise_sigma_m, swr2 / sw * double(npts) / dof);
  out.noise_sigma_m = std::sqrt(s2);
  // Element offsets: the mean offset's square less its noise, and what the pose absorbed (3 of the G
  // offsets' degrees of freedom); a mean offset m of the two-end model has variance sigma_e^2 / 2.
  const double absorb = nel > 4 ? double(nel) / double(nel - 3) : 4.0;
  std::unordered_map<int, double> own;
  std::vector<double> b2s;
  for (const auto& [id, st] : stats) {
    const double b2 = std::max(0.0, st.mean * st.mean - s2 / st.n_eff) * absorb * (cfg.two_ends ? 2.0 : 1.0);
    own[id] = b2;
    b2s.push_back(b2);
  }
  // Pooled over the elements: the mean, or robustly the median / 0.455 (a chi-square of one degree of
  // freedom's median / mean), so that a few elements with clutter or a moved wall do not set everyone's.
  double pooled = 0;
  if (!b2s.empty()) {
    if (cfg.median_pooling) {
      std::nth_element(b2s.begin(), b2s.begin() + b2s.size() / 2, b2s.end());
      pooled = b2s[b2s.size() / 2] / 0.455;
    } else {
      for (double v : b2s) pooled += v;
      pooled /= double(b2s.size());
    }
  }
  out.element_sigma_m = std::sqrt(pooled);
  const double floor2 = std::max(cfg.plan_sigma_m * cfg.plan_sigma_m, pooled);
  const double noise_k = double(npts) / dof;
  // Bread and meat.
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero(), M = Eigen::Matrix3d::Zero();
  for (const auto& [id, acc] : elems) {
    Eigen::Matrix<double, 3, 2> G = Eigen::Matrix<double, 3, 2>::Zero();
    double mean = 0;
    for (const auto& st : stats)
      if (st.first == id) mean = st.second.mean;
    for (const auto& o : acc.obs) {
      H += o.w * o.j * o.j.transpose();
      // Noise: the point's own score about its element's offset (heteroscedasticity-consistent: clutter
      // the loss down-weights counts as little as it pulls), at least the noise floor.
      const double sc = cfg.robust_noise ? std::max(std::pow(o.w * (o.r - mean), 2) * noise_k, std::pow(o.w * cfg.min_noise_sigma_m, 2))
                                         : s2 * o.w * o.w;
      M += sc * o.j * o.j.transpose();
      G += o.w * o.j * o.c.transpose();
    }
    if (cfg.element_correlation) {
      auto it = own.find(id);
      const double o2 = it == own.end() ? 0.0 : it->second;
      // An element far off the others (a moved wall) keeps its own offset; the rest share the pooled one.
      double se2 = cfg.estimator == "model-max" ? std::max(floor2, o2) : (o2 > 4 * floor2 ? o2 : floor2);
      if (cfg.element_loss_scale_m > 0 && se2 > floor2) {
        // b2 = mean^2 * absorb * ends: back to the element's mean offset for its weight under the loss.
        const double m2 = o2 / (absorb * (cfg.two_ends ? 2.0 : 1.0));
        const double c2 = cfg.element_loss_scale_m * cfg.element_loss_scale_m;
        const double w = c2 / (c2 + m2);
        se2 = std::max(floor2, se2 * w * w);
      }
      M += se2 * G * G.transpose();
    }
  }
  out.information = H;
  // P = H^+ M H^+ (+ max_variance along what H leaves unconstrained). Yaw is scaled to metres by the
  // points' rms lever arm so that the eigenvalue test compares like with like.
  const double L = std::sqrt(std::max(1e-6, H(2, 2) / std::max(1e-12, H(0, 0) + H(1, 1))));
  const Eigen::Vector3d D(1, 1, 1 / L);  // scaled coordinates z = D^-1 x  ->  H_z = D H D
  const Eigen::Matrix3d Hz = D.asDiagonal() * H * D.asDiagonal();
  const Eigen::Matrix3d Mz = D.asDiagonal() * M * D.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(Hz);
  const double lmax = std::max(es.eigenvalues().maxCoeff(), 1e-300);
  Eigen::Matrix3d Hinv = Eigen::Matrix3d::Zero(), Null = Eigen::Matrix3d::Zero();
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d v = es.eigenvectors().col(i);
    const double l = es.eigenvalues()[i];
    if (l > 1e-9 * lmax && l > 1e-12) Hinv += v * v.transpose() / l;
    else Null += v * v.transpose();
  }
  Eigen::Matrix3d Pz = Hinv * Mz * Hinv;
  const Eigen::Matrix3d P = D.asDiagonal() * Pz * D.asDiagonal();
  // The unconstrained directions (in the scaled space) get max_variance in each of their components.
  const Eigen::Matrix3d Pn = D.asDiagonal() * Null * D.asDiagonal();
  out.covariance = 0.5 * (P + P.transpose()) + cfg.max_variance * Pn / std::max(1e-12, Pn.diagonal().maxCoeff());
  if (Null.isZero(0)) out.covariance = 0.5 * (P + P.transpose());
  // Cap (numbers beyond max_variance mean "unconstrained" and only hurt the later algebra).
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> ec(out.covariance);
  Eigen::Vector3d ev = ec.eigenvalues().cwiseMax(1e-12).cwiseMin(cfg.max_variance);
  out.covariance = ec.eigenvectors() * ev.asDiagonal() * ec.eigenvectors().transpose();
  out.valid = true;
  return out;
}

}  // namespace fploc::optimizer
