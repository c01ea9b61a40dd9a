#include "fploc/laser2d/grid_localizer.h"

#include <algorithm>
#include <array>
#include <deque>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "field_fit.h"
#include "fploc/laser2d/correlative_search.h"

namespace fploc::laser2d {

namespace {

using detail::FieldFitOptions;

// A step's prediction sigmas (xy, yaw) by the model base + k * |increment|: the wheels' (sigma_*) or the laser
// odometry's (laser_sigma_*); without the base while dead-reckoning with dead_reckoning_motion_only.
struct StepSigma {
  double xy = 0, yaw = 0;
};
// Squared Mahalanobis distance of pose a from b, independent sigmas in x/y (sxy) and yaw (syaw).
double mahalanobis2(const Pose2& a, const Pose2& b, double sxy, double syaw) {
  const double ex = a.x - b.x, ey = a.y - b.y, eyaw = wrap_angle(a.yaw - b.yaw);
  return (ex * ex + ey * ey) / (sxy * sxy) + eyaw * eyaw / (syaw * syaw);
}

StepSigma wheel_step_sigma(const GridLocalizerConfig& c, const Pose2& inc, bool base) {
  const double step = std::hypot(inc.x, inc.y), turn = std::abs(wrap_angle(inc.yaw));
  return {(base ? c.sigma_xy_m : 0.0) + c.sigma_xy_per_m * step,
          (base ? c.sigma_yaw_rad : 0.0) + c.sigma_yaw_per_rad * turn + c.sigma_yaw_per_m * step};
}
StepSigma laser_step_sigma(const GridLocalizerConfig& c, const Pose2& inc, bool base) {
  const double step = std::hypot(inc.x, inc.y), turn = std::abs(wrap_angle(inc.yaw));
  return {(base ? c.laser_sigma_xy_m : 0.0) + c.laser_sigma_xy_per_m * step,
          (base ? c.laser_sigma_yaw_rad : 0.0) + c.laser_sigma_yaw_per_rad * turn + c.laser_sigma_yaw_per_m * step};
}

FieldFitOptions fit_options(const GridLocalizerConfig& cfg) {
  FieldFitOptions o;
  o.point_sigma_m = cfg.point_sigma_m;
  o.huber_m = cfg.huber_m;
  o.loss = cfg.fit_loss;
  o.max_iterations = cfg.max_iterations;
  return o;
}

}  // namespace

struct GridLocalizer::Impl {
  std::unique_ptr<ceres::Problem> refine_at(const std::vector<Eigen::Vector2d>& pts, const Pose2& pred, double sxy,
                                            double syaw, double* x, double* cost, int* iterations, bool fix_yaw = false) const {
    FieldFitOptions o = fit_options(cfg);
    o.huber_first = cfg.huber_first_above_sigma_m > 0 && sxy > cfg.huber_first_above_sigma_m;
    return detail::refine_on_field(field, o, pts, pred, sxy, syaw, x, cost, iterations, fix_yaw);
  }
  detail::InterpolatedField field;
  std::shared_ptr<const DistanceField> df;
  std::unique_ptr<ScorePyramid> pyramid;  // exp(-d^2 / 2 s^2) per cell and its max-pooled levels
  GridLocalizerConfig cfg;
  Pose2 pose;
  double sxy = 0, syaw = 0;  // current uncertainty of `pose`
  bool reconfirming = false;            // published POOR until the track is re-confirmed (reconfirm_after_lost)
  std::deque<double> recent_inliers;    // the inlier shares of the fits since it left LOST (last confirm_scans)
  std::vector<double> ranges;  // scratch: the scan's ranges (median for the published covariance)
  std::optional<Pose2> last_odom;
  std::optional<Pose2> raw_inc;  // this scan's odometry increment as measured (before the calibration)
  OdometryCalibration calib;
  LaserOdometry laser;
  std::optional<Pose2> prev_fit;  // the previous scan's pose when it was a good fit (calibration pairs)
  int poor_run = 0;
  // Since the last fit on laser steps: the variance the wheels' model would have added beyond the laser steps'.
  double wheel_extra_xy2 = 0, wheel_extra_yaw2 = 0;
  bool first = true;
  // Motion since the last wide re-acquisition search (negative: none yet in this episode).
  double search_moved_m = -1, search_turned_rad = 0;
  // Re-acquisition hypotheses (while LOST): each tracked by odometry and its own local fit.
  struct Hypothesis {
    Pose2 pose;
    double sxy = 0, syaw = 0;
    int hits = 0;
    double inlier_sum = 0;
    double travel_m = 0;  // the odometry's travel since it was proposed
    double last = 0;      // its latest fit's inlier share
    double lowest = 1;    // its lowest fit's inlier share
    int id = 0;
    double mean() const { return hits > 0 ? inlier_sum / hits : 0; }
  };
  std::vector<Hypothesis> hyps;
  // Global localization: searching the whole map (start_global, or LOST for global_after_lost_scans).
  bool global = false;
  bool gave_up = false;                 // the whole-map search ran out of global_budget_s
  double stamp = std::numeric_limits<double>::quiet_NaN();     // this scan's time (NaN: not given)
  double global_t0 = std::numeric_limits<double>::quiet_NaN();  // the whole-map search's first stamped scan
  int next_place_id = 0;
  std::vector<uint8_t> free_cells;  // per cell of the field (row-major, row 0 bottom): 1 known free (set_free_space)
  Pose2 global_centre;              // the whole-map window: the free cells' (else the field's) world bounding box
  double global_half_m = 0;


  // One local fit: the search around pred (+-window_sigmas sigma, capped at max_xy / max_yaw), the refinement,
  // the inliers, the acceptance test and the covariance.
  struct Fit {
    Pose2 est;
    bool accepted = false;
    double inlier_ratio = 0, rms = 0, score = 0, wxy = 0, wyaw = 0;
    int inliers = 0, leaves = 0, iterations = 0, refined = 0;
    Eigen::Matrix3d cov = Eigen::Matrix3d::Identity();
    // Every refined candidate (the chosen one included): the rivals of the chosen fit.
    struct Alt {
      Pose2 pose;
      double inlier_ratio = 0;
    };
    std::vector<Alt> alts;
  };
  Fit fit(const std::vector<Eigen::Vector2d>& pts, const Pose2& pred, double sxy, double syaw, double max_xy,
          double max_yaw, int keep, double min_inlier_ratio) const;
  // The fit lies inside the window searched around pred (the refinement may slide out of it along a flat wall).
  bool inside(const Fit& f, const Pose2& pred) const {
    return std::hypot(f.est.x - pred.x, f.est.y - pred.y) <= f.wxy + df->resolution() &&
           std::abs(wrap_angle(f.est.yaw - pred.yaw)) <= f.wyaw + cfg.search_yaw_step_rad;
  }
  // The best inlier share of a refined candidate at another place than the fit's.
  double rival(const Fit& f) const {
    double r = 0;
    for (const auto& a : f.alts)
      if (std::hypot(a.pose.x - f.est.x, a.pose.y - f.est.y) > cfg.rival_sep_xy_m ||
          std::abs(wrap_angle(a.pose.yaw - f.est.yaw)) > cfg.rival_sep_yaw_rad)
        r = std::max(r, a.inlier_ratio);
    return r;
  }

