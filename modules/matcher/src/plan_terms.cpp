#include "fploc/matcher/plan_terms.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

namespace fploc::matcher {
namespace {

enum class LossKind { kNone, kHuber, kCauchy, kGemanMcClure };

LossKind loss_kind(const std::string& loss, double scale) {
  if (loss == "none" || scale <= 0) return LossKind::kNone;
  if (loss == "geman-mcclure") return LossKind::kGemanMcClure;
  return loss == "cauchy" ? LossKind::kCauchy : LossKind::kHuber;
}

// Closest point on one target with d(p - q)/dp; returns the squared distance.
inline double closest_one(const TargetGeom& e, const Eigen::Vector2d& p, Eigen::Vector2d* q, Eigen::Matrix2d* J) {
  if (e.kind == ElementKind::kSegment) {
    const Eigen::Vector2d d = p - e.a;
    const double t = d.dot(e.u);
    if (t <= 0.0 || e.len == 0.0) {
      *q = e.a;
      if (J) J->setIdentity();
      return d.squaredNorm();
    }
    if (t >= e.len) {
      *q = e.b;
      if (J) J->setIdentity();
      return (p - e.b).squaredNorm();
    }
    *q = e.a + t * e.u;
    if (J) {
      const Eigen::Vector2d n(-e.u.y(), e.u.x());
      *J = n * n.transpose();
    }
    const double cr = d.x() * e.u.y() - d.y() * e.u.x();
    return cr * cr;
  }
  // Circle / arc.
  const Eigen::Vector2d d = p - e.c;
  const double nd = d.norm();
  bool inside = true;
  if (e.kind == ElementKind::kArc) {
    const double ang = std::atan2(d.y(), d.x());
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
  return (p - *q).squaredNorm();
}

// Closest of the candidates; returns the squared distance (inf when there are none); *which: its index
// in cand (-1 when none).
inline double closest_of2(const std::vector<TargetGeom>& g, const int* cand, int n, const Eigen::Vector2d& p,
                          Eigen::Vector2d* q, Eigen::Matrix2d* J, int* which = nullptr) {
  if (which) *which = n > 0 ? 0 : -1;
  if (n == 1) return closest_one(g[size_t(cand[0])], p, q, J);
  double best = std::numeric_limits<double>::infinity();
  int bi = -1;
  Eigen::Vector2d qi;
  for (int i = 0; i < n; ++i) {
    const double d2 = closest_one(g[size_t(cand[i])], p, &qi, nullptr);
    if (d2 < best) {
      best = d2;
      bi = i;
      *q = qi;
    }
  }
  if (which) *which = bi;
  if (bi < 0) {
    *q = p;
    if (J) J->setZero();
    return best;
  }
  if (J) closest_one(g[size_t(cand[bi])], p, q, J);
  return best;
}

// g = sqrt(rho(s)/s) and dg/ds for the robust loss (rho(s) = s below the scale: g = 1, dg = 0).
inline void robust_scale(LossKind loss, double a, double s, double* g, double* dg) {
  *g = 1;
  *dg = 0;
  const double a2 = a * a;
  if (loss == LossKind::kNone || s < 1e-18) return;
  double rho, rho1;
  if (loss == LossKind::kHuber) {
    if (s <= a2) return;
    const double r = std::sqrt(s);
    rho = 2 * a * r - a2;
    rho1 = a / r;
  } else if (loss == LossKind::kCauchy) {
    rho = a2 * std::log1p(s / a2);
    rho1 = 1.0 / (1.0 + s / a2);
  } else {  // Geman-McClure: rho bounded by a^2, influence falling as 1/r^3 (a wall moved 3a away pulls
            // ~1/10 of what it pulls under Cauchy, whose influence falls only as 1/r)
    const double d = a2 + s;
    rho = a2 * s / d;
    rho1 = a2 * a2 / (d * d);
  }
  *g = std::sqrt(rho / s);
  *dg = (rho1 * s - rho) / (2 * (*g) * s * s);
}

// All points of one frame in one residual block (Ceres' per-block overhead dominates per-point
// blocks), one residual per point: its distance to the closest of its candidates, |p' - q(p')| (the
// paper's ||ANNF(p'), p'||). Its gradient is n^T dp'/dx with n the unit vector from q to p', so the
// normal equations equal those of the 2D residual p' - q at half the rows. The robust loss is folded in
// exactly: r~ = w g(s) d with g = sqrt(rho(s)/s), s = d^2, so r~^2 = w^2 rho(s), and dr~/dx =
// w (g + 2 s g'(s)) dd/dx.
class FrameCost : public ceres::CostFunction {
 public:
  FrameCost(const std::vector<TargetGeom>* targets, std::vector<Assignment> as, std::vector<Eigen::Vector2d> pts,
            LossKind loss, double scale, double w, bool compact)
      : targets_(targets), as_(std::move(as)), pts_(std::move(pts)), loss_(loss), a_(scale), w_(w), compact_(compact) {
    set_num_residuals(compact_ ? 4 : int(as_.size()));
    mutable_parameter_block_sizes()->push_back(3);
  }
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override {
    if (compact_) return evaluate_compact(params[0], residuals, jacobians ? jacobians[0] : nullptr);
    return evaluate_points(params, residuals, jacobians);
  }

 private:
  // The per-point form: one residual (and Jacobian row) per assignment.
  bool evaluate_points(double const* const* params, double* residuals, double** jacobians) const {
    const double* x = params[0];
    const double c = std::cos(x[2]), s = std::sin(x[2]);
    double* jac = jacobians ? jacobians[0] : nullptr;
    Eigen::Vector2d q;
    Eigen::Matrix2d J;
    for (size_t i = 0; i < as_.size(); ++i) {
      const Eigen::Vector2d& p = pts_[i];
      const double rx = c * p.x() - s * p.y(), ry = s * p.x() + c * p.y();
      const Eigen::Vector2d pw(rx + x[0], ry + x[1]);
      int which = -1;
      const double d2 = closest_of2(*targets_, as_[i].cand, as_[i].n, pw, &q, jac ? &J : nullptr, &which);
      const double d = std::sqrt(d2);
      double g, dg;
      robust_scale(loss_, a_, d2, &g, &dg);
      const double we = w_ * (which >= 0 ? double(as_[i].w[which]) : 1.0);
      residuals[i] = we * g * d;
      if (jac) {
        // n: from q to p'; at d = 0 the element's normal (segments/circles: the projection J's range).
        Eigen::Vector2d n;
        if (d > 1e-12) {
          n = (pw - q) / d;
        } else if (J.trace() < 1.5) {  // J = n n^T (interior of a segment / circle): its larger column
          n = J.col(0).squaredNorm() >= J.col(1).squaredNorm() ? J.col(0) : J.col(1);
          n.normalize();
        } else {  // on an end point: no direction
          n.setZero();
        }
        const double k = we * (g + 2 * dg * d2);
        jac[3 * i] = k * n.x();
        jac[3 * i + 1] = k * n.y();
        jac[3 * i + 2] = k * (n.x() * -ry + n.y() * rx);
      }
    }
    return true;
  }
  // The compact form (square-root information): the same cost, gradient and Gauss-Newton matrix as the
  // per-point form in 4 residuals. With J (n x 3) and r (n) of the per-point form, H = J^T J = V L V^T:
  // J~ = [L^1/2 V^T; 0], r~ = [L^-1/2 V^T J^T r; sqrt(|r|^2 - |L^-1/2 V^T J^T r|^2)] give J~^T J~ = H,
  // J~^T r~ = J^T r and |r~|^2 = |r|^2 (J^T r lies in H's range), so the trust-region steps and the
  // costs Ceres sees are those of the per-point form, without its n x 3 Jacobian and per-row work.
  bool evaluate_compact(const double* x, double* residuals, double* jac) const {
    thread_local std::vector<double> r, J;  // scratch (Ceres evaluates one block at a time per thread)
    r.resize(as_.size());
    J.resize(3 * as_.size());
    const double* xs[1] = {x};
    double* js[1] = {J.data()};
    evaluate_points(xs, r.data(), js);
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    double cost2 = 0;
    for (size_t i = 0; i < as_.size(); ++i) {
      const Eigen::Vector3d j(J[3 * i], J[3 * i + 1], J[3 * i + 2]);
      H.noalias() += j * j.transpose();
      g += r[i] * j;
      cost2 += r[i] * r[i];
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(H);
    const double lmax = std::max(es.eigenvalues().maxCoeff(), 0.0);
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> Jt = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rt = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      const double l = es.eigenvalues()[k];
      if (!(l > 1e-14 * lmax) || !(l > 0)) continue;
      const Eigen::Vector3d v = es.eigenvectors().col(k);
      const double sl = std::sqrt(l);
      Jt.row(k) = sl * v.transpose();
      rt[k] = v.dot(g) / sl;
    }
    residuals[0] = rt[0];
    residuals[1] = rt[1];
    residuals[2] = rt[2];
    residuals[3] = std::sqrt(std::max(0.0, cost2 - rt.squaredNorm()));
    if (jac) {
      for (int k = 0; k < 9; ++k) jac[k] = Jt.data()[k];
      jac[9] = jac[10] = jac[11] = 0.0;
    }
    return true;
  }

  const std::vector<TargetGeom>* targets_;
  std::vector<Assignment> as_;
  std::vector<Eigen::Vector2d> pts_;
  LossKind loss_;
  double a_, w_;
  bool compact_;
};

}  // namespace

double closest_of(const std::vector<TargetGeom>& targets, const int* cand, int n, const Eigen::Vector2d& p,
                  Eigen::Vector2d* q, Eigen::Matrix2d* dr_dp) {
  return std::sqrt(closest_of2(targets, cand, n, p, q, dr_dp));
}

void assign(const NearestLookup& lookup, const FeatureFrame& f, const Pose2& x, const AssignOptions& o,
            std::vector<Assignment>* out) {
  out->clear();
  const auto& g = lookup.geometry();
  const bool groups = o.group_rule && lookup.element_targets();
  const int maxc = std::clamp(o.max_candidates, 1, kMaxCandidates);
  const size_t stride = size_t(std::max(1, o.stride));
  const double g2 = o.gate_m * o.gate_m;
  struct GroupPoint {
    int32_t group;
    int point;
    Eigen::Vector2d pw;
    Assignment a;
  };
  std::vector<GroupPoint> gps;
  Eigen::Vector2d q;
  const std::vector<float>* ew = lookup.element_targets() ? o.element_weight : nullptr;
  // Weights of the candidates; those of weight <= 0 are taken out.
  auto weigh = [ew](Assignment* a) {
    if (!ew) return;
    int k = 0;
    for (int i = 0; i < a->n; ++i) {
      const size_t id = size_t(a->cand[i]);
      const float w = id < ew->size() ? (*ew)[id] : 1.0f;
      if (!(w > 0)) continue;
      a->cand[k] = a->cand[i];
      a->w[k] = w;
      ++k;
    }
    a->n = k;
  };
  const double c = std::cos(x.yaw), s = std::sin(x.yaw);
  out->reserve(f.points.size() / stride + 1);
  for (size_t i = 0; i < f.points.size(); i += stride) {
    const auto& fp = f.points[i];
    const Eigen::Vector2d pw(c * fp.p.x() - s * fp.p.y() + x.x, s * fp.p.x() + c * fp.p.y() + x.y);
    Assignment a;
    a.point = int(i);
    a.n = lookup.candidates(pw, a.cand, maxc);
    weigh(&a);
    if (a.n <= 0) continue;
    if (groups && fp.group >= 0) {
      gps.push_back({fp.group, int(i), pw, a});
      continue;
    }
    if (closest_of2(g, a.cand, a.n, pw, &q, nullptr) <= g2) out->push_back(a);
  }
  if (gps.empty()) return;
  // One element per group: the candidate (from the union of its points' candidates) with the smallest
  // truncated sum of squared distances over the group's points; ties to the first found.
  std::stable_sort(gps.begin(), gps.end(), [](const GroupPoint& a, const GroupPoint& b) { return a.group < b.group; });
  std::vector<int> cands;
  const size_t n_single = out->size();
  for (size_t b = 0; b < gps.size();) {
    size_t e = b;
    cands.clear();
    for (; e < gps.size() && gps[e].group == gps[b].group; ++e)
      for (int k = 0; k < gps[e].a.n; ++k)
        if (std::find(cands.begin(), cands.end(), gps[e].a.cand[k]) == cands.end()) cands.push_back(gps[e].a.cand[k]);
    int best = -1;
    double best_cost = std::numeric_limits<double>::infinity();
    for (int el : cands) {
      double cost = 0;
      for (size_t i = b; i < e && cost < best_cost; ++i) cost += std::min(closest_one(g[size_t(el)], gps[i].pw, &q, nullptr), g2);
      if (cost < best_cost) {
        best_cost = cost;
        best = el;
      }
    }
    if (best >= 0)
      for (size_t i = b; i < e; ++i) {
        if (closest_one(g[size_t(best)], gps[i].pw, &q, nullptr) > g2) continue;
        Assignment a;
        a.point = gps[i].point;
        a.n = 1;
        a.cand[0] = best;
        if (ew && size_t(best) < ew->size()) a.w[0] = (*ew)[size_t(best)];
        out->push_back(a);
      }
    b = e;
  }
  // Point order (deterministic and cache-friendly for the residuals).
  if (out->size() > n_single)
    std::sort(out->begin(), out->end(), [](const Assignment& a, const Assignment& b) { return a.point < b.point; });
}

void add_frame_term(ceres::Problem* problem, double* pose, const NearestLookup& lookup, const FeatureFrame& f,
                    const std::vector<Assignment>& as, const std::string& loss, double scale, double weight, bool compact) {
  if (as.empty()) return;
  std::vector<Eigen::Vector2d> pts;
  pts.reserve(as.size());
  for (const auto& a : as) pts.push_back(f.points[size_t(a.point)].p);
  problem->AddResidualBlock(
      new FrameCost(&lookup.geometry(), as, std::move(pts), loss_kind(loss, scale), scale, weight, compact), nullptr, pose);
}

Eigen::Matrix3d frame_information(const NearestLookup& lookup, const FeatureFrame& f, const std::vector<Assignment>& as,
                                  const Pose2& x, const std::string& loss, double scale) {
  const auto& g = lookup.geometry();
  const LossKind lk = loss_kind(loss, scale);
  const double c = std::cos(x.yaw), s = std::sin(x.yaw);
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  Eigen::Vector2d q;
  Eigen::Matrix2d J;
  for (const auto& a : as) {
    const Eigen::Vector2d& p = f.points[size_t(a.point)].p;
    const double rx = c * p.x() - s * p.y(), ry = s * p.x() + c * p.y();
    const Eigen::Vector2d pw(rx + x.x, ry + x.y);
    int which = -1;
    closest_of2(g, a.cand, a.n, pw, &q, &J, &which);
    const double we = which >= 0 ? double(a.w[which]) : 1.0;
    Eigen::Matrix<double, 2, 3> Jr;
    Jr.leftCols<2>() = J;
    Jr.col(2) = J * Eigen::Vector2d(-ry, rx);
    double gs, dg;
    robust_scale(lk, scale, (pw - q).squaredNorm(), &gs, &dg);
    H += (we * we * gs * gs) * Jr.transpose() * Jr;
  }
  return H;
}

FitQuality evaluate_fit(const NearestLookup& lookup, const FeatureFrame& f, const Pose2& x, double inlier_m, int stride) {
  FitQuality fq;
  const auto& g = lookup.geometry();
  const size_t st = size_t(std::max(1, stride));
  double sum2 = 0;
  int cand[kMaxCandidates];
  Eigen::Vector2d cp;
  const double in2 = inlier_m * inlier_m;
  for (size_t i = 0; i < f.points.size(); i += st) {
    ++fq.num_points;
    const Eigen::Vector2d pw = transform(x, f.points[i].p);
    const int n = lookup.candidates(pw, cand, kMaxCandidates);
    const double d2 = n > 0 ? closest_of2(g, cand, n, pw, &cp, nullptr) : std::numeric_limits<double>::infinity();
    if (d2 <= in2) {
      ++fq.num_inliers;
      sum2 += d2;
    }
  }
  fq.inlier_ratio = fq.num_points > 0 ? double(fq.num_inliers) / fq.num_points : 0.0;
  fq.rms_m = fq.num_inliers > 0 ? std::sqrt(sum2 / fq.num_inliers) : 0.0;
  return fq;
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

}  // namespace fploc::matcher