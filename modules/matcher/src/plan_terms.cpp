#include "fploc/matcher/plan_terms.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

namespace fploc {
namespace {

enum class LossKind { kNone, kHuber, kCauchy };

// Closest point on one element with d(p - q)/dp.
double closest_one(const Element& e, const Eigen::Vector2d& p, Eigen::Vector2d* q, Eigen::Matrix2d* J) {
  switch (e.kind) {
    case ElementKind::kSegment: {
      const Eigen::Vector2d ab = e.b - e.a;
      const double l2 = ab.squaredNorm();
      const double t = l2 > 0 ? (p - e.a).dot(ab) / l2 : 0.0;
      if (t <= 0.0 || l2 == 0.0) {
        *q = e.a;
        if (J) J->setIdentity();
      } else if (t >= 1.0) {
        *q = e.b;
        if (J) J->setIdentity();
      } else {
        *q = e.a + t * ab;
        if (J) {
          const Eigen::Vector2d n = Eigen::Vector2d(-ab.y(), ab.x()) / std::sqrt(l2);
          *J = n * n.transpose();
        }
      }
      break;
    }
    case ElementKind::kCircle:
    case ElementKind::kArc: {
      const Eigen::Vector2d d = p - e.c;
      const double nd = d.norm();
      bool inside = true;
      if (e.kind == ElementKind::kArc) {
        double ang = std::atan2(d.y(), d.x());
        double rel = std::fmod(ang - e.a0, 2 * M_PI);
        if (rel < 0) rel += 2 * M_PI;
        inside = e.a0 + rel <= e.a1;
      }
      if (inside && nd > 0) {
        const Eigen::Vector2d u = d / nd;
        *q = e.c + e.r * u;
        if (J) *J = u * u.transpose();
      } else if (inside) {
        *q = e.c + Eigen::Vector2d(e.r, 0);
        if (J) J->setIdentity();
      } else {
        *q = (p - e.a).squaredNorm() <= (p - e.b).squaredNorm() ? e.a : e.b;
        if (J) J->setIdentity();
      }
      break;
    }
  }
  return (p - *q).norm();
}

class PointCost : public ceres::SizedCostFunction<2, 3> {
 public:
  PointCost(const std::vector<Element>* targets, const Assignment& a, const Eigen::Vector2d& p, double w)
      : targets_(targets), a_(a), p_(p), w_(w) {}
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override {
    const double* x = params[0];
    const double c = std::cos(x[2]), s = std::sin(x[2]);
    const Eigen::Vector2d pw(c * p_.x() - s * p_.y() + x[0], s * p_.x() + c * p_.y() + x[1]);
    Eigen::Vector2d q;
    Eigen::Matrix2d J;
    closest_of(*targets_, a_.cand, a_.n, pw, &q, &J);
    residuals[0] = w_ * (pw.x() - q.x());
    residuals[1] = w_ * (pw.y() - q.y());
    if (jacobians && jacobians[0]) {
      Eigen::Matrix<double, 2, 3> dp;
      dp << 1, 0, -s * p_.x() - c * p_.y(), 0, 1, c * p_.x() - s * p_.y();
      Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>> out(jacobians[0]);
      out = w_ * J * dp;
    }
    return true;
  }

