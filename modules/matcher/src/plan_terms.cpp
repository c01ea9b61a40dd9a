#include "fploc/matcher/plan_terms.h"

#include "askew_faces.h"

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

// rho(s) and rho'(s) of the robust loss (s = r^2; rho(s) = s for none).
inline void robust_rho(LossKind loss, double a, double s, double* rho, double* rho1) {
  const double a2 = a * a;
  switch (loss) {
    case LossKind::kNone: *rho = s; *rho1 = 1; return;
    case LossKind::kHuber:
      if (s <= a2) { *rho = s; *rho1 = 1; return; }
      *rho = 2 * a * std::sqrt(s) - a2;
      *rho1 = a / std::sqrt(s);
      return;
    case LossKind::kCauchy: *rho = a2 * std::log1p(s / a2); *rho1 = 1.0 / (1.0 + s / a2); return;
    case LossKind::kGemanMcClure: {
      const double d = a2 + s;
      *rho = a2 * s / d;
      *rho1 = a2 * a2 / (d * d);
      return;
    }
  }
}

// rho'(s) alone (IRLS weights).
inline double robust_weight(LossKind loss, double a, double s) {
  const double a2 = a * a;
  switch (loss) {
    case LossKind::kNone: return 1;
    case LossKind::kHuber: return s <= a2 ? 1.0 : a / std::sqrt(s);
    case LossKind::kCauchy: return 1.0 / (1.0 + s / a2);
    case LossKind::kGemanMcClure: {
      const double d = a2 + s;
      return a2 * a2 / (d * d);
    }
  }
  return 1;
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
            LossKind loss, double scale, double w, bool compact, const AsBuiltModel* ab = nullptr)
      : targets_(targets), as_(std::move(as)), pts_(std::move(pts)), loss_(loss), a_(scale), w_(w),
        compact_(compact || (ab && ab->on())) {
    if (ab && ab->on()) ab_ = *ab;
    set_num_residuals(compact_ ? 4 : int(as_.size()));
    mutable_parameter_block_sizes()->push_back(3);
  }
  // As-built model: the robust weights of the points and of the offsets, from the offsets solved at x (IRLS),
  // fixed for this term's solve (the look-up rounds refresh them), so the term is a weighted least-squares
  // cost that the offsets enter linearly and are eliminated from exactly. keep_information: the scale that
  // gives the term the plain term's translational information at x.
  void prepare(const double* x) {
    if (!ab_.on()) return;
    Eigen::Matrix3d Hp, Ha;
    Eigen::Vector3d g;
    double c2;
    accumulate(x, true, &Ha, &g, &c2);
    prepared_ = true;
    if (ab_.per_wall) aggregate_walls(x);
    if (!ab_.keep_information) return;
    accumulate(x, false, &Hp, &g, &c2);
    const double tp = Hp(0, 0) + Hp(1, 1), ta = Ha(0, 0) + Ha(1, 1);
    if (tp > 0 && ta > 0) kappa_ = tp / ta;
  }
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override {
    if (compact_) return evaluate_compact(params[0], residuals, jacobians ? jacobians[0] : nullptr);
    return evaluate_points(params, residuals, jacobians);
  }

 private:
  // A point of the as-built model: on element `el`, signed offset r (along the segment's left normal, or
  // radially), r = U . (the element's offsets) + noise, d r / d x = j; w2 its squared weight, pw2 that without
  // its sampling weight (Assignment::sw), which sets its element's offset prior.
  struct Obs {
    int el, i;          // element, assignment
    double r, w2, pw2;
    Eigen::Vector2d U;  // d r / d (o_a, o_b) (segments) or d r / d (centre offset) (circles), up to sign
    Eigen::Vector3d j;
  };
  // Point i at pose x (c, s: cos, sin of the yaw): its folded robust residual and Jacobian row (plain), or,
  // with ob and the point on a segment's interior, its Obs (returns false: no plain row).
  bool row(size_t i, const double* x, double c, double s, double* res, double* jrow, Obs* ob) const {
    const Eigen::Vector2d& p = pts_[i];
    const double rx = c * p.x() - s * p.y(), ry = s * p.x() + c * p.y();
    const Eigen::Vector2d pw(rx + x[0], ry + x[1]);
    int which = -1;
    Eigen::Vector2d q;
    Eigen::Matrix2d J;
    const double d2 = closest_of2(*targets_, as_[i].cand, as_[i].n, pw, &q, jrow || ob ? &J : nullptr, &which);
    const double we_el = w_ * (which >= 0 ? double(as_[i].w[which]) : 1.0);
    const double we = we_el * double(as_[i].sw);
    if (ob && which >= 0) {
      // Segments: the signed offset from its line (also a little past an end: the wall as built may go on),
      // U = (1 - t, t) with t clamped to the segment. Circles and arcs (points within the arc): the signed
      // radial offset, U = the unit direction from the centre (a pillar displaced by its centre's offset).
      const TargetGeom& e = (*targets_)[size_t(as_[i].cand[which])];
      if (e.kind == ElementKind::kSegment && e.len > 0) {
        const Eigen::Vector2d n(-e.u.y(), e.u.x());
        ob->el = as_[i].cand[which];
        ob->r = (pw - e.a).dot(n);
        const double t = std::clamp((pw - e.a).dot(e.u) / e.len, 0.0, 1.0);
        ob->U = Eigen::Vector2d(1 - t, t);
        ob->w2 = we * we;
        ob->pw2 = we_el * we_el;
        ob->j = Eigen::Vector3d(n.x(), n.y(), n.x() * -ry + n.y() * rx);
        return false;
      }
      const Eigen::Vector2d dc = pw - e.c;
      const double nd = dc.norm();
      if (e.kind != ElementKind::kSegment && nd > 1e-9 && J.trace() < 1.5) {
        const Eigen::Vector2d u = dc / nd;
        ob->el = as_[i].cand[which];
        ob->r = nd - e.r;
        ob->U = u;
        ob->w2 = we * we;
        ob->pw2 = we_el * we_el;
        ob->j = Eigen::Vector3d(u.x(), u.y(), u.x() * -ry + u.y() * rx);
        return false;
      }
    }
    const double d = std::sqrt(d2);
    double g, dg;
    robust_scale(loss_, a_, d2, &g, &dg);
    *res = we * g * d;
    if (jrow) {
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
      jrow[0] = k * n.x();
      jrow[1] = k * n.y();
      jrow[2] = k * (n.x() * -ry + n.y() * rx);
    }
    return true;
  }
  // The per-point form: one residual (and Jacobian row) per assignment.
  bool evaluate_points(double const* const* params, double* residuals, double** jacobians) const {
    const double* x = params[0];
    const double c = std::cos(x[2]), s = std::sin(x[2]);
    double* jac = jacobians ? jacobians[0] : nullptr;
    for (size_t i = 0; i < as_.size(); ++i) row(i, x, c, s, residuals + i, jac ? jac + 3 * i : nullptr, nullptr);
    return true;
  }
  // Per wall instead of per point (the weights prepare() fixed make this exact but for U): a point of a single
  // candidate segment (the PCA group rule gives every grouped point one) has r = n . (R p + t - a) = c alpha +
  // s beta + k with alpha = n . p, beta = n . perp(p), k = n . t - n . a, and Jacobian row j = (n, c beta - s alpha),
  // so every sum the elimination needs (A, b, B, r^2, H, g) is a polynomial of degree <= 2 in (c, s, k) whose
  // coefficients are weighted moments of the wall's points. They are summed once here; an evaluation then costs
  // one pass over the walls instead of one closest-point query per point. U = (1 - t, t) (where along the wall
  // the point lies) is taken at the term's pose: within one solve a point slides along its wall by the pose's
  // change (cm), a change of U of cm / wall length; the look-up rounds re-build it. Points with several
  // candidates (the closest is chosen per evaluation), circles, arcs and plain rows stay per point (dyn_).
  struct WallAgg {
    int el = -1;
    double w2 = 0, na = 0;
    Eigen::Vector2d n = Eigen::Vector2d::Zero();
    double S = 0, Sa = 0, Sb = 0, Saa = 0, Sab = 0, Sbb = 0;  // sum W, W alpha, W beta, W alpha^2, ...
    double A00 = 0, A01 = 0, A11 = 0;                          // sum W U U^T
    Eigen::Vector2d SU = Eigen::Vector2d::Zero(), SUa = Eigen::Vector2d::Zero(), SUb = Eigen::Vector2d::Zero();
  };
  static constexpr double kFreezeMargin = 0.10;
  void aggregate_walls(const double* x) {
    walls_.clear();
    dyn_.clear();
    thread_local std::vector<int> slot;
    if (slot.size() < targets_->size()) slot.assign(targets_->size(), -1);
    const double c = std::cos(x[2]), s = std::sin(x[2]);
    for (size_t i = 0; i < as_.size(); ++i) {
      const Eigen::Vector2d& p = pts_[i];
      const Eigen::Vector2d pw(c * p.x() - s * p.y() + x[0], s * p.x() + c * p.y() + x[1]);
      // The candidate the point is on: its only one, or the closest when the next is >= kFreezeMargin farther
      // (a point 10 cm nearer one wall than any other stays with it while the pose moves by a few cm).
      int k_on = as_[i].n == 1 ? 0 : -1;
      if (as_[i].n > 1) {
        double d1 = std::numeric_limits<double>::infinity(), d2 = d1;
        int k1 = -1;
        Eigen::Vector2d q;
        for (int k = 0; k < as_[i].n; ++k) {
          const double d = std::sqrt(closest_one((*targets_)[size_t(as_[i].cand[k])], pw, &q, nullptr));
          if (d < d1) {
            d2 = d1;
            d1 = d;
            k1 = k;
          } else if (d < d2) {
            d2 = d;
          }
        }
        if (k1 >= 0 && d2 - d1 >= kFreezeMargin) k_on = k1;
      }
      const TargetGeom* e = k_on >= 0 ? &(*targets_)[size_t(as_[i].cand[k_on])] : nullptr;
      if (!e || e->kind != ElementKind::kSegment || !(e->len > 0)) {
        dyn_.push_back(int(i));
        continue;
      }
      const int el = as_[i].cand[k_on];
      if (slot[size_t(el)] < 0) {
        slot[size_t(el)] = int(walls_.size());
        WallAgg w;
        w.el = el;
        w.n = Eigen::Vector2d(-e->u.y(), e->u.x());
        w.na = w.n.dot(e->a);
        const double we = w_ * double(as_[i].w[k_on]);  // the offset prior: without the sampling weight
        w.w2 = we * we;
        walls_.push_back(w);
      }
      WallAgg& w = walls_[size_t(slot[size_t(el)])];
      const double t = std::clamp((pw - e->a).dot(e->u) / e->len, 0.0, 1.0);
      const Eigen::Vector2d U(1 - t, t);
      const double we = w_ * double(as_[i].w[k_on]) * double(as_[i].sw);
      const double W = we * we * double(point_w_[i]);
      const double al = w.n.dot(p), be = w.n.x() * -p.y() + w.n.y() * p.x();
      w.S += W;
      w.Sa += W * al;
      w.Sb += W * be;
      w.Saa += W * al * al;
      w.Sab += W * al * be;
      w.Sbb += W * be * be;
      w.A00 += W * U[0] * U[0];
      w.A01 += W * U[0] * U[1];
      w.A11 += W * U[1] * U[1];
      w.SU += W * U;
      w.SUa += (W * al) * U;
      w.SUb += (W * be) * U;
    }
    for (const WallAgg& w : walls_) slot[size_t(w.el)] = -1;
    std::sort(walls_.begin(), walls_.end(), [](const WallAgg& a, const WallAgg& b) { return a.el < b.el; });
    aggregated_ = true;
  }
  // accumulate() of the as-built model with the weights prepare() fixed: the walls' moments (aggregate_walls)
  // and one pass over the other points, summed per element (no grouping), then each element's offsets
  // eliminated.
  void accumulate_prepared(const double* x, Eigen::Matrix3d* H, Eigen::Vector3d* g, double* cost2) const {
    struct ElemAcc {
      double a00 = 0, a01 = 0, a11 = 0, b0 = 0, b1 = 0, rr = 0, w2 = 0;
      Eigen::Matrix<double, 2, 3> B = Eigen::Matrix<double, 2, 3>::Zero();
      bool used = false;
    };
    thread_local std::vector<ElemAcc> acc;
    thread_local std::vector<int> used;
    if (acc.size() < targets_->size()) acc.resize(targets_->size());
    used.clear();
    const double c = std::cos(x[2]), s = std::sin(x[2]);
    const double cc = c * c, cs = c * s, ss = s * s;
    for (const WallAgg& w : walls_) {
      ElemAcc& a = acc[size_t(w.el)];
      a.used = true;
      a.w2 = w.w2;
      used.push_back(w.el);
      const double k = w.n.x() * x[0] + w.n.y() * x[1] - w.na;
      const double ra = c * w.Sa + s * w.Sb;            // sum W (c alpha + s beta)
      const double rj = c * w.Sb - s * w.Sa;            // sum W (c beta - s alpha): sum W j_yaw
      const double sr = ra + k * w.S;                   // sum W r
      a.a00 += w.A00;
      a.a01 += w.A01;
      a.a11 += w.A11;
      const Eigen::Vector2d bu = c * w.SUa + s * w.SUb + k * w.SU;  // sum W r U
      a.b0 += bu[0];
      a.b1 += bu[1];
      a.rr += cc * w.Saa + 2 * cs * w.Sab + ss * w.Sbb + 2 * k * ra + k * k * w.S;
      const Eigen::Vector2d ju = c * w.SUb - s * w.SUa;  // sum W U j_yaw
      a.B(0, 0) += w.SU[0] * w.n.x();
      a.B(0, 1) += w.SU[0] * w.n.y();
      a.B(0, 2) += ju[0];
      a.B(1, 0) += w.SU[1] * w.n.x();
      a.B(1, 1) += w.SU[1] * w.n.y();
      a.B(1, 2) += ju[1];
      H->topLeftCorner<2, 2>().noalias() += w.S * w.n * w.n.transpose();
      H->block<2, 1>(0, 2) += rj * w.n;
      H->block<1, 2>(2, 0) += rj * w.n.transpose();
      (*H)(2, 2) += cc * w.Sbb - 2 * cs * w.Sab + ss * w.Saa;
      g->head<2>() += sr * w.n;
      (*g)[2] += cc * w.Sab - cs * w.Saa + cs * w.Sbb - ss * w.Sab + k * rj;
    }
    Obs ob;
    double res, jr[3];
    const size_t n_dyn = aggregated_ ? dyn_.size() : as_.size();
    for (size_t di = 0; di < n_dyn; ++di) {
      const size_t i = aggregated_ ? size_t(dyn_[di]) : di;
      if (!row(i, x, c, s, &res, jr, &ob)) {
        ElemAcc& a = acc[size_t(ob.el)];
        if (!a.used) {
          a.used = true;
          a.w2 = ob.pw2;
          used.push_back(ob.el);
        }
        const double w = ob.w2 * point_w_[i];
        const double u0 = ob.U[0], u1 = ob.U[1];
        a.a00 += w * u0 * u0;
        a.a01 += w * u0 * u1;
        a.a11 += w * u1 * u1;
        a.b0 += w * ob.r * u0;
        a.b1 += w * ob.r * u1;
        a.rr += w * ob.r * ob.r;
        a.B.row(0) += (w * u0) * ob.j.transpose();
        a.B.row(1) += (w * u1) * ob.j.transpose();
        H->noalias() += w * ob.j * ob.j.transpose();
        *g += (w * ob.r) * ob.j;
        continue;
      }
      const Eigen::Vector3d j(jr[0], jr[1], jr[2]);
      H->noalias() += j * j.transpose();
      *g += res * j;
      *cost2 += res * res;
    }
    const double lam0 = (ab_.point_sigma_m / ab_.sigma_m) * (ab_.point_sigma_m / ab_.sigma_m);
    for (int el : used) {
      ElemAcc& a = acc[size_t(el)];
      Eigen::Vector2d lw(1, 1);
      const auto it = std::lower_bound(offset_w_.begin(), offset_w_.end(), el,
                                       [](const std::pair<int, Eigen::Vector2d>& p, int v) { return p.first < v; });
      if (it != offset_w_.end() && it->first == el) lw = it->second;
      lw *= lam0 * a.w2;
      // The 2x2 block A = [a00 + lw0, a01; a01, a11 + lw1] (positive definite: lw > 0) inverted in closed form.
      const double A00 = a.a00 + lw[0], A11 = a.a11 + lw[1], A01 = a.a01;
      const double det = A00 * A11 - A01 * A01;
      Eigen::Matrix2d Ai;
      if (det > 1e-300 && A00 > 0) {
        Ai << A11 / det, -A01 / det, -A01 / det, A00 / det;
      } else {
        Eigen::Matrix2d A;
        A << A00, A01, A01, A11;
        Ai = A.ldlt().solve(Eigen::Matrix2d::Identity());
      }
      const Eigen::Vector2d bb(a.b0, a.b1);
      const Eigen::Vector2d o = Ai * bb;
      const Eigen::Matrix<double, 2, 3> AiB = Ai * a.B;
      H->noalias() -= a.B.transpose() * AiB;
      *g -= a.B.transpose() * o;
      *cost2 += a.rr - bb.dot(o);
      a = ElemAcc();
    }
  }
  // Whether the points of one element (first..last, their robust weights in point_w_) lie on a line askew to
  // it beyond what a wall standing off its drawn place can be (AsBuiltModel::max_askew_m): their end offsets by
  // weighted least squares without the prior, o_f, and the difference d = o_b - o_a (the line's turn against
  // the wall, over the wall's length), against 2 max_askew_m^2 + its own variance (point_sigma_m^2 v^T A^-1 v).
  // A metre's prior keeps a line seen over a short piece of its wall finite; its turn is then uncertain by about
  // a metre, and so plausible. Askew lines are faces, partitions and clutter, not a displaced wall.
  bool askew_to_its_wall(const Obs* first, const Obs* last, double w2max) const {
    const double P = ab_.max_askew_m;
    constexpr double kChi2Dof1P99 = 6.63;  // the 99 % point of chi-square with 1 degree of freedom
    constexpr double kRidgeM = 1.0;        // the prior that keeps an ill-determined end finite
    const double ps2 = ab_.point_sigma_m * ab_.point_sigma_m;
    Eigen::Matrix2d A = (ps2 / (kRidgeM * kRidgeM)) * w2max * Eigen::Matrix2d::Identity();
    Eigen::Vector2d bb = Eigen::Vector2d::Zero();
    for (const Obs* o = first; o != last; ++o) {
      const double w = o->w2 * point_w_[size_t(o->i)];
      A.noalias() += w * o->U * o->U.transpose();
      bb += w * o->r * o->U;
    }
    const Eigen::Matrix2d Ai = A.inverse();
    const Eigen::Vector2d v(-1, 1);
    const double d = v.dot(Ai * bb);
    return d * d > kChi2Dof1P99 * (2 * P * P + ps2 * v.dot(Ai * v));
  }
  // Gauss-Newton matrix H, gradient g and cost (sum of squared residuals) of the frame at x: the per-point
  // form, or (as_built) the as-built model's with the segments' end offsets eliminated.
  void accumulate(const double* x, bool as_built, Eigen::Matrix3d* H, Eigen::Vector3d* g, double* cost2) const {
    thread_local std::vector<Obs> obs;
    obs.clear();
    H->setZero();
    g->setZero();
    *cost2 = 0;
    const double c = std::cos(x[2]), s = std::sin(x[2]);
    Obs ob;
    double res, jr[3];
    if (as_built && prepared_) {
      accumulate_prepared(x, H, g, cost2);
      return;
    }
    for (size_t i = 0; i < as_.size(); ++i) {
      if (!row(i, x, c, s, &res, jr, as_built ? &ob : nullptr)) {
        ob.i = int(i);
        obs.push_back(ob);
        continue;
      }
      const Eigen::Vector3d j(jr[0], jr[1], jr[2]);
      H->noalias() += j * j.transpose();
      *g += res * j;
      *cost2 += res * res;
    }
    if (obs.empty()) return;
    // Group by element: counting sort on the element id (stable: point order within an element).
    thread_local std::vector<Obs> sorted;
    thread_local std::vector<int> start;
    start.assign(targets_->size() + 1, 0);
    for (const Obs& o : obs) ++start[size_t(o.el) + 1];
    for (size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
    sorted.resize(obs.size());
    for (const Obs& o : obs) sorted[size_t(start[size_t(o.el)]++)] = o;
    const double lam0 = (ab_.point_sigma_m / ab_.sigma_m) * (ab_.point_sigma_m / ab_.sigma_m);
    const double ce = ab_.loss_scale_m, ce2 = ce * ce;
    auto rho1_e = [&](double o2) { return ce <= 0 ? 1.0 : 1.0 / (1.0 + o2 / ce2); };
    if (!prepared_) {
      point_w_.assign(as_.size(), 1.0f);
      offset_w_.clear();
    }
    size_t wi = 0;
    for (size_t b = 0; b < sorted.size();) {
      size_t e = b;
      const int el = sorted[b].el;
      double w2max = 0;
      for (; e < sorted.size() && sorted[e].el == el; ++e) w2max = std::max(w2max, sorted[e].pw2);
      const double lam = lam0 * w2max;
      Eigen::Vector2d lw(lam, lam);  // the offsets' prior weights
      if (!prepared_) {
        // IRLS at the term's pose: the offsets under the points' loss and their own; then the weights.
        Eigen::Vector2d o = Eigen::Vector2d::Zero();
        for (int it = 0; it < 5; ++it) {
          Eigen::Matrix2d A;
          A << lam * rho1_e(o[0] * o[0]), 0, 0, lam * rho1_e(o[1] * o[1]);
          Eigen::Vector2d bb = Eigen::Vector2d::Zero();
          for (size_t k = b; k < e; ++k) {
            const Eigen::Vector2d& U = sorted[k].U;
            const double ee = sorted[k].r - U.dot(o);
            const double w = sorted[k].w2 * robust_weight(loss_, a_, ee * ee);
            A.noalias() += w * U * U.transpose();
            bb += w * sorted[k].r * U;
          }
          o = A.ldlt().solve(bb);
        }
        double sw = 0, swe = 0;
        for (size_t k = b; k < e; ++k) {
          const double ee = sorted[k].r - sorted[k].U.dot(o);
          const double rw = robust_weight(loss_, a_, ee * ee);
          point_w_[size_t(sorted[k].i)] = float(rw);
          sw += sorted[k].w2 * rw;
          swe += sorted[k].w2 * rw * ee * ee;
        }
        // Points that do not lie on one line with their wall (AsBuiltModel::max_spread_sigmas): the element's
        // share, its points' weights and its offsets' prior alike, scaled down by (limit / spread)^2; with the gate
        // on (max_askew_m > 0), only when their own line is askew to the wall.
        double share = 1;
        const double lim = ab_.max_spread_sigmas * ab_.point_sigma_m;
        if (lim > 0 && sw > 0 && swe > lim * lim * sw &&
            (!(ab_.max_askew_m > 0) || askew_to_its_wall(sorted.data() + b, sorted.data() + e, w2max))) {
          share = lim * lim * sw / swe;
          for (size_t k = b; k < e; ++k) point_w_[size_t(sorted[k].i)] *= float(share);
        }
        offset_w_.emplace_back(el, share * Eigen::Vector2d(rho1_e(o[0] * o[0]), rho1_e(o[1] * o[1])));
        lw = lam * offset_w_.back().second;
      } else {
        while (wi < offset_w_.size() && offset_w_[wi].first < el) ++wi;
        if (wi < offset_w_.size() && offset_w_[wi].first == el) lw = lam * offset_w_[wi].second;
      }
      // Weighted least squares in (x, o) with the weights fixed: o = A^-1 b eliminated exactly.
      Eigen::Matrix2d A;
      A << lw[0], 0, 0, lw[1];
      Eigen::Vector2d bb = Eigen::Vector2d::Zero();
      Eigen::Matrix<double, 2, 3> B = Eigen::Matrix<double, 2, 3>::Zero();
      double rr = 0;
      for (size_t k = b; k < e; ++k) {
        const Eigen::Vector2d& U = sorted[k].U;
        const double w = sorted[k].w2 * point_w_[size_t(sorted[k].i)];
        A.noalias() += w * U * U.transpose();
        B.noalias() += w * U * sorted[k].j.transpose();
        bb += w * sorted[k].r * U;
        H->noalias() += w * sorted[k].j * sorted[k].j.transpose();
        *g += w * sorted[k].r * sorted[k].j;
        rr += w * sorted[k].r * sorted[k].r;
      }
      const Eigen::LDLT<Eigen::Matrix2d> ldlt(A);
      const Eigen::Vector2d o = ldlt.solve(bb);
      H->noalias() -= B.transpose() * ldlt.solve(B);
      *g -= B.transpose() * o;  // sum w e j with e = r - U o
      *cost2 += rr - bb.dot(o);  // sum w e^2 + o^T L o at the optimal o
      b = e;
    }
  }
  // The compact form (square-root information): the same cost, gradient and Gauss-Newton matrix as the
  // per-point form in 4 residuals. With J (n x 3) and r (n) of the per-point form, H = J^T J = V L V^T:
  // J~ = [L^1/2 V^T; 0], r~ = [L^-1/2 V^T J^T r; sqrt(|r|^2 - |L^-1/2 V^T J^T r|^2)] give J~^T J~ = H,
  // J~^T r~ = J^T r and |r~|^2 = |r|^2 (J^T r lies in H's range), so the trust-region steps and the
  // costs Ceres sees are those of the per-point form, without its n x 3 Jacobian and per-row work.
  bool evaluate_compact(const double* x, double* residuals, double* jac) const {
    Eigen::Matrix3d H;
    Eigen::Vector3d g;
    double cost2;
    accumulate(x, ab_.on(), &H, &g, &cost2);
    if (kappa_ != 1.0) {
      H *= kappa_;
      g *= kappa_;
      cost2 *= kappa_;
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
  AsBuiltModel ab_;  // off unless given
  double kappa_ = 1.0;
  // As-built model, fixed by prepare(): each assignment's robust weight, each element's offsets' weights
  // (by element id; an element not met there keeps weight 1).
  bool prepared_ = false;
  // aggregate_walls(): the walls' moments (sorted by element) and the assignments evaluated per point.
  bool aggregated_ = false;
  std::vector<WallAgg> walls_;
  std::vector<int> dyn_;
  mutable std::vector<float> point_w_;
  mutable std::vector<std::pair<int, Eigen::Vector2d>> offset_w_;
};

}  // namespace

double closest_of(const std::vector<TargetGeom>& targets, const int* cand, int n, const Eigen::Vector2d& p,
                  Eigen::Vector2d* q, Eigen::Matrix2d* dr_dp) {
  return std::sqrt(closest_of2(targets, cand, n, p, q, dr_dp));
}

namespace {
// The candidates of weight <= 0 (AssignOptions::element_weight) taken out, the others' weights set.
void weigh(const std::vector<float>* ew, Assignment* a) {
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
}

inline Eigen::Vector2d to_world(const Pose2& x, double c, double s, const Eigen::Vector2d& p) {
  return Eigen::Vector2d(c * p.x() - s * p.y() + x.x, s * p.x() + c * p.y() + x.y);
}
}  // namespace


void select_points(const NearestLookup& lookup, const FeatureFrame& f, const Pose2& x, const AssignOptions& o,
                   std::vector<SampledPoint>* out) {
  out->clear();
  const size_t n = f.points.size();
  const size_t stride = size_t(std::max(1, o.stride));
  const bool budget = o.element_quota > 0 && stride > 1 && lookup.element_targets();
  const bool askew_rule = o.askew_max_m > 0 && lookup.element_targets();
  if (!budget && !askew_rule) {
    out->reserve(n / stride + 1);
    for (size_t i = 0; i < n; i += stride) out->push_back({int(i), 1.0f});
    return;
  }
  // Per-element budget: every point looked up, its closest candidate within the gate counted per element; an
  // element with at most element_quota points keeps them all (sampling weight 1/sqrt(stride): each stands for
  // itself, a stride-th point for stride points), the others every stride-th point. Askew faces
  // (askew_max_m): the points of a run along an element that lies on a line askew to it are left out.
  const auto& g = lookup.geometry();
  const std::vector<float>* ew = o.element_weight;
  const int maxc = std::clamp(o.max_candidates, 1, kMaxCandidates);
  const double g2 = o.gate_m * o.gate_m;
  const double c = std::cos(x.yaw), s = std::sin(x.yaw);
  thread_local std::vector<int> on, count;
  thread_local std::vector<char> drop;
  on.assign(n, -1);
  if (count.size() < g.size()) count.resize(g.size(), 0);
  Assignment a;
  Eigen::Vector2d q;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d pw = to_world(x, c, s, f.points[i].p);
    a.n = lookup.candidates(pw, a.cand, maxc);
    weigh(ew, &a);
    if (a.n <= 0) continue;
    int which = -1;
    if (closest_of2(g, a.cand, a.n, pw, &q, nullptr, &which) <= g2 && which >= 0) {
      on[i] = a.cand[which];
      ++count[size_t(on[i])];
    }
  }
  if (askew_rule) askew_points(g, f, x, on, o, &drop);
  const float rare_w = float(1.0 / std::sqrt(double(stride)));
  out->reserve(n / stride + 1);
  for (size_t i = 0; i < n; ++i) {
    if (askew_rule && drop[i]) continue;
    const bool rare = budget && on[i] >= 0 && count[size_t(on[i])] <= o.element_quota;
    if (rare) out->push_back({int(i), rare_w});
    else if (i % stride == 0) out->push_back({int(i), 1.0f});
  }
  for (size_t i = 0; i < n; ++i)
    if (on[i] >= 0) count[size_t(on[i])] = 0;
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
  const double c = std::cos(x.yaw), s = std::sin(x.yaw);
  auto one = [&](size_t i, float sw) {
    const Eigen::Vector2d pw = to_world(x, c, s, f.points[i].p);
    Assignment a;
    a.point = int(i);
    a.sw = sw;
    a.n = lookup.candidates(pw, a.cand, maxc);
    weigh(ew, &a);
    if (a.n <= 0) return;
    // The grouped points wait for their group's element.
    if (groups && f.points[i].group >= 0) {
      gps.push_back({f.points[i].group, int(i), pw, a});
      return;
    }
    if (closest_of2(g, a.cand, a.n, pw, &q, nullptr) <= g2) out->push_back(a);
  };
  const std::vector<SampledPoint>* sel = o.points;
  thread_local std::vector<SampledPoint> own;
  if (!sel && selects_per_element(lookup, o)) {
    select_points(lookup, f, x, o, &own);
    sel = &own;
  }
  if (sel) {
    out->reserve(sel->size());
    for (const SampledPoint& sp : *sel)
      if (sp.point >= 0 && size_t(sp.point) < f.points.size()) one(size_t(sp.point), sp.sw);
  } else {
    out->reserve(f.points.size() / stride + 1);
    for (size_t i = 0; i < f.points.size(); i += stride) one(i, 1.0f);
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
        a.sw = gps[i].a.sw;
        out->push_back(a);
      }
    b = e;
  }
  // Point order (deterministic and cache-friendly for the residuals).
  if (out->size() > n_single)
    std::sort(out->begin(), out->end(), [](const Assignment& a, const Assignment& b) { return a.point < b.point; });
}