  // Every k-th point so that about 100 remain (the correlative search's points).
  static std::vector<Eigen::Vector2d> search_points(const std::vector<Eigen::Vector2d>& pts) {
    const size_t sk = std::max<size_t>(1, pts.size() / 100);
    std::vector<Eigen::Vector2d> sp;
    for (size_t i = 0; i < pts.size(); i += sk) sp.push_back(pts[i]);
    return sp;
  }
  // The lowest score of a pose with min_inlier_ratio of the points within inlier_m: nothing below it can become a
  // hypothesis (prunes most of a wide search where the map does not explain the scan).
  double hypothesis_min_score() const {
    const double r = cfg.inlier_m / cfg.score_sigma_m;
    return cfg.min_inlier_ratio * std::exp(-0.5 * r * r);
  }
  // Each hypothesis refitted around its odometry-propagated pose; dropped at its first failed fit.
  void track_hypotheses(const std::vector<Eigen::Vector2d>& pts) {
    std::vector<Hypothesis> kept;
    for (auto& h : hyps) {
      const Fit f = fit(pts, h.pose, h.sxy, h.syaw, cfg.max_window_xy_m, cfg.max_window_yaw_rad, 1, cfg.min_inlier_ratio);
      if (!f.accepted || f.inlier_ratio < cfg.min_inlier_ratio) continue;
      h.pose = f.est;
      h.sxy = std::sqrt(std::max(f.cov(0, 0), f.cov(1, 1)));
      h.syaw = std::sqrt(f.cov(2, 2));
      ++h.hits;
      h.inlier_sum += f.inlier_ratio;
      h.last = f.inlier_ratio;
      h.lowest = std::min(h.lowest, f.inlier_ratio);
      kept.push_back(h);
    }
    hyps = std::move(kept);
  }
  // A refined search candidate becomes a new hypothesis when it fits (accepted, >= min_inlier_ratio) and no
  // hypothesis is already there (within sep_xy and sep_yaw).
  void add_hypothesis(const Fit& f, double sep_xy, double sep_yaw) {
    if (!f.accepted || f.inlier_ratio < cfg.min_inlier_ratio) return;
    for (const auto& h : hyps)
      if (std::hypot(h.pose.x - f.est.x, h.pose.y - f.est.y) < sep_xy && std::abs(wrap_angle(h.pose.yaw - f.est.yaw)) < sep_yaw)
        return;
    Hypothesis h;
    h.pose = f.est;
    h.sxy = std::sqrt(std::max(f.cov(0, 0), f.cov(1, 1)));
    h.syaw = std::sqrt(f.cov(2, 2));
    h.hits = 1;
    h.inlier_sum = f.inlier_ratio;
    h.last = f.inlier_ratio;
    h.lowest = f.inlier_ratio;
    h.id = next_place_id++;
    hyps.push_back(h);
  }
  // Global localization's scan: the hypotheses tracked, new ones from the whole-map search, and one taken when it
  // dominates (GridLocalizerConfig::global_*); else LOST at the leading hypothesis.
  GridResult global_step(const std::vector<Eigen::Vector2d>& pts, GridResult res);
  // LOST after the whole-map search gave up: where it was, with the whole map's spread.
  GridResult gave_up_result(GridResult res) {
    ++poor_run;
    res.global = false;
    res.global_gave_up = true;
    if (std::isfinite(stamp) && std::isfinite(global_t0)) res.global_elapsed_s = stamp - global_t0;
    res.pose = pose;
    res.status = GridStatus::kLost;
    res.hypotheses = 0;
    res.covariance = Eigen::Vector3d(global_half_m * global_half_m, global_half_m * global_half_m, M_PI * M_PI).asDiagonal();
    return res;
  }

  // On a laser step: the fit in the window the wheels' model would have grown since the last fit (the laser
  // steps' own window can be too small: a laser increment wrong by more than its sigma, or a pose the last fits
  // left further off than their covariance says). Only an unrivalled fit that explains almost the whole scan
  // (reacquire_strong_ratio) is returned.
  std::optional<Fit> wheel_window_fit(const std::vector<Eigen::Vector2d>& pts, const Pose2& pred, double sxy,
                                      double syaw) const {
    if (wheel_extra_xy2 <= 0 && wheel_extra_yaw2 <= 0) return std::nullopt;
    Fit g = fit(pts, pred, std::sqrt(sxy * sxy + wheel_extra_xy2), std::sqrt(syaw * syaw + wheel_extra_yaw2),
                cfg.max_window_xy_m, cfg.max_window_yaw_rad, 1, 1.1);
    if (!inside(g, pred) || g.inlier_ratio < cfg.reacquire_strong_ratio ||
        (cfg.rival_margin >= 0 && rival(g) >= g.inlier_ratio - cfg.rival_margin))
      return std::nullopt;
    g.accepted = true;
    return g;
  }

  Impl(std::shared_ptr<const DistanceField> f, const GridLocalizerConfig& c)
      : field(std::move(f)), df(field.df) {
    pyramid = std::make_unique<ScorePyramid>(*df, c.score_sigma_m, c.search_levels);
    cfg = c;
    calib = OdometryCalibration(c.calibration);
    laser = LaserOdometry(c.laser);
    // The whole-map window without a free-space mask: the field's corners.
    std::vector<Eigen::Vector2d> corners;
    for (int j : {0, df->height() - 1})
      for (int i : {0, df->width() - 1}) corners.push_back(cell_world(i, j));
    set_global_window(corners);
  }
  Eigen::Vector2d cell_world(int i, int j) const {
    const double lx = (i + 0.5) * df->resolution(), ly = (j + 0.5) * df->resolution();
    const double c = std::cos(df->origin_yaw()), s = std::sin(df->origin_yaw());
    return {df->origin_x() + c * lx - s * ly, df->origin_y() + s * lx + c * ly};
  }
  // The square window (the search's shape) covering these world points.
  void set_global_window(const std::vector<Eigen::Vector2d>& p) {
    if (p.empty()) return;
    Eigen::Vector2d lo = p.front(), hi = p.front();
    for (const auto& q : p) lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
    global_centre = {0.5 * (lo.x() + hi.x()), 0.5 * (lo.y() + hi.y()), 0};
    global_half_m = 0.5 * std::max(hi.x() - lo.x(), hi.y() - lo.y()) + df->resolution();
  }
  bool position_free(double x, double y) const {
    const Eigen::Vector2d c = df->to_cell({x, y});
    const long i = std::lround(c.x()), j = std::lround(c.y());
    if (i < 0 || j < 0 || i >= df->width() || j >= df->height()) return false;
    return free_cells[size_t(j) * size_t(df->width()) + size_t(i)] != 0;
  }
};

std::optional<FitLoss> fit_loss_from_name(const std::string& name) {
  if (name == "huber") return FitLoss::kHuber;
  if (name == "cauchy") return FitLoss::kCauchy;
  if (name == "tukey") return FitLoss::kTukey;
  return std::nullopt;
}

GridLocalizer::GridLocalizer(std::shared_ptr<const DistanceField> field, GridLocalizerConfig cfg) : cfg_(cfg) {
  if (!field || field->width() <= 0) throw std::invalid_argument("grid localizer: empty distance field");
  impl_ = std::make_unique<Impl>(std::move(field), cfg_);
}

GridLocalizer::~GridLocalizer() = default;

void GridLocalizer::set_initial_pose(const Pose2& pose) {
  impl_->pose = pose;
  impl_->sxy = cfg_.initial_sigma_xy_m;
  impl_->syaw = cfg_.initial_sigma_yaw_rad;
  impl_->last_odom.reset();
  impl_->laser.reset();
  impl_->prev_fit.reset();
  impl_->search_moved_m = -1;
  impl_->poor_run = 0;
  impl_->reconfirming = false;  // the pose given is taken as it is
  impl_->recent_inliers.clear();
  impl_->first = true;
  impl_->global = false;
  impl_->gave_up = false;
  impl_->hyps.clear();
  have_pose_ = true;
}

void GridLocalizer::set_free_space(const OccupancyGrid& g) {
  Impl& m = *impl_;
  const DistanceField& d = *m.df;
  if (g.width != d.width() || g.height != d.height() || std::abs(g.resolution - d.resolution()) > 1e-9 ||
      std::abs(g.origin_x - d.origin_x()) > 1e-9 || std::abs(g.origin_y - d.origin_y()) > 1e-9 ||
      std::abs(g.origin_yaw - d.origin_yaw()) > 1e-9 || g.data.size() != size_t(g.width) * size_t(g.height))
    throw std::invalid_argument("grid localizer: free space: " + (g.source.empty() ? std::string("the grid") : g.source) +
                                " is not the grid of the distance field (size, resolution or origin differ)");
  m.free_cells.assign(g.data.size(), 0);
  std::vector<Eigen::Vector2d> corners;
  int lo_i = g.width, lo_j = g.height, hi_i = -1, hi_j = -1;
  for (int j = 0; j < g.height; ++j)
    for (int i = 0; i < g.width; ++i)
      if (g.at(i, j) >= 0 && !g.occupied(i, j)) {
        m.free_cells[size_t(j) * size_t(g.width) + size_t(i)] = 1;
        lo_i = std::min(lo_i, i), hi_i = std::max(hi_i, i), lo_j = std::min(lo_j, j), hi_j = std::max(hi_j, j);
      }
  if (hi_i < 0) throw std::invalid_argument("grid localizer: free space: " + (g.source.empty() ? std::string("the grid") : g.source) +
                                            " has no known-free cell");
  for (int j : {lo_j, hi_j})
    for (int i : {lo_i, hi_i}) corners.push_back(m.cell_world(i, j));
  m.set_global_window(corners);
}

void GridLocalizer::start_global() {
  set_initial_pose(impl_->global_centre);
  impl_->global = true;
  impl_->global_t0 = std::numeric_limits<double>::quiet_NaN();
}

std::vector<Eigen::Vector2d> scan_points(const std::vector<float>& ranges, double angle_min, double increment,
                                         double min_range, double max_range, const Pose2& mount, bool upside_down) {
  std::vector<Eigen::Vector2d> out;
  out.reserve(ranges.size());
  const double c = std::cos(mount.yaw), s = std::sin(mount.yaw);
  for (size_t i = 0; i < ranges.size(); ++i) {
    const double r = ranges[i];
    if (!std::isfinite(r) || r < min_range || r >= max_range) continue;
    const double a = (angle_min + double(i) * increment) * (upside_down ? -1 : 1);
    const double lx = r * std::cos(a), ly = r * std::sin(a);
    out.emplace_back(mount.x + c * lx - s * ly, mount.y + s * lx + c * ly);
  }
  return out;
}


GridLocalizer::Impl::Fit GridLocalizer::Impl::fit(const std::vector<Eigen::Vector2d>& pts, const Pose2& pred, double sxy,
                                                  double syaw, double max_xy, double max_yaw, int keep,
                                                  double min_inlier_ratio) const {
  Fit f;
  const DistanceField& d = *df;
  f.wxy = std::clamp(cfg.window_sigmas * sxy, 2 * d.resolution(), max_xy);
  f.wyaw = std::clamp(cfg.window_sigmas * syaw, cfg.search_yaw_step_rad, max_yaw);
  // Correlative search (branch and bound, on at most ~100 points).
  const size_t sk = std::max<size_t>(1, pts.size() / 100);
  std::vector<Eigen::Vector2d> sp;
  for (size_t i = 0; i < pts.size(); i += sk) sp.push_back(pts[i]);
  SearchWindow win;
  win.center = pred;
  win.xy_m = f.wxy;
  win.yaw_rad = f.wyaw;
  win.yaw_step_rad = cfg.search_yaw_step_rad;
  win.sigma_xy_m = sxy;
  win.sigma_yaw_rad = syaw;
  win.prior_kappa = cfg.prior_weight_sigmas;
  SearchOptions sopt;
  sopt.keep = std::max({1, keep, cfg.consistent_candidates});
  sopt.min_ratio = cfg.candidate_ratio;
  SearchStats sst;
  const std::vector<SearchCandidate> cands = correlative_search(d, *pyramid, sp, win, sopt, &sst);
  f.leaves = int(sst.leaves);
  f.score = cands.empty() ? 0 : cands.front().score;
  // Refinement of each candidate with the prediction as a prior.
  std::vector<std::array<double, 3>> xs;  // parameter blocks (alive while their problem is)
  for (const auto& c : cands) xs.push_back({c.pose.x, c.pose.y, c.pose.yaw});
  const bool consistent = cfg.consistent_candidates > 0;
  if (consistent || xs.empty()) xs.push_back({pred.x, pred.y, pred.yaw});
  const size_t n_free = xs.size();
  if (consistent && cfg.odometry_yaw_candidate) xs.push_back({pred.x, pred.y, pred.yaw});
  std::vector<std::unique_ptr<ceres::Problem>> problems;
  std::vector<double> costs(xs.size()), inl(xs.size()), sss(xs.size());
  std::vector<int> ninl(xs.size());
  for (size_t i = 0; i < xs.size(); ++i) {
    problems.push_back(refine_at(pts, pred, sxy, syaw, xs[i].data(), &costs[i], &f.iterations, i >= n_free));
    // Inliers at the refined pose.
    ninl[i] = detail::count_inliers(d, pts, xs[i].data(), cfg.inlier_m, &sss[i]);
    inl[i] = pts.empty() ? 0 : double(ninl[i]) / double(pts.size());
  }
  size_t bi = 0;
  if (!consistent) {
    // The least cost.
    for (size_t i = 1; i < xs.size(); ++i)
      if (costs[i] < costs[bi]) bi = i;
  } else {
    // The fit nearest the prediction, unless another is clearly better supported by the map.
    auto m2 = [&](size_t i) { return mahalanobis2({xs[i][0], xs[i][1], xs[i][2]}, pred, sxy, syaw); };
    size_t near = 0, best = 0;
    for (size_t i = 1; i < xs.size(); ++i) {
      if (m2(i) < m2(near)) near = i;
      if (inl[i] > inl[best]) best = i;
    }
    // No conflict (the fit nearest the prediction is where the search's best refines to): the search's best.
    auto same = [&](size_t a, size_t b) {
      return std::hypot(xs[a][0] - xs[b][0], xs[a][1] - xs[b][1]) < cfg.same_place_xy_m &&
             std::abs(wrap_angle(xs[a][2] - xs[b][2])) < cfg.same_place_yaw_rad;
    };
    if (same(near, 0)) bi = 0;
    else bi = inl[best] >= inl[near] + cfg.jump_inlier_margin ? best : near;
  }
  std::unique_ptr<ceres::Problem> problem = std::move(problems[bi]);
  if (bi >= n_free) {  // yaw held: the covariance from the full problem at that pose (no iterations)
    GridLocalizerConfig c0 = cfg;
    c0.max_iterations = 0;
    double unused = 0;
    problem = detail::refine_on_field(field, fit_options(c0), pts, pred, sxy, syaw, xs[bi].data(), &unused, nullptr);
  }
  f.refined = int(xs.size());
  for (size_t i = 0; i < xs.size(); ++i) f.alts.push_back({{xs[i][0], xs[i][1], wrap_angle(xs[i][2])}, inl[i]});
  const double* x = xs[bi].data();
  f.est = {x[0], x[1], wrap_angle(x[2])};
  f.inliers = ninl[bi];
  f.inlier_ratio = inl[bi];
  f.rms = f.inliers > 0 ? std::sqrt(sss[bi] / f.inliers) : 0;
  const bool near = mahalanobis2(f.est, pred, sxy, syaw) <= cfg.gate_sigmas * cfg.gate_sigmas;
  // The refinement may not leave the window searched (a scan of one flat wall fits anywhere along it).
  const bool inside = this->inside(f, pred);
  f.accepted = (inside && f.inlier_ratio >= min_inlier_ratio) || (near && f.inlier_ratio >= cfg.min_inlier_ratio_near);
  // Covariance from the Jacobian at the solution (loss applied).
  f.cov = detail::covariance_of(*problem, Eigen::Vector3d(sxy * sxy, sxy * sxy, syaw * syaw).asDiagonal());
  return f;
}

GridResult GridLocalizer::Impl::global_step(const std::vector<Eigen::Vector2d>& pts, GridResult res) {
  res.global = true;
  res.search_xy_m = global_half_m;
  res.search_yaw_rad = M_PI;
  if (std::isfinite(stamp)) {
    if (!std::isfinite(global_t0)) global_t0 = stamp;
    res.global_elapsed_s = stamp - global_t0;
  }
  // Out of budget: give up before this scan's search (LOST, no whole-map search until a new start).
  if (cfg.global_budget_s > 0 && res.global_elapsed_s > cfg.global_budget_s) {
    global = false;
    gave_up = true;
    for (const auto& h : hyps) res.places.push_back({h.id, h.pose, h.hits, h.mean(), h.lowest, h.travel_m});
    hyps.clear();
    return gave_up_result(res);
  }
  if (pts.size() >= 10) {
    track_hypotheses(pts);
    SearchWindow win;
    win.center = global_centre;
    win.xy_m = global_half_m;
    win.yaw_rad = M_PI;
    win.yaw_step_rad = cfg.search_yaw_step_rad;
    win.prior_kappa = 0;  // no preference anywhere in the map
    SearchOptions so;
    so.keep = cfg.global_candidates;
    so.sep_xy_m = cfg.global_sep_xy_m;
    so.sep_yaw_rad = cfg.global_sep_yaw_rad;
    so.min_ratio = cfg.candidate_ratio;
    so.min_score = hypothesis_min_score();
    if (!free_cells.empty()) so.position_ok = [this](double x, double y) { return position_free(x, y); };
    SearchStats st;
    const std::vector<SearchCandidate> cands = correlative_search(*df, *pyramid, search_points(pts), win, so, &st);
    res.wide_search = true;
    res.candidates = int(st.leaves);
    res.score = cands.empty() ? 0 : cands.front().score;
    for (const auto& c : cands) {
      const double s0 = 2 * df->resolution(), y0 = 2 * cfg.search_yaw_step_rad;
      add_hypothesis(fit(pts, c.pose, s0, y0, s0, y0, 1, cfg.min_inlier_ratio), so.sep_xy_m, so.sep_yaw_rad);
    }
  }
  for (const auto& h : hyps) res.places.push_back({h.id, h.pose, h.hits, h.mean(), h.lowest, h.travel_m});
  // The leader: enough scans, travel and mean inlier share; the best mean of those. It is taken only when every
  // other hypothesis at another place has a mean lower by global_confirm_margin, whatever its number of scans.
  int lead = -1;
  for (size_t i = 0; i < hyps.size(); ++i) {
    const Hypothesis& h = hyps[i];
    if (h.hits >= cfg.confirm_scans && h.travel_m >= cfg.global_confirm_travel_m &&
        h.mean() >= cfg.global_confirm_inlier_ratio && (lead < 0 || h.mean() > hyps[size_t(lead)].mean()))
      lead = int(i);
  }
  if (lead >= 0) {
    const Hypothesis& l = hyps[size_t(lead)];
    for (size_t i = 0; i < hyps.size() && lead >= 0; ++i) {
      const Hypothesis& h = hyps[i];
      const bool elsewhere = std::hypot(h.pose.x - l.pose.x, h.pose.y - l.pose.y) > cfg.rival_sep_xy_m ||
                             std::abs(wrap_angle(h.pose.yaw - l.pose.yaw)) > cfg.rival_sep_yaw_rad;
      const bool close = h.mean() > l.mean() - cfg.global_confirm_margin ||
                         1 - h.mean() < cfg.global_confirm_outlier_ratio * (1 - l.mean());
      if (int(i) != lead && elsewhere && close) lead = -1;
    }
  }
  if (lead >= 0) {
    const Hypothesis h = hyps[size_t(lead)];
    hyps.clear();
    global = false;
    pose = h.pose;
    sxy = h.sxy;
    syaw = h.syaw;
    poor_run = 0;
    search_moved_m = -1;
    res.pose = h.pose;
    res.status = GridStatus::kOk;
    res.covariance = Eigen::Vector3d(h.sxy * h.sxy, h.sxy * h.sxy, h.syaw * h.syaw).asDiagonal();
    res.inlier_ratio = h.last;
    res.hypotheses = 0;
    res.reacquired = true;
    return res;
  }
  std::sort(hyps.begin(), hyps.end(), [](const auto& a, const auto& b) {
    return a.hits != b.hits ? a.hits > b.hits : a.mean() > b.mean();
  });
  if (int(hyps.size()) > cfg.global_max_hypotheses) hyps.resize(size_t(std::max(0, cfg.global_max_hypotheses)));
  // Not localized: LOST, at the leading hypothesis (else where the search is centred), with the whole map's spread.
  if (!hyps.empty()) pose = hyps.front().pose;
  ++poor_run;
  res.pose = pose;
  res.status = GridStatus::kLost;
  res.inlier_ratio = hyps.empty() ? 0 : hyps.front().last;
  res.hypotheses = int(hyps.size());
  res.covariance = Eigen::Vector3d(global_half_m * global_half_m, global_half_m * global_half_m, M_PI * M_PI).asDiagonal();
  return res;
}

GridResult GridLocalizer::update(const std::vector<Eigen::Vector2d>& points, const std::optional<Pose2>& odom) {
  return update(points, odom, std::numeric_limits<double>::quiet_NaN());
}

GridResult GridLocalizer::update(const std::vector<Eigen::Vector2d>& points, const std::optional<Pose2>& odom,
                                 double stamp_s) {
  Impl& m = *impl_;
  m.stamp = stamp_s;
  m.raw_inc.reset();
  GridResult res = step(points, odom);
  // Calibration: a pair of consecutive good fits (>= min_inlier_ratio, from tracking; a confirmed
  // re-acquisition starts a new pair but is not one) measures the wheels' error over that step.
  const bool good = res.status == GridStatus::kOk && res.inlier_ratio >= cfg_.min_inlier_ratio;
  if (cfg_.calibrate_odometry && good && !res.reacquired && m.prev_fit && m.raw_inc)
    m.calib.observe(*m.raw_inc, between(*m.prev_fit, res.pose));
  if (good) m.prev_fit = res.pose;
  else m.prev_fit.reset();
  res.odom_bias_rad_per_m = m.calib.bias_rad_per_m();
  res.odom_turn_scale_error = m.calib.turn_scale_error();
  res.odom_scale = m.calib.scale();
  res.odom_pairs = m.calib.pairs();
  // What is published: the status of a track not yet re-confirmed and of a weak fit, and the map's share of the
  // covariance (see the config).
  if (cfg_.reconfirm_after_lost) {
    if (res.status == GridStatus::kLost) {
      m.reconfirming = true;
      m.recent_inliers.clear();
    } else if (res.status == GridStatus::kPoor) {
      m.recent_inliers.clear();  // "in a row"
    } else if (res.status == GridStatus::kOk && m.reconfirming) {
      m.recent_inliers.push_back(res.inlier_ratio);
      if (int(m.recent_inliers.size()) > cfg_.confirm_scans) m.recent_inliers.pop_front();
      double mean = 0;
      for (double r : m.recent_inliers) mean += r;
      mean /= double(m.recent_inliers.size());
      if (res.reacquired || (int(m.recent_inliers.size()) >= cfg_.confirm_scans && mean >= cfg_.confirm_inlier_ratio))
        m.reconfirming = false;
      else
        res.status = GridStatus::kPoor;
    }
  }
  if (cfg_.weak_fit_is_poor && res.status == GridStatus::kOk && res.inlier_ratio < cfg_.min_inlier_ratio)
    res.status = GridStatus::kPoor;
  if (cfg_.map_sigma_cells > 0 && res.status != GridStatus::kNotInitialised && !points.empty()) {
    m.ranges.clear();
    for (const auto& p : points) m.ranges.push_back(p.norm());
    auto mid = m.ranges.begin() + m.ranges.size() / 2;
    std::nth_element(m.ranges.begin(), mid, m.ranges.end());
    const double sxy = cfg_.map_sigma_cells * m.df->resolution(), syaw = sxy / std::max(*mid, 1.0);
    res.covariance += Eigen::Vector3d(sxy * sxy, sxy * sxy, syaw * syaw).asDiagonal();
  }
  return res;
}

GridResult GridLocalizer::step(const std::vector<Eigen::Vector2d>& points_in, const std::optional<Pose2>& odom) {
  GridResult res;
  if (!have_pose_) return res;
  Impl& m = *impl_;
  const DistanceField& df = *m.df;

  // Points: every k-th so that at most max_points remain.
  std::vector<Eigen::Vector2d> pts;
  {
    const size_t n = points_in.size();
    const size_t k = cfg_.max_points > 0 ? std::max<size_t>(1, (n + size_t(cfg_.max_points) - 1) / size_t(cfg_.max_points)) : 1;
    for (size_t i = 0; i < n; i += k) {
      const double r = points_in[i].norm();
      if (r >= cfg_.min_range_m && r <= cfg_.max_range_m) pts.push_back(points_in[i]);
    }
  }
  // 1. Prediction and its uncertainty (also of every re-acquisition hypothesis).
  Pose2 pred = m.pose;
  double sxy = m.sxy, syaw = m.syaw;
  double qxy = 0, qyaw = 0;
  std::optional<Pose2> inc;
  const bool wheels = odom && m.last_odom;
  if (wheels) {
    m.raw_inc = between(*m.last_odom, *odom);
    inc = cfg_.calibrate_odometry ? m.calib.correct(*m.raw_inc) : *m.raw_inc;
  }
  // The laser odometry's increment where it matches, the wheels' (or none) otherwise; the first scan starts it.
  std::optional<LaserOdometryStep> laser;
  if (cfg_.laser_odometry) {
    const StepSigma w = inc ? wheel_step_sigma(cfg_, *inc, true) : StepSigma{cfg_.no_odom_sigma_xy_m, cfg_.no_odom_sigma_yaw_rad};
    laser = m.laser.update(pts, inc ? *inc : Pose2{}, w.xy, w.yaw);
    if (m.first) laser.reset();
  }
  // After a fit: base + motion (the window around a fresh fit); while dead-reckoning: the motion only.
  const bool base = !(cfg_.dead_reckoning_motion_only && m.poor_run > 0);
  if (laser) {
    // What the wheels' model would have added since the last fit (the wide retry's window while re-acquiring).
    const StepSigma q = laser_step_sigma(cfg_, laser->increment, base);
    if (m.poor_run == 0) m.wheel_extra_xy2 = m.wheel_extra_yaw2 = 0;
    if (wheels) {
      const StepSigma w = wheel_step_sigma(cfg_, *inc, base);
      m.wheel_extra_xy2 += std::max(0.0, w.xy * w.xy - q.xy * q.xy);
      m.wheel_extra_yaw2 += std::max(0.0, w.yaw * w.yaw - q.yaw * q.yaw);
    }
    inc = laser->increment;
    res.laser_step = true;
    res.laser_inlier_ratio = laser->inlier_ratio;
    res.laser_increment = laser->increment;
    qxy = q.xy;
    qyaw = q.yaw;
  } else if (wheels) {
    const StepSigma q = wheel_step_sigma(cfg_, *inc, base);
    qxy = q.xy;
    qyaw = q.yaw;
  }
  if (laser || wheels) {
    const double step = std::hypot(inc->x, inc->y);
    pred = compose(m.pose, *inc);
    sxy = std::sqrt(sxy * sxy + qxy * qxy + step * step * syaw * syaw);
    syaw = std::sqrt(syaw * syaw + qyaw * qyaw);
  } else if (!m.first) {
    qxy = cfg_.no_odom_sigma_xy_m;
    qyaw = cfg_.no_odom_sigma_yaw_rad;
    sxy = std::sqrt(sxy * sxy + qxy * qxy);
    syaw = std::sqrt(syaw * syaw + qyaw * qyaw);
  }
  for (auto& h : m.hyps) {
    const double step = inc ? std::hypot(inc->x, inc->y) : 0;
    if (inc) h.pose = compose(h.pose, *inc);
    h.travel_m += step;
    h.sxy = std::sqrt(h.sxy * h.sxy + qxy * qxy + step * step * h.syaw * h.syaw);
    h.syaw = std::sqrt(h.syaw * h.syaw + qyaw * qyaw);
  }
  m.first = false;
  if (odom) m.last_odom = odom;

  res.num_points = int(pts.size());
  // Global localization: from start_global, or a kidnapped robot (LOST for global_after_lost_scans scans).
  if (m.gave_up) return m.gave_up_result(res);
  if (!m.global && cfg_.reacquire && cfg_.global_after_lost_scans > 0 &&
      m.poor_run >= cfg_.lost_after + cfg_.global_after_lost_scans) {
    m.global = true;
    m.global_t0 = std::numeric_limits<double>::quiet_NaN();
  }
  if (m.global) return m.global_step(pts, res);
  auto keep_prediction = [&]() {
    m.pose = pred;
    m.sxy = sxy;
    m.syaw = syaw;
    ++m.poor_run;
    res.pose = pred;
    res.status = m.poor_run >= cfg_.lost_after ? GridStatus::kLost : GridStatus::kPoor;
    res.covariance = Eigen::Vector3d(sxy * sxy, sxy * sxy, syaw * syaw).asDiagonal();
    res.hypotheses = int(m.hyps.size());
  };
  if (pts.size() < 10) {
    res.search_xy_m = std::clamp(cfg_.window_sigmas * sxy, 2 * df.resolution(), cfg_.max_window_xy_m);
    res.search_yaw_rad = std::clamp(cfg_.window_sigmas * syaw, cfg_.search_yaw_step_rad, cfg_.max_window_yaw_rad);
    keep_prediction();
    return res;
  }

  // 2. LOST: re-acquisition. A single scan's fit no longer decides (after a long stretch the map does not
  // explain, a wrong place can match one scan well): every hypothesis is tracked by the odometry and its own
  // local fit and dropped when a fit fails; new ones come from a wide search around the dead-reckoned
  // prediction (+-window_sigmas sigma, capped at reacquire_xy_m / reacquire_yaw_rad); one is taken when it has
  // matched confirm_scans scans in a row and no other hypothesis has matched nearly as many.
  if (cfg_.reacquire && m.poor_run >= cfg_.reacquire_after) {
    // The fit around the dead-reckoned prediction: a strong fit that agrees with it (within gate_sigmas) ends
    // LOST at once (the map and the odometry agree; nothing to confirm); a weak one near it is followed (POOR).
    const Impl::Fit f = m.fit(pts, pred, sxy, syaw, cfg_.max_window_xy_m, cfg_.max_window_yaw_rad, 1, 1.1);
    {
      const bool near = mahalanobis2(f.est, pred, sxy, syaw) <= cfg_.gate_sigmas * cfg_.gate_sigmas;
      // (Tried: leaving LOST only with confirm_inlier_ratio here too: intel 18.1 -> 185 cm, more weak fits
      // followed; freiburg-079 86 -> 91 cm.)
      const bool inside = m.inside(f, pred);
      const bool unrivalled = cfg_.rival_margin < 0 || m.rival(f) < f.inlier_ratio - cfg_.rival_margin;
      // Within gate_sigmas of this step's own odometry uncertainty (not the accumulated one).
      const double step_xy = std::max(qxy, cfg_.sigma_xy_m), step_yaw = std::max(qyaw, cfg_.sigma_yaw_rad);
      const bool one_step = mahalanobis2(f.est, pred, step_xy, step_yaw) <= cfg_.gate_sigmas * cfg_.gate_sigmas;
      // On laser steps: also the window the wheels' model would have searched, where only a scan the map
      // explains almost entirely (reacquire_strong_ratio), and unrivalled, may move the pose (the pose the last
      // fits left can be off by more than their covariance says: csail 400, 23 deg).
      const bool ends = ((f.accepted && near && f.inlier_ratio >= cfg_.min_inlier_ratio) ||
                         (inside && f.inlier_ratio >= cfg_.reacquire_strong_ratio)) && unrivalled;
      std::optional<Impl::Fit> wide;
      if (!ends && cfg_.laser_wide_retry && res.laser_step) wide = m.wheel_window_fit(pts, pred, sxy, syaw);
      if (ends || wide) {
        const Impl::Fit& t = wide ? *wide : f;
        m.hyps.clear();
        m.pose = t.est;
        m.sxy = std::sqrt(std::max(t.cov(0, 0), t.cov(1, 1)));
        m.syaw = std::sqrt(t.cov(2, 2));
        m.poor_run = 0;
        m.search_moved_m = -1;
        res.pose = t.est;
        res.status = GridStatus::kOk;
        res.covariance = t.cov;
        res.inlier_ratio = t.inlier_ratio;
        res.search_xy_m = t.wxy;
        res.search_yaw_rad = t.wyaw;
        return res;
      }
      // Weak, near the prediction: follow it, but keep the dead-reckoned uncertainty (a weak fit does not
      // confirm the pose; shrinking it would narrow the re-acquisition search around a wrong place).
      // Only a correction of this step's odometry, and only when the scan does not also fit elsewhere.
      if (f.accepted && cfg_.follow_weak && (cfg_.follow_weak_when_lost || m.poor_run < cfg_.lost_after) &&
          (!cfg_.weak_follow_step_only || (one_step && unrivalled)))
        pred = f.est;
    }
    m.track_hypotheses(pts);
    // POOR: +-window_sigmas sigma of the dead-reckoned pose; LOST: the whole re-acquisition window (a LOST
    // tracker's own uncertainty is no longer to be trusted: it may have been confirmed at a wrong place).
    const bool lost = m.poor_run >= cfg_.lost_after;
    const bool whole = lost && !cfg_.lost_window_from_sigma;
    const double wide_xy = whole ? cfg_.reacquire_xy_m
                                : std::clamp(cfg_.window_sigmas * sxy, 2 * df.resolution(), cfg_.reacquire_xy_m);
    const double wide_yaw = whole ? cfg_.reacquire_yaw_rad
                                 : std::clamp(cfg_.window_sigmas * syaw, cfg_.search_yaw_step_rad, cfg_.reacquire_yaw_rad);
    res.search_xy_m = wide_xy;
    res.search_yaw_rad = wide_yaw;
    res.inlier_ratio = f.inlier_ratio;
    // New hypotheses: the wide search's distinct candidates, each refined on its own (throttled by the motion
    // since the last one).
    if (inc && m.search_moved_m >= 0) {
      m.search_moved_m += std::hypot(inc->x, inc->y);
      m.search_turned_rad += std::abs(wrap_angle(inc->yaw));
    }
    const bool search_now = m.search_moved_m < 0 || m.search_moved_m >= cfg_.reacquire_search_every_m ||
                            m.search_turned_rad >= cfg_.reacquire_search_every_rad;
    if (search_now) {
      m.search_moved_m = 0;
      m.search_turned_rad = 0;
      res.wide_search = true;
      SearchWindow win;
      win.center = pred;
      win.xy_m = wide_xy;
      win.yaw_rad = wide_yaw;
      win.yaw_step_rad = cfg_.search_yaw_step_rad;
      win.sigma_xy_m = sxy;
      win.sigma_yaw_rad = syaw;
      win.prior_kappa = 0;  // where the robot is after a long dead-reckoning: no preference within the window
      SearchOptions so;
      so.keep = cfg_.reacquire_candidates;
      so.min_ratio = cfg_.candidate_ratio;
      // A pose with min_inlier_ratio of the points within inlier_m scores at least this much: nothing below it
      // can become a hypothesis (prunes most of a wide search where the map does not explain the scan).
      so.min_score = m.hypothesis_min_score();
      const std::vector<Eigen::Vector2d> sp = Impl::search_points(pts);
      // A strong fit (>= reacquire_strong_ratio) within the dead-reckoned window (not yet LOST) that no other
      // candidate comes close to (confirm_margin) ends POOR at once: the map explains the scan almost
      // entirely there and nowhere else nearby (csail: a 30 deg odometry turn error beyond the tracking window).
      std::optional<Impl::Fit> strong;
      double runner_up = 0;
      for (const auto& c : correlative_search(df, *m.pyramid, sp, win, so)) {
        const double s0 = 2 * df.resolution(), y0 = 2 * cfg_.search_yaw_step_rad;
        const Impl::Fit f = m.fit(pts, c.pose, s0, y0, s0, y0, 1, cfg_.min_inlier_ratio);
        if (!lost) {
          if (!strong || f.inlier_ratio > strong->inlier_ratio) {
            if (strong) runner_up = std::max(runner_up, strong->inlier_ratio);
            strong = f;
          } else {
            runner_up = std::max(runner_up, f.inlier_ratio);
          }
        }
        m.add_hypothesis(f, so.sep_xy_m, so.sep_yaw_rad);
      }
      if (strong && strong->inlier_ratio >= cfg_.reacquire_strong_ratio &&
          runner_up < strong->inlier_ratio - cfg_.confirm_margin) {
        m.hyps.clear();
        m.pose = strong->est;
        m.sxy = std::sqrt(std::max(strong->cov(0, 0), strong->cov(1, 1)));
        m.syaw = std::sqrt(strong->cov(2, 2));
        m.poor_run = 0;
        m.search_moved_m = -1;
        res.pose = strong->est;
        res.status = GridStatus::kOk;
        res.covariance = strong->cov;
        res.inlier_ratio = strong->inlier_ratio;
        res.reacquired = true;
        return res;
      }
    }
    std::sort(m.hyps.begin(), m.hyps.end(), [](const auto& a, const auto& b) {
      return a.hits != b.hits ? a.hits > b.hits : a.mean() > b.mean();
    });
    if (int(m.hyps.size()) > cfg_.max_hypotheses) m.hyps.resize(size_t(cfg_.max_hypotheses));
    // A hypothesis is taken only where the calibrated dead reckoning can be (within confirm_within_sigmas of its
    // grown uncertainty): a place the map explains as well but the odometry cannot have reached is a wrong lock.
    // On laser steps the bound is the wheels' model's (the dead-reckoned uncertainty plus what the wheels would
    // have added since the last fit): laser steps that follow a wrong place are self-consistent, so their own
    // sigma says nothing of how far off the dead-reckoned pose may be.
    auto agrees = [&](const Impl::Hypothesis& h) {
      if (cfg_.confirm_within_sigmas <= 0) return true;
      const double gxy2 = sxy * sxy + (res.laser_step ? m.wheel_extra_xy2 : 0.0);
      const double gyaw2 = syaw * syaw + (res.laser_step ? m.wheel_extra_yaw2 : 0.0);
      const double ex = h.pose.x - pred.x, ey = h.pose.y - pred.y, eyaw = wrap_angle(h.pose.yaw - pred.yaw);
      return (ex * ex + ey * ey) / gxy2 + eyaw * eyaw / gyaw2 <= cfg_.confirm_within_sigmas * cfg_.confirm_within_sigmas ||
             (cfg_.far_confirm_travel_m >= 0 && h.travel_m >= cfg_.far_confirm_travel_m &&
              h.mean() >= cfg_.reacquire_strong_ratio);
    };
    if (!m.hyps.empty() && m.hyps[0].hits >= cfg_.confirm_scans && m.hyps[0].mean() >= cfg_.confirm_inlier_ratio &&
        agrees(m.hyps[0]) &&
        (m.hyps.size() == 1 || m.hyps[1].hits < cfg_.confirm_scans - 1 ||
         m.hyps[0].mean() >= m.hyps[1].mean() + cfg_.confirm_margin)) {
      const Impl::Hypothesis h = m.hyps[0];
      m.hyps.clear();
      m.pose = h.pose;
      m.sxy = h.sxy;
      m.syaw = h.syaw;
      m.poor_run = 0;
      m.search_moved_m = -1;
      res.pose = h.pose;
      res.status = GridStatus::kOk;
      res.covariance = Eigen::Vector3d(h.sxy * h.sxy, h.sxy * h.sxy, h.syaw * h.syaw).asDiagonal();
      res.hypotheses = 0;
      res.reacquired = true;
      return res;
    }
    keep_prediction();
    return res;
  }
  m.hyps.clear();
  m.search_moved_m = -1;

  // 3. Tracking: the local fit around the prediction; a failed fit right after a good one is retried once in a
  // wider window (an odometry error beyond the window), taken only when the map supports it on its own.
  Impl::Fit f = m.fit(pts, pred, sxy, syaw, cfg_.max_window_xy_m, cfg_.max_window_yaw_rad,
                      cfg_.refine_candidates, cfg_.min_inlier_ratio);
  if (!f.accepted && m.poor_run == 0 && cfg_.retry_window_factor > 1) {
    const double k = cfg_.retry_window_factor;
    Impl::Fit g = m.fit(pts, pred, k * sxy, k * syaw, k * cfg_.max_window_xy_m, std::min(M_PI, k * cfg_.max_window_yaw_rad),
                        cfg_.refine_candidates, cfg_.min_inlier_ratio);
    if (g.accepted && g.inlier_ratio >= cfg_.min_inlier_ratio) f = std::move(g);
  }
  // On a laser step, a failed fit is also tried in the window the wheels' model gives this step (a laser
  // increment can be wrong by more than its sigma: a large turn), as while re-acquiring.
  if (!f.accepted && m.poor_run == 0 && cfg_.laser_wide_retry && cfg_.laser_track_retry && res.laser_step)
    if (auto g = m.wheel_window_fit(pts, pred, sxy, syaw)) f = std::move(*g);
  res.search_xy_m = f.wxy;
  res.search_yaw_rad = f.wyaw;
  res.candidates = f.leaves;
  res.score = f.score;
  res.iterations = f.iterations;
  res.refined = f.refined;
  res.num_inliers = f.inliers;
  res.inlier_ratio = f.inlier_ratio;
  res.rms_m = f.rms;
  // A matched laser step and a weakly supported map fit far from it disagree: the step is trusted (the fit counts
  // as failed, POOR, towards LOST like any). Far in this step's own sigmas: a retry fit's were widened.
  if (f.accepted && res.laser_step && cfg_.laser_conflict_inlier_ratio > 0 &&
      f.inlier_ratio < cfg_.laser_conflict_inlier_ratio) {
    if (mahalanobis2(f.est, pred, sxy, syaw) > cfg_.gate_sigmas * cfg_.gate_sigmas) f.accepted = false;
  }
  if (f.accepted) {
    res.covariance = f.cov;
    m.pose = f.est;
    m.sxy = std::sqrt(std::max(f.cov(0, 0), f.cov(1, 1)));
    m.syaw = std::sqrt(f.cov(2, 2));
    res.pose = f.est;
    // A weak fit (accepted only because it agrees with the prediction) is followed, but a run of them is a
    // track the map no longer confirms: they count towards LOST (re-acquisition) like failed fits.
    const bool weak = cfg_.reacquire && f.inlier_ratio < cfg_.min_inlier_ratio;
    m.poor_run = weak ? m.poor_run + 1 : 0;
    res.status = weak && m.poor_run >= cfg_.lost_after ? GridStatus::kLost : GridStatus::kOk;
  } else {
    keep_prediction();
  }
  return res;
}

}  // namespace fploc::laser2d