 private:
  const std::vector<Element>* targets_;
  Assignment a_;
  Eigen::Vector2d p_;
  double w_;
};

// All points of one frame in one residual block (Ceres' per-block overhead dominates per-point
// blocks). The robust loss is folded into the residuals exactly: r~ = g(s) r with g = sqrt(rho(s)/s),
// s = |r|^2, so |r~|^2 = rho(s), and the Jacobian is the exact derivative of r~.
class FrameCost : public ceres::CostFunction {
 public:
  FrameCost(const std::vector<Element>* targets, std::vector<Assignment> as, std::vector<Eigen::Vector2d> pts,
            LossKind loss, double scale, double w)
      : targets_(targets), as_(std::move(as)), pts_(std::move(pts)), loss_(loss), a_(scale), w_(w) {
    set_num_residuals(int(2 * as_.size()));
    mutable_parameter_block_sizes()->push_back(3);
  }
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override {
    const double* x = params[0];
    const double c = std::cos(x[2]), s = std::sin(x[2]);
    double* jac = jacobians ? jacobians[0] : nullptr;
    Eigen::Vector2d q;
    Eigen::Matrix2d J;
    for (size_t i = 0; i < as_.size(); ++i) {
      const Eigen::Vector2d& p = pts_[i];
      const Eigen::Vector2d pw(c * p.x() - s * p.y() + x[0], s * p.x() + c * p.y() + x[1]);
      closest_of(*targets_, as_[i].cand, as_[i].n, pw, &q, jac ? &J : nullptr);
      const Eigen::Vector2d r = w_ * (pw - q);
      const double sq = r.squaredNorm();
      double g = 1, dg = 0;
      robust_scale(sq, &g, &dg);
      residuals[2 * i] = g * r.x();
      residuals[2 * i + 1] = g * r.y();
      if (jac) {
        Eigen::Matrix<double, 2, 3> dp;
        dp << 1, 0, -s * p.x() - c * p.y(), 0, 1, c * p.x() - s * p.y();
        const Eigen::Matrix<double, 2, 3> Jr = w_ * J * dp;
        Eigen::Matrix<double, 2, 3> Jt = g * Jr;
        if (dg != 0) Jt += (2 * dg) * r * (r.transpose() * Jr);
        Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>>(jac + 6 * i) = Jt;
      }
    }
    return true;
  }

 private:
  // g = sqrt(rho(s)/s) and dg/ds.
  void robust_scale(double s, double* g, double* dg) const {
    const double a2 = a_ * a_;
    if (loss_ == LossKind::kNone || s < 1e-18) return;
    double rho, rho1;
    if (loss_ == LossKind::kHuber) {
      if (s <= a2) return;
      const double r = std::sqrt(s);
      rho = 2 * a_ * r - a2;
      rho1 = a_ / r;
    } else {  // Cauchy
      rho = a2 * std::log1p(s / a2);
      rho1 = 1.0 / (1.0 + s / a2);
    }
    *g = std::sqrt(rho / s);
    *dg = (rho1 * s - rho) / (2 * (*g) * s * s);
  }
  const std::vector<Element>* targets_;
  std::vector<Assignment> as_;
  std::vector<Eigen::Vector2d> pts_;
  LossKind loss_;
  double a_, w_;
};

}  // namespace

double closest_of(const std::vector<Element>& targets, const int* cand, int n, const Eigen::Vector2d& p,
                  Eigen::Vector2d* q, Eigen::Matrix2d* dr_dp) {
  double best = std::numeric_limits<double>::infinity();
  int best_i = -1;
  Eigen::Vector2d qi;
  for (int i = 0; i < n; ++i) {
    const double d = closest_one(targets[size_t(cand[i])], p, &qi, nullptr);
    if (d < best) {
      best = d;
      best_i = i;
      *q = qi;
    }
  }
  if (best_i >= 0 && dr_dp) closest_one(targets[size_t(cand[best_i])], p, q, dr_dp);
  if (best_i < 0) {
    *q = p;
    if (dr_dp) dr_dp->setZero();
  }
  return best;
}

void assign(const NearestLookup& lookup, const FeatureFrame& f, const Pose2& x, const AssignOptions& o,
            std::vector<Assignment>* out) {
  out->clear();
  const auto& targets = lookup.targets();
  const bool groups = o.group_rule && lookup.element_targets();
  const int maxc = std::clamp(o.max_candidates, 1, kMaxCandidates);
  const int stride = std::max(1, o.stride);
  struct GroupPoint {
    int point;
    Eigen::Vector2d pw;
  };
  std::map<int32_t, std::vector<GroupPoint>> group_points;
  std::map<int32_t, std::vector<int>> group_cands;
  Eigen::Vector2d q;
  for (size_t i = 0; i < f.points.size(); i += size_t(stride)) {
    const auto& fp = f.points[i];
    const Eigen::Vector2d pw = transform(x, fp.p);
    Assignment a;
    a.point = int(i);
    a.n = lookup.candidates(pw, a.cand, maxc);
    if (a.n <= 0) continue;
    if (groups && fp.group >= 0) {
      group_points[fp.group].push_back({int(i), pw});
      auto& gc = group_cands[fp.group];
      for (int k = 0; k < a.n; ++k)
        if (std::find(gc.begin(), gc.end(), a.cand[k]) == gc.end()) gc.push_back(a.cand[k]);
      continue;
    }
    if (closest_of(targets, a.cand, a.n, pw, &q, nullptr) <= o.gate_m) out->push_back(a);
  }
  // One element per group: the candidate with the smallest truncated sum of squared distances.
  const double g2 = o.gate_m * o.gate_m;
  for (const auto& [g, pts] : group_points) {
    const auto& gc = group_cands[g];
    int best = -1;
    double best_cost = std::numeric_limits<double>::infinity();
    for (int e : gc) {
      double cost = 0;
      for (const auto& gp : pts) cost += std::min(std::pow(closest_one(targets[size_t(e)], gp.pw, &q, nullptr), 2), g2);
      if (cost < best_cost) {
        best_cost = cost;
        best = e;
      }
    }
    if (best < 0) continue;
    for (const auto& gp : pts) {
      if (closest_one(targets[size_t(best)], gp.pw, &q, nullptr) > o.gate_m) continue;
      Assignment a;
      a.point = gp.point;
      a.n = 1;
      a.cand[0] = best;
      out->push_back(a);
    }
  }
}

ceres::CostFunction* make_point_cost(const std::vector<Element>* targets, const Assignment& a,
                                     const Eigen::Vector2d& p_sensor, double weight) {
  return new PointCost(targets, a, p_sensor, weight);
}

void add_frame_term(ceres::Problem* problem, double* pose, const NearestLookup& lookup, const FeatureFrame& f,
                    const std::vector<Assignment>& as, const std::string& loss, double scale, double weight) {
  if (as.empty()) return;
  std::vector<Eigen::Vector2d> pts;
  pts.reserve(as.size());
  for (const auto& a : as) pts.push_back(f.points[size_t(a.point)].p);
  const LossKind k = (loss == "none" || scale <= 0) ? LossKind::kNone : loss == "cauchy" ? LossKind::kCauchy : LossKind::kHuber;
  problem->AddResidualBlock(new FrameCost(&lookup.targets(), as, std::move(pts), k, scale, weight), nullptr, pose);
}

void add_plan_terms(ceres::Problem* problem, double* pose, const NearestLookup& lookup, const FeatureFrame& f,
                    const std::vector<Assignment>& as, ceres::LossFunction* loss, double weight) {
  for (const auto& a : as)
    problem->AddResidualBlock(make_point_cost(&lookup.targets(), a, f.points[size_t(a.point)].p, weight), loss, pose);
}

FitQuality evaluate_fit(const NearestLookup& lookup, const FeatureFrame& f, const Pose2& x, double inlier_m) {
  FitQuality q;
  q.num_points = int(f.points.size());
  double sum2 = 0;
  int cand[kMaxCandidates];
  Eigen::Vector2d cp;
  for (const auto& fp : f.points) {
    const Eigen::Vector2d pw = transform(x, fp.p);
    const int n = lookup.candidates(pw, cand, kMaxCandidates);
    const double d = closest_of(lookup.targets(), cand, n, pw, &cp, nullptr);
    if (d <= inlier_m) {
      ++q.num_inliers;
      sum2 += d * d;
    }
  }
  q.inlier_ratio = q.num_points > 0 ? double(q.num_inliers) / q.num_points : 0.0;
  q.rms_m = q.num_inliers > 0 ? std::sqrt(sum2 / q.num_inliers) : 0.0;
  return q;
}

const char* to_string(FitStatus s) {
  switch (s) {
    case FitStatus::kOk: return "OK";
    case FitStatus::kPoor: return "POOR";
    case FitStatus::kLost: return "LOST";
    case FitStatus::kNotInitialised: return "NOT_INITIALISED";
  }
  return "?";
}

}  // namespace fploc