namespace {
FrameCost* new_frame_cost(const double* pose, const NearestLookup& lookup, const FeatureFrame& f,
                          const std::vector<Assignment>& as, const std::string& loss, double scale, double weight,
                          bool compact, const AsBuiltModel* as_built) {
  std::vector<Eigen::Vector2d> pts(as.size());
  for (size_t i = 0; i < as.size(); ++i) pts[i] = f.points[size_t(as[i].point)].p;
  const bool ab = as_built && as_built->on() && lookup.element_targets();
  auto* cost = new FrameCost(&lookup.geometry(), as, std::move(pts), loss_kind(loss, scale), scale, weight, compact,
                             ab ? as_built : nullptr);
  cost->prepare(pose);
  return cost;
}
}  // namespace

void add_frame_term(ceres::Problem* problem, double* pose, const NearestLookup& lookup, const FeatureFrame& f,
                    const std::vector<Assignment>& as, const std::string& loss, double scale, double weight, bool compact,
                    const AsBuiltModel* as_built) {
  if (as.empty()) return;
  problem->AddResidualBlock(new_frame_cost(pose, lookup, f, as, loss, scale, weight, compact, as_built), nullptr, pose);
}

std::shared_ptr<ceres::CostFunction> make_frame_term(const double* pose, const NearestLookup& lookup, const FeatureFrame& f,
                                                     const std::vector<Assignment>& as, const std::string& loss,
                                                     double scale, double weight, bool compact, const AsBuiltModel* as_built) {
  if (as.empty()) return nullptr;
  return std::shared_ptr<ceres::CostFunction>(new_frame_cost(pose, lookup, f, as, loss, scale, weight, compact, as_built));
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
    const double we = (which >= 0 ? double(a.w[which]) : 1.0) * double(a.sw);
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