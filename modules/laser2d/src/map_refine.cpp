#include "fploc/laser2d/map_refine.h"

#include "field_fit.h"
#include "fploc/floorplan/distance_field.h"
#include "fploc/floorplan/occupancy.h"

#include <ceres/ceres.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

namespace fploc::laser2d {

namespace {

// The others' points on a raster of cell_m, by the orientation of their normal (`bins` bins over 180 degrees), with
// summed-area tables of their count and first and second moments (coordinates relative to the raster's origin), so
// the line of any window of cells is O(1). A query sums the two bins nearest its own normal: the points of a wall
// perpendicular to it (a corner's other arm) are not in them, and do not bias the line's mean.
class LineField {
 public:
  LineField(double x0, double y0, int w, int h, double cell, int bins)
      : x0_(x0), y0_(y0), w_(w), h_(h), bins_(bins), cell_(cell) {}

  void clear() { acc_.assign(size_t(w_ + 1) * size_t(h_ + 1) * size_t(bins_), Moments{}); }
  void add(const Eigen::Vector2d& p, const Eigen::Vector2d& normal) {
    const double x = p.x() - x0_, y = p.y() - y0_;
    const int i = int(std::floor(x / cell_)), j = int(std::floor(y / cell_));
    if (i < 0 || j < 0 || i >= w_ || j >= h_) return;
    double a = std::atan2(normal.y(), normal.x());
    if (a < 0) a += M_PI;
    const int b = std::min(bins_ - 1, int(a / (M_PI / bins_)));
    Moments& m = at(i + 1, j + 1, b);
    m.n += 1, m.sx += x, m.sy += y, m.sxx += x * x, m.sxy += x * y, m.syy += y * y;
  }
  // After the points: the cells' moments become summed-area tables.
  void integrate() {
    for (int j = 1; j <= h_; ++j)
      for (int i = 1; i <= w_; ++i)
        for (int b = 0; b < bins_; ++b) {
          Moments& m = at(i, j, b);
          m += at(i - 1, j, b);
          m += at(i, j - 1, b);
          m -= at(i - 1, j - 1, b);
        }
  }
  // The line of the others' points around world point p whose normals lie near `normal`: its mean (world) and unit
  // normal; false when there are too few points or they are not linear.
  bool line(const Eigen::Vector2d& p, const Eigen::Vector2d& normal, int r, int min_points, double max_flatness,
            Eigen::Vector2d* mean, Eigen::Vector2d* nrm) const {
    const int i = int(std::floor((p.x() - x0_) / cell_)), j = int(std::floor((p.y() - y0_) / cell_));
    const int i0 = std::max(0, i - r), j0 = std::max(0, j - r), i1 = std::min(w_, i + r + 1), j1 = std::min(h_, j + r + 1);
    if (i0 >= i1 || j0 >= j1) return false;
    double a = std::atan2(normal.y(), normal.x());
    if (a < 0) a += M_PI;
    const int b0 = int(std::floor(a / (M_PI / bins_) - 0.5));
    Moments m;
    for (int b : {b0, b0 + 1}) {
      const int bb = ((b % bins_) + bins_) % bins_;
      m += at(i1, j1, bb);
      m -= at(i0, j1, bb);
      m -= at(i1, j0, bb);
      m += at(i0, j0, bb);
    }
    if (m.n < min_points) return false;
    const double mx = m.sx / m.n, my = m.sy / m.n;
    Eigen::Matrix2d c;
    c(0, 0) = m.sxx / m.n - mx * mx;
    c(0, 1) = c(1, 0) = m.sxy / m.n - mx * my;
    c(1, 1) = m.syy / m.n - my * my;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(c);
    const double l0 = std::max(0.0, es.eigenvalues()(0)), l1 = es.eigenvalues()(1);
    if (!(l1 > 0) || l0 > max_flatness * l1) return false;
    *mean = {mx + x0_, my + y0_};
    *nrm = es.eigenvectors().col(0).normalized();
    return true;
  }

 private:
  struct Moments {
    double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
    Moments& operator+=(const Moments& o) {
      n += o.n, sx += o.sx, sy += o.sy, sxx += o.sxx, sxy += o.sxy, syy += o.syy;
      return *this;
    }
    Moments& operator-=(const Moments& o) {
      n -= o.n, sx -= o.sx, sy -= o.sy, sxx -= o.sxx, sxy -= o.sxy, syy -= o.syy;
      return *this;
    }
  };
  size_t index(int i, int j, int b) const { return (size_t(j) * size_t(w_ + 1) + size_t(i)) * size_t(bins_) + size_t(b); }
  Moments& at(int i, int j, int b) { return acc_[index(i, j, b)]; }
  const Moments& at(int i, int j, int b) const { return acc_[index(i, j, b)]; }
  double x0_, y0_;
  int w_, h_, bins_;
  double cell_;
  std::vector<Moments> acc_;
};

// A point's distance along the normal of its line [point sigmas].
struct PointToLine {
  PointToLine(const Eigen::Vector2d& p, const Eigen::Vector2d& m, const Eigen::Vector2d& n, double inv_sigma)
      : p_(p), m_(m), n_(n), inv_sigma_(inv_sigma) {}
  template <class T>
  bool operator()(const T* x, T* r) const {
    const T c = cos(x[2]), s = sin(x[2]);
    const T wx = x[0] + c * p_.x() - s * p_.y() - m_.x();
    const T wy = x[1] + s * p_.x() + c * p_.y() - m_.y();
    r[0] = (n_.x() * wx + n_.y() * wy) * inv_sigma_;
    return true;
  }
  Eigen::Vector2d p_, m_, n_;
  double inv_sigma_;
};


Eigen::Vector2d transform(const double* x, const Eigen::Vector2d& p) {
  const double c = std::cos(x[2]), s = std::sin(x[2]);
  return {x[0] + c * p.x() - s * p.y(), x[1] + s * p.x() + c * p.y()};
}

}  // namespace

std::vector<Pose2> refine_map_poses(const std::vector<std::vector<Eigen::Vector2d>>& scans_in, const std::vector<Pose2>& start,
                                    const MapRefineConfig& cfg, MapRefineStats* stats) {
  const size_t n = std::min(scans_in.size(), start.size());
  std::vector<Pose2> poses(start.begin(), start.begin() + long(n));
  if (n < 2 || cfg.passes <= 0 || !(cfg.cell_m > 0)) return poses;
  // At most max_points per scan (every k-th).
  std::vector<std::vector<Eigen::Vector2d>> scans(n);
  for (size_t k = 0; k < n; ++k) {
    const auto& s = scans_in[k];
    const size_t step = cfg.max_points > 0 ? std::max<size_t>(1, (s.size() + size_t(cfg.max_points) - 1) / size_t(cfg.max_points)) : 1;
    for (size_t i = 0; i < s.size(); i += step) scans[k].push_back(s[i]);
  }
  // Each point's normal in its scan's frame, from the returns around it (PCA of the points within +-2 of it that
  // lie within 0.15 m or 6 % of its range of it, i.e. ~3 beam spacings of a 1-degree scan; none where they are not
  // linear): the others' line is taken only where it agrees.
  std::vector<std::vector<Eigen::Vector2d>> normals(n);
  for (size_t k = 0; k < n; ++k) {
    const auto& s = scans[k];
    normals[k].assign(s.size(), Eigen::Vector2d::Zero());
    for (size_t i = 0; i < s.size(); ++i) {
      const double near = std::max(0.15, 0.06 * s[i].norm());
      Eigen::Vector2d m = Eigen::Vector2d::Zero();
      std::vector<Eigen::Vector2d> nb;
      for (long d = -2; d <= 2; ++d) {
        const long q = long(i) + d;
        if (q < 0 || q >= long(s.size()) || (s[size_t(q)] - s[i]).norm() > near) continue;
        nb.push_back(s[size_t(q)]);
        m += s[size_t(q)];
      }
      if (nb.size() < 3) continue;
      m /= double(nb.size());
      Eigen::Matrix2d c = Eigen::Matrix2d::Zero();
      for (const auto& q : nb) c += (q - m) * (q - m).transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(c);
      if (es.eigenvalues()(0) <= 0.1 * es.eigenvalues()(1)) normals[k][i] = es.eigenvectors().col(0).normalized();
    }
  }
  const double min_cos = std::cos(cfg.max_normal_angle_rad);
  // The raster covers every point at the starting poses with a margin of max_shift + a metre of rotation lever.
  double x0 = std::numeric_limits<double>::max(), y0 = x0, x1 = -x0, y1 = -x0;
  for (size_t k = 0; k < n; ++k) {
    const double x[3] = {poses[k].x, poses[k].y, poses[k].yaw};
    for (const auto& p : scans[k]) {
      const Eigen::Vector2d w = transform(x, p);
      x0 = std::min(x0, w.x()), y0 = std::min(y0, w.y()), x1 = std::max(x1, w.x()), y1 = std::max(y1, w.y());
    }
  }
  if (!(x1 >= x0)) return poses;
  const double margin = 1.0 + cfg.max_shift_m;
  x0 -= margin, y0 -= margin, x1 += margin, y1 += margin;
  const int w = int(std::ceil((x1 - x0) / cfg.cell_m)), h = int(std::ceil((y1 - y0) / cfg.cell_m));
  // The tables take 4 bins x 6 doubles per cell (~190 B; aces's 80 x 80 m at 5 cm: ~0.5 GB): a larger raster is
  // not refined.
  if (double(w) * double(h) * std::max(3, cfg.normal_bins) > 4e7) return poses;
  LineField field(x0, y0, w, h, cfg.cell_m, std::max(3, cfg.normal_bins));
  const int groups = std::max(1, std::min<int>(cfg.groups, int(n)));
  const double inv_sigma = 1 / cfg.point_sigma_m;
  for (int pass = 0; pass < cfg.passes; ++pass) {
    MapRefineStats::Pass ps;
    double shift2 = 0, res2 = 0;
    long res_n = 0;
    for (int g = 0; g < groups; ++g) {
      field.clear();
      for (size_t k = 0; k < n; ++k) {
        if (int(k % size_t(groups)) == g) continue;
        const double x[3] = {poses[k].x, poses[k].y, poses[k].yaw};
        const double c = std::cos(x[2]), sn = std::sin(x[2]);
        for (size_t i = 0; i < scans[k].size(); ++i) {
          const Eigen::Vector2d& ns = normals[k][i];
          if (ns.squaredNorm() == 0) continue;  // no normal: not on a line
          field.add(transform(x, scans[k][i]), {c * ns.x() - sn * ns.y(), sn * ns.x() + c * ns.y()});
        }
      }
      field.integrate();
      // The field variant: the distance field of the others' hits on a raster of cell_m (a cell with a hit is
      // occupied), the grid localizer's Ceres fit on it (detail::refine_on_field).
      std::unique_ptr<detail::InterpolatedField> dfield;
      if (cfg.method == MapRefineMethod::kField) {
        OccupancyGrid og;
        og.width = w, og.height = h, og.resolution = cfg.cell_m, og.origin_x = x0, og.origin_y = y0;
        og.data.assign(size_t(w) * size_t(h), 0);
        for (size_t k = 0; k < n; ++k) {
          if (int(k % size_t(groups)) == g) continue;
          const double x[3] = {poses[k].x, poses[k].y, poses[k].yaw};
          for (const auto& p : scans[k]) {
            const Eigen::Vector2d wp = transform(x, p);
            const int i = int(std::floor((wp.x() - x0) / cfg.cell_m)), j = int(std::floor((wp.y() - y0) / cfg.cell_m));
            if (i >= 0 && j >= 0 && i < w && j < h) og.data[size_t(j) * size_t(w) + size_t(i)] = 100;
          }
        }
        dfield = std::make_unique<detail::InterpolatedField>(std::make_shared<DistanceField>(og, 0.5));
      }
      // A refined pose is taken when enough of its scan fits (inl points, at least min_ratio of them and
      // cfg.min_inliers; ss their squared distances) and it stays near its start; else the pose is kept.
      auto take = [&](size_t k, const double* x, int inl, double ss, double min_ratio) {
        const bool near = std::hypot(x[0] - start[k].x, x[1] - start[k].y) <= cfg.max_shift_m &&
                          std::abs(wrap_angle(x[2] - start[k].yaw)) <= cfg.max_turn_rad;
        if (double(inl) >= min_ratio * double(scans[k].size()) && inl >= cfg.min_inliers && near &&
            std::isfinite(x[0] + x[1] + x[2])) {
          shift2 += std::pow(x[0] - poses[k].x, 2) + std::pow(x[1] - poses[k].y, 2);
          poses[k] = {x[0], x[1], wrap_angle(x[2])};
          ++ps.refined;
          res2 += ss;
          res_n += inl;
        } else {
          ++ps.kept;
        }
      };
      for (size_t k = size_t(g); k < n; k += size_t(groups)) {
        const auto& pts = scans[k];
        if (pts.empty()) continue;
        double x[3] = {poses[k].x, poses[k].y, poses[k].yaw};
        if (dfield) {
          detail::FieldFitOptions fo;
          fo.point_sigma_m = cfg.point_sigma_m, fo.huber_m = cfg.huber_m, fo.max_iterations = cfg.max_iterations * 2;
          double cost = 0;
          int its = 0;
          detail::refine_on_field(*dfield, fo, pts, start[k], cfg.prior_sigma_xy_m, cfg.prior_sigma_yaw_rad, x, &cost, &its);
          double ss = 0;
          const int inl = detail::count_inliers(*dfield->df, pts, x, cfg.inlier_m, &ss);
          take(k, x, inl, ss, 0.5);
          continue;
        }
        for (int round = 0; round < cfg.icp_rounds; ++round) {
          ceres::Problem::Options po;
          po.loss_function_ownership = ceres::TAKE_OWNERSHIP;
          po.cost_function_ownership = ceres::TAKE_OWNERSHIP;
          ceres::Problem problem(po);
          int used = 0;
          const double c = std::cos(x[2]), sn = std::sin(x[2]);
          for (size_t i = 0; i < pts.size(); ++i) {
            const auto& p = pts[i];
            const Eigen::Vector2d& ns = normals[k][i];
            if (ns.squaredNorm() == 0) continue;
            const Eigen::Vector2d nw(c * ns.x() - sn * ns.y(), sn * ns.x() + c * ns.y());
            Eigen::Vector2d m, nrm;
            if (!field.line(transform(x, p), nw, cfg.radius_cells, cfg.min_line_points, cfg.max_flatness, &m, &nrm)) continue;
            if (std::abs(nrm.dot(nw)) < min_cos) continue;
            problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PointToLine, 1, 3>(new PointToLine(p, m, nrm, inv_sigma)),
                                     new ceres::HuberLoss(cfg.huber_m * inv_sigma), x);
            ++used;
          }
          if (used < 3) break;
          problem.AddResidualBlock(new ceres::AutoDiffCostFunction<detail::PriorCost, 3, 3>(
                                       new detail::PriorCost(start[k], cfg.prior_sigma_xy_m, cfg.prior_sigma_yaw_rad)),
                                   nullptr, x);
          const double before[3] = {x[0], x[1], x[2]};
          detail::solve_small(&problem, cfg.max_iterations);
          if (std::hypot(x[0] - before[0], x[1] - before[1]) < 1e-4 && std::abs(wrap_angle(x[2] - before[2])) < 1e-5) break;
        }
        // Taken when enough of the scan lies on the others' lines and the pose stays near its start.
        int inl = 0;
        double ss = 0;
        const double cx = std::cos(x[2]), sx = std::sin(x[2]);
        for (size_t i = 0; i < pts.size(); ++i) {
          const Eigen::Vector2d wp = transform(x, pts[i]);
          const Eigen::Vector2d& ns = normals[k][i];
          if (ns.squaredNorm() == 0) continue;
          const Eigen::Vector2d nw(cx * ns.x() - sx * ns.y(), sx * ns.x() + cx * ns.y());
          Eigen::Vector2d m, nrm;
          if (!field.line(wp, nw, cfg.radius_cells, cfg.min_line_points, cfg.max_flatness, &m, &nrm) ||
              std::abs(nrm.dot(nw)) < min_cos)
            continue;
          const double d = nrm.dot(wp - m);
          if (std::abs(d) < cfg.inlier_m) ++inl, ss += d * d;
        }
        take(k, x, inl, ss, cfg.min_inlier_ratio);
      }
    }
    // High-pass: the corrections' moving mean over +-highpass_scans scans (in the scans' order) is taken out, so only
    // their part that changes from scan to scan (the reference's white per-pose noise) is applied and the map
    // keeps the reference's slow shape.
    if (cfg.highpass_scans > 0) {
      std::vector<Eigen::Vector3d> c(n);
      for (size_t k = 0; k < n; ++k)
        c[k] = {poses[k].x - start[k].x, poses[k].y - start[k].y, wrap_angle(poses[k].yaw - start[k].yaw)};
      std::vector<Eigen::Vector3d> prefix(n + 1, Eigen::Vector3d::Zero());
      for (size_t k = 0; k < n; ++k) prefix[k + 1] = prefix[k] + c[k];
      const size_t hw = size_t(cfg.highpass_scans);
      for (size_t k = 0; k < n; ++k) {
        const size_t lo = k > hw ? k - hw : 0, hi = std::min(n, k + hw + 1);
        const Eigen::Vector3d m = (prefix[hi] - prefix[lo]) / double(hi - lo);
        poses[k] = {start[k].x + c[k].x() - m.x(), start[k].y + c[k].y() - m.y(), wrap_angle(start[k].yaw + c[k].z() - m.z())};
      }
    }
    double from2 = 0, yaw2 = 0;
    for (size_t k = 0; k < n; ++k) {
      from2 += std::pow(poses[k].x - start[k].x, 2) + std::pow(poses[k].y - start[k].y, 2);
      yaw2 += std::pow(wrap_angle(poses[k].yaw - start[k].yaw), 2);
    }
    ps.rms_shift_m = ps.refined ? std::sqrt(shift2 / ps.refined) : 0;
    ps.rms_from_start_m = std::sqrt(from2 / double(n));
    ps.rms_from_start_yaw_rad = std::sqrt(yaw2 / double(n));
    ps.rms_residual_m = res_n ? std::sqrt(res2 / double(res_n)) : 0;
    if (stats) stats->passes.push_back(ps);
  }
  return poses;
}

}  // namespace fploc::laser2d
