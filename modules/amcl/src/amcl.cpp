#include "fploc/amcl/amcl.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "fploc/annf/annf.h"
#include "fploc/annf/baselines.h"
#include "fploc/annf/cache.h"

namespace fploc::amcl {

namespace {
// nav2 angleutils::angle_diff(a, b): the smaller signed difference a - b.
double angle_diff(double a, double b) { return wrap_angle(wrap_angle(a) - wrap_angle(b)); }
}  // namespace

void validate(const Config& c) {
  auto bad = [](const std::string& what) { throw std::invalid_argument("amcl: " + what); };
  if (c.min_particles < 1) bad("min_particles must be >= 1");
  if (c.max_particles < c.min_particles) bad("max_particles must be >= min_particles");
  for (double a : {c.alpha1, c.alpha2, c.alpha3, c.alpha4})
    if (!(a >= 0)) bad("alpha1..alpha4 must be >= 0");
  if (!(c.z_hit >= 0) || !(c.z_rand >= 0) || !(c.z_hit + c.z_rand > 0)) bad("z_hit, z_rand must be >= 0, not both 0");
  if (!(c.sigma_hit > 0)) bad("sigma_hit must be > 0");
  if (!(c.laser_likelihood_max_dist > 0)) bad("laser_likelihood_max_dist must be > 0");
  if (c.max_beams < 2) bad("max_beams must be >= 2 (nav2 refuses the update below)");
  if (!(c.update_min_d >= 0) || !(c.update_min_a >= 0)) bad("update_min_d, update_min_a must be >= 0");
  if (c.resample_interval < 1) bad("resample_interval must be >= 1");
  if (!(c.pf_err > 0) || !(c.pf_z > 0)) bad("pf_err, pf_z must be > 0");
  if (!(c.bin_xy > 0) || !(c.bin_yaw > 0)) bad("bin sizes must be > 0");
  if (!(c.recovery_alpha_slow >= 0 && c.recovery_alpha_slow <= 1) || !(c.recovery_alpha_fast >= 0 && c.recovery_alpha_fast <= 1))
    bad("recovery_alpha_slow, recovery_alpha_fast must be in [0, 1]");
  if (!(c.map_resolution > 0)) bad("map_resolution must be > 0");
  if (!(c.converged_dist > 0)) bad("converged_dist must be > 0");
  if (!std::isfinite(c.free_clearance)) bad("free_clearance must be finite");
}

// ---- KLD ------------------------------------------------------------------------------------------
int kld_limit(int k, double err, double z, int min_n, int max_n) {
  if (k <= 1) return max_n;
  const double b = 2.0 / (9.0 * (double(k) - 1.0));
  const double x = 1.0 - b + std::sqrt(b) * z;
  const double n = std::ceil((double(k) - 1.0) / (2.0 * err) * x * x * x);
  if (!(n >= double(min_n))) return min_n;
  if (n > double(max_n)) return max_n;
  return int(n);
}

// ---- bins -----------------------------------------------------------------------------------------
BinSet::BinSet(double bin_xy, double bin_yaw) : bxy_(bin_xy), byaw_(bin_yaw) {
  nyaw_ = int64_t(std::ceil(2 * M_PI / bin_yaw - 1e-9));
  table_.assign(1024, -1);
}

void BinSet::clear() {
  keys_.clear();
  label_.clear();
  std::fill(table_.begin(), table_.end(), -1);
}

BinSet::Key BinSet::key(double x, double y, double yaw) const {
  double a = std::fmod(yaw + M_PI, 2 * M_PI);
  if (a < 0) a += 2 * M_PI;
  int64_t k = int64_t(std::floor(a / byaw_));
  if (k >= nyaw_) k = nyaw_ - 1;
  return {int64_t(std::floor(x / bxy_)), int64_t(std::floor(y / bxy_)), k};
}

uint64_t BinSet::hash(const Key& k) {
  uint64_t h = uint64_t(k.i) * 0x9E3779B97F4A7C15ull;
  h ^= uint64_t(k.j) * 0xC2B2AE3D27D4EB4Full + (h << 6) + (h >> 2);
  h ^= uint64_t(k.k) * 0x165667B19E3779F9ull + (h << 6) + (h >> 2);
  return h ^ (h >> 29);
}

int BinSet::find(const Key& k) const {
  const size_t mask = table_.size() - 1;
  for (size_t s = hash(k) & mask;; s = (s + 1) & mask) {
    const int v = table_[s];
    if (v < 0) return -1;
    const Key& o = keys_[size_t(v)];
    if (o.i == k.i && o.j == k.j && o.k == k.k) return v;
  }
}

void BinSet::grow() {
  table_.assign(table_.size() * 2, -1);
  const size_t mask = table_.size() - 1;
  for (size_t v = 0; v < keys_.size(); ++v) {
    size_t s = hash(keys_[v]) & mask;
    while (table_[s] >= 0) s = (s + 1) & mask;
    table_[s] = int(v);
  }
}

bool BinSet::insert(double x, double y, double yaw) {
  const Key k = key(x, y, yaw);
  if (find(k) >= 0) return false;
  if ((keys_.size() + 1) * 2 > table_.size()) {
    keys_.push_back(k);
    grow();
  } else {
    keys_.push_back(k);
    const size_t mask = table_.size() - 1;
    size_t s = hash(k) & mask;
    while (table_[s] >= 0) s = (s + 1) & mask;
    table_[s] = int(keys_.size() - 1);
  }
  return true;
}

int BinSet::cluster() {
  label_.assign(keys_.size(), -1);
  int n = 0;
  std::vector<int> stack;
  for (size_t b = 0; b < keys_.size(); ++b) {
    if (label_[b] >= 0) continue;
    label_[b] = n;
    stack.assign(1, int(b));
    while (!stack.empty()) {
      const Key c = keys_[size_t(stack.back())];
      stack.pop_back();
      for (int di = -1; di <= 1; ++di)
        for (int dj = -1; dj <= 1; ++dj)
          for (int dk = -1; dk <= 1; ++dk) {
            if (!di && !dj && !dk) continue;
            Key q{c.i + di, c.j + dj, ((c.k + dk) % nyaw_ + nyaw_) % nyaw_};
            const int v = find(q);
            if (v >= 0 && label_[size_t(v)] < 0) {
              label_[size_t(v)] = n;
              stack.push_back(v);
            }
          }
    }
    ++n;
  }
  return n;
}

int BinSet::cluster_of(double x, double y, double yaw) const {
  const int v = find(key(x, y, yaw));
  return v < 0 || size_t(v) >= label_.size() ? -1 : label_[size_t(v)];
}

// ---- cluster statistics (nav2 pf_cluster_stats) ---------------------------------------------------
SetStats cluster_stats(const std::vector<Particle>& ps, BinSet& bins, double converged_dist) {
  SetStats st;
  bins.clear();
  for (const auto& p : ps) bins.insert(p.x, p.y, p.yaw);
  const int nc = bins.cluster();
  struct Acc {
    double w = 0, m[4] = {0, 0, 0, 0}, c[2][2] = {{0, 0}, {0, 0}};
    int n = 0;
  };
  std::vector<Acc> acc(size_t(std::max(nc, 0)));
  Acc all;
  auto add = [](Acc& a, const Particle& p) {
    a.w += p.w;
    ++a.n;
    a.m[0] += p.w * p.x;
    a.m[1] += p.w * p.y;
    a.m[2] += p.w * std::cos(p.yaw);
    a.m[3] += p.w * std::sin(p.yaw);
    const double v[2] = {p.x, p.y};
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 2; ++k) a.c[j][k] += p.w * v[j] * v[k];
  };
  for (const auto& p : ps) {
    const int c = bins.cluster_of(p.x, p.y, p.yaw);
    if (c < 0) continue;
    add(acc[size_t(c)], p);
    add(all, p);
  }
  auto finish = [](const Acc& a, Pose2& mean, Eigen::Matrix3d& cov) {
    cov.setZero();
    if (!(a.w > 0)) return;
    mean = {a.m[0] / a.w, a.m[1] / a.w, std::atan2(a.m[3], a.m[2])};
    const double mv[2] = {mean.x, mean.y};
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 2; ++k) cov(j, k) = a.c[j][k] / a.w - mv[j] * mv[k];
    // nav2 uses the unnormalised resultant (weights sum to 1 there); normalise so it holds for any scale.
    const double r = std::sqrt(a.m[2] * a.m[2] + a.m[3] * a.m[3]) / a.w;
    cov(2, 2) = -2.0 * std::log(std::max(r, 1e-300));
  };
  st.clusters.resize(acc.size());
  double best_w = 0;
  for (size_t i = 0; i < acc.size(); ++i) {
    auto& c = st.clusters[i];
    c.weight = acc[i].w;
    c.count = acc[i].n;
    finish(acc[i], c.mean, c.cov);
    if (c.weight > best_w) {
      best_w = c.weight;
      st.best = int(i);
    }
  }
  finish(all, st.mean, st.cov);
  // nav2 pf_update_converged: unweighted mean, every particle within converged_dist in x and y.
  if (!ps.empty()) {
    double mx = 0, my = 0;
    for (const auto& p : ps) {
      mx += p.x;
      my += p.y;
    }
    mx /= double(ps.size());
    my /= double(ps.size());
    st.converged = std::all_of(ps.begin(), ps.end(), [&](const Particle& p) {
      return std::abs(p.x - mx) <= converged_dist && std::abs(p.y - my) <= converged_dist;
    });
  }
  return st;
}

// ---- resampling helpers --------------------------------------------------------------------------
int sample_index(const std::vector<double>& c, double r) {
  // first i with c[i+1] > r, i.e. c[i] <= r < c[i+1]
  const auto it = std::upper_bound(c.begin() + 1, c.end(), r);
  const int i = int(it - (c.begin() + 1));
  const int n = int(c.size()) - 1;
  return std::clamp(i, 0, n - 1);
}

std::vector<int> low_variance_indices(const std::vector<double>& w, int M, double u0) {
  std::vector<int> out;
  if (w.empty() || M <= 0) return out;
  double total = 0;
  for (double v : w) total += v;
  out.reserve(size_t(M));
  const double step = total / M;
  double c = w[0];
  size_t i = 0;
  for (int m = 0; m < M; ++m) {
    const double U = (u0 + m) * step;
    while (U >= c && i + 1 < w.size()) c += w[++i];
    out.push_back(int(i));
  }
  return out;
}

// ---- likelihood field ----------------------------------------------------------------------------
LikelihoodField::LikelihoodField(const FloorPlan& plan, double resolution, double max_dist)
    : res_(resolution), inv_(1.0 / resolution), max_dist_(max_dist) {
  if (plan.elements.empty()) throw std::runtime_error("amcl: empty floor plan");
  annf::AnnfOptions ao;
  ao.mode = annf::AnnfMode::kExact;
  ao.max_depth = 6;  // only cell centres are read; the exact field is exact everywhere
  const std::shared_ptr<const annf::Annf> exact = annf::cached_annf(plan, ao);  // shared on disk (fploc/annf/cache.h)
  const annf::DistanceGrid grid(*exact, resolution);
  ox_ = grid.origin().x();
  oy_ = grid.origin().y();
  nx_ = grid.nx();
  ny_ = grid.ny();
  dist_.resize(size_t(nx_) * ny_);
  for (uint32_t j = 0; j < ny_; ++j)
    for (uint32_t i = 0; i < nx_; ++i)
      dist_[size_t(j) * nx_ + i] = float(std::min<double>(grid.cell_distance(i, j), max_dist));
}

LikelihoodField::~LikelihoodField() = default;

double LikelihoodField::distance(double x, double y) const {
  const double fx = (x - ox_) * inv_, fy = (y - oy_) * inv_;
  if (!(fx >= 0 && fy >= 0 && fx < double(nx_) && fy < double(ny_))) return max_dist_;
  return dist_[size_t(uint32_t(fy)) * nx_ + uint32_t(fx)];
}

std::vector<Eigen::Vector2d> LikelihoodField::free_cells(double clearance) const {
  if (clearance <= 0) clearance = res_ * std::sqrt(0.5);
  std::vector<Eigen::Vector2d> out;
  for (uint32_t j = 0; j < ny_; ++j)
    for (uint32_t i = 0; i < nx_; ++i)
      if (dist_[size_t(j) * nx_ + i] > clearance) out.emplace_back(ox_ + (i + 0.5) * res_, oy_ + (j + 0.5) * res_);
  return out;
}

const std::vector<float>& LikelihoodField::pz3_table(double z_hit, double z_rand_term, double sigma) const {
  if (pz3_key_[0] == z_hit && pz3_key_[1] == z_rand_term && pz3_key_[2] == sigma && !pz3_.empty()) return pz3_;
  const double denom = 2 * sigma * sigma;
  auto f = [&](double z) {
    const double pz = z_hit * std::exp(-(z * z) / denom) + z_rand_term;
    return float(pz * pz * pz);
  };
  pz3_.resize(dist_.size() + 1);
  for (size_t i = 0; i < dist_.size(); ++i) pz3_[i] = f(dist_[i]);
  pz3_.back() = f(max_dist_);  // off the map: max distance (nav2)
  pz3_key_[0] = z_hit;
  pz3_key_[1] = z_rand_term;
  pz3_key_[2] = sigma;
  return pz3_;
}

// ---- scan conversion -----------------------------------------------------------------------------
LaserScan points_to_scan(const std::vector<Eigen::Vector2d>& points, int bins, double range_min, double range_max,
                         int* skipped) {
  if (bins < 2) throw std::invalid_argument("amcl: scan bins must be >= 2");
  LaserScan s;
  s.angle_min = -M_PI;
  s.angle_increment = 2 * M_PI / bins;
  s.range_min = range_min;
  s.range_max = range_max;
  s.ranges.assign(size_t(bins), std::numeric_limits<float>::infinity());
  int bad = 0;
  for (const auto& p : points) {
    const double r = p.norm();
    if (!std::isfinite(r) || r < range_min || r > range_max) {
      ++bad;
      continue;
    }
    // Nearest beam bearing (bins centred on angle_min + i * increment; pointcloud_to_laserscan truncates,
    // which turns the whole scan by half a bin).
    int i = int(std::lround((std::atan2(p.y(), p.x()) - s.angle_min) / s.angle_increment));
    if (i >= bins) i -= bins;
    i = std::clamp(i, 0, bins - 1);
    if (float(r) < s.ranges[size_t(i)]) s.ranges[size_t(i)] = float(r);
  }
  if (skipped) *skipped = bad;
  return s;
}

// ---- the filter ----------------------------------------------------------------------------------
Amcl::Amcl(const FloorPlan& plan, Config cfg) : cfg_(cfg), rng_(cfg.seed), bins_(cfg.bin_xy, cfg.bin_yaw) {
  validate(cfg_);
  field_ = std::make_unique<LikelihoodField>(plan, cfg_.map_resolution, cfg_.laser_likelihood_max_dist);
  free_ = field_->free_cells(cfg_.free_clearance);
  if (free_.empty()) throw std::runtime_error("amcl: the plan has no free cells (free_clearance too large?)");
  set_.reserve(size_t(cfg_.max_particles));
  next_.reserve(size_t(cfg_.max_particles));
}

Amcl::~Amcl() = default;

Particle Amcl::random_pose() {
  // nav2 uniformPoseGenerator (NEW_UNIFORM_SAMPLING): a random free cell's centre, uniform yaw.
  const size_t i = std::min(free_.size() - 1, size_t(rng_.uniform() * double(free_.size())));
  Particle p;
  p.x = free_[i].x();
  p.y = free_[i].y();
  p.yaw = rng_.uniform() * 2 * M_PI - M_PI;
  return p;
}

void Amcl::init_pose(const Pose2& mean, const Eigen::Matrix3d& cov_in) {
  if (!finite(mean) || !cov_in.allFinite()) throw std::invalid_argument("amcl: non-finite initial pose or covariance");
  // nav2 pf_pdf_gaussian_sample: eigen-decompose the covariance, sample independent normals along the axes.
  const Eigen::Matrix3d cov = 0.5 * (cov_in + cov_in.transpose());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  const Eigen::Vector3d sd = es.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  const Eigen::Matrix3d R = es.eigenvectors();
  set_.assign(size_t(cfg_.max_particles), Particle{});
  for (auto& p : set_) {
    Eigen::Vector3d v(rng_.gaussian(sd[0]), rng_.gaussian(sd[1]), rng_.gaussian(sd[2]));
    v = R * v;
    p.x = mean.x + v[0];
    p.y = mean.y + v[1];
    p.yaw = wrap_angle(mean.yaw + v[2]);
    p.w = 1.0 / cfg_.max_particles;
  }
  start_from_set();
}

void Amcl::init_global() {
  set_.resize(size_t(cfg_.max_particles));
  for (auto& p : set_) {
    p = random_pose();
    p.w = 1.0 / cfg_.max_particles;
  }
  start_from_set();
}

// A freshly drawn particle set (pf_init / global localization): averages reset, statistics and the
// estimate of the new set, and the next scan takes the odometry reference.
void Amcl::start_from_set() {
  w_slow_ = w_fast_ = 0;
  compute_stats();
  initialised_ = true;
  pf_init_ = false;
  have_estimate_ = false;
  estimate_ = select_estimate();
}

void Amcl::compute_stats() { stats_ = cluster_stats(set_, bins_, cfg_.converged_dist); }

void Amcl::motion_update(const Pose2& old_pose, const Pose2& pose) {
  // nav2 DifferentialMotionModel::odometryUpdate (Probabilistic Robotics p. 136, sample_motion_model_odometry).
  const double dx = pose.x - old_pose.x, dy = pose.y - old_pose.y;
  const double dyaw = angle_diff(pose.yaw, old_pose.yaw);
  const double delta_trans = std::sqrt(dx * dx + dy * dy);
  const double delta_rot1 = delta_trans < 0.01 ? 0.0 : angle_diff(std::atan2(dy, dx), old_pose.yaw);
  const double delta_rot2 = angle_diff(dyaw, delta_rot1);
  // Forward and backward motion treated alike (nav2).
  const double rot1_noise = std::min(std::abs(angle_diff(delta_rot1, 0.0)), std::abs(angle_diff(delta_rot1, M_PI)));
  const double rot2_noise = std::min(std::abs(angle_diff(delta_rot2, 0.0)), std::abs(angle_diff(delta_rot2, M_PI)));
  const double a1 = cfg_.alpha1, a2 = cfg_.alpha2, a3 = cfg_.alpha3, a4 = cfg_.alpha4;
  const double sd_rot1 = std::sqrt(a1 * rot1_noise * rot1_noise + a2 * delta_trans * delta_trans);
  const double sd_trans =
      std::sqrt(a3 * delta_trans * delta_trans + a4 * rot1_noise * rot1_noise + a4 * rot2_noise * rot2_noise);
  const double sd_rot2 = std::sqrt(a1 * rot2_noise * rot2_noise + a2 * delta_trans * delta_trans);
  for (auto& p : set_) {
    const double rot1_hat = angle_diff(delta_rot1, rng_.gaussian(sd_rot1));
    const double trans_hat = delta_trans - rng_.gaussian(sd_trans);
    const double rot2_hat = angle_diff(delta_rot2, rng_.gaussian(sd_rot2));
    p.x += trans_hat * std::cos(p.yaw + rot1_hat);
    p.y += trans_hat * std::sin(p.yaw + rot1_hat);
    p.yaw = wrap_angle(p.yaw + rot1_hat + rot2_hat);
  }
}

int Amcl::sensor_update(const LaserScan& scan) {
  // nav2 AmclNode::updateFilter + LikelihoodFieldModel::sensorFunction.
  double range_max = scan.range_max;
  if (cfg_.laser_max_range > 0) range_max = std::min(range_max, cfg_.laser_max_range);
  double range_min = scan.range_min;
  if (cfg_.laser_min_range > 0) range_min = std::max(range_min, cfg_.laser_min_range);
  if (!(range_max > 0) || !std::isfinite(range_max)) return 0;
  const int n = int(scan.ranges.size());
  int step = n > 1 ? (n - 1) / (cfg_.max_beams - 1) : 1;
  if (step < 1) step = 1;
  // Beam end points in the sensor frame (the sensor is the robot's reference point here).
  thread_local std::vector<Eigen::Vector2d> beams;
  beams.clear();
  for (int i = 0; i < n; i += step) {
    double r = scan.ranges[size_t(i)];
    if (r <= range_min) r = range_max;  // nav2 maps short readings to max range (then skipped)
    if (r >= range_max || r != r) continue;
    const double b = scan.angle_min + i * scan.angle_increment;
    beams.emplace_back(r * std::cos(b), r * std::sin(b));
  }
  if (beams.empty()) return 0;
  const auto& table = field_->pz3_table(cfg_.z_hit, cfg_.z_rand / range_max, cfg_.sigma_hit);
  double total = 0;
  for (auto& p : set_) {
    const double c = std::cos(p.yaw), s = std::sin(p.yaw);
    double q = 1.0;
    for (const auto& e : beams) q += field_->pz3(table, p.x + c * e.x() - s * e.y(), p.y + s * e.x() + c * e.y());
    p.w *= q;
    total += p.w;
  }
  // nav2 pf_update_sensor.
  if (total > 0) {
    double w_avg = 0;
    for (auto& p : set_) {
      w_avg += p.w;
      p.w /= total;
    }
    w_avg /= double(set_.size());
    w_slow_ = w_slow_ == 0.0 ? w_avg : w_slow_ + cfg_.recovery_alpha_slow * (w_avg - w_slow_);
    w_fast_ = w_fast_ == 0.0 ? w_avg : w_fast_ + cfg_.recovery_alpha_fast * (w_avg - w_fast_);
  } else {
    for (auto& p : set_) p.w = 1.0 / double(set_.size());
  }
  return int(beams.size());
}

void Amcl::resample() {
  // nav2 pf_update_resample.
  const size_t na = set_.size();
  cumulative_.assign(na + 1, 0.0);
  for (size_t i = 0; i < na; ++i) cumulative_[i + 1] = cumulative_[i] + set_[i].w;
  double w_diff = w_slow_ > 0 ? 1.0 - w_fast_ / w_slow_ : 0.0;
  if (!(w_diff > 0)) w_diff = 0.0;
  next_.clear();
  bins_.clear();
  auto limit_reached = [&]() { return int(next_.size()) > kld_limit(bins_.size(), cfg_.pf_err, cfg_.pf_z, cfg_.min_particles, cfg_.max_particles); };
  if (cfg_.resampler == Resampler::kMultinomial) {
    while (int(next_.size()) < cfg_.max_particles) {
      Particle q;
      if (rng_.uniform() < w_diff) {
        q = random_pose();
      } else {
        q = set_[size_t(sample_index(cumulative_, rng_.uniform() * cumulative_.back()))];
      }
      q.w = 1.0;
      next_.push_back(q);
      bins_.insert(q.x, q.y, q.yaw);
      if (limit_reached()) break;
    }
  } else {
    // Dry run: the same KLD loop decides how many particles (and which are random); then the drawn ones
    // are replaced by one low-variance pass over the weights.
    std::vector<char> is_random;
    while (int(next_.size()) < cfg_.max_particles) {
      Particle q;
      const bool rnd = rng_.uniform() < w_diff;
      q = rnd ? random_pose() : set_[size_t(sample_index(cumulative_, rng_.uniform() * cumulative_.back()))];
      q.w = 1.0;
      next_.push_back(q);
      is_random.push_back(rnd);
      bins_.insert(q.x, q.y, q.yaw);
      if (limit_reached()) break;
    }
    int drawn = 0;
    for (char r : is_random) drawn += r ? 0 : 1;
    std::vector<double> w(na);
    for (size_t i = 0; i < na; ++i) w[i] = set_[i].w;
    const std::vector<int> idx = low_variance_indices(w, drawn, rng_.uniform());
    size_t k = 0;
    for (size_t m = 0; m < next_.size(); ++m)
      if (!is_random[m]) {
        next_[m] = set_[size_t(idx[k++])];
        next_[m].w = 1.0;
      }
  }
  if (w_diff > 0) w_slow_ = w_fast_ = 0.0;  // nav2: avoid spiralling into complete randomness
  const double inv = 1.0 / double(next_.size());
  for (auto& p : next_) p.w = inv;
  set_.swap(next_);
  compute_stats();
}

Pose2 Amcl::estimate() const { return estimate_; }

Pose2 Amcl::select_estimate() const {
  if (cfg_.estimate == EstimateMode::kBestCluster && stats_.best >= 0) return stats_.clusters[size_t(stats_.best)].mean;
  return stats_.mean;
}

void Amcl::publish(const Pose2& odom) {
  estimate_ = select_estimate();
  // nav2 calculateMaptoOdomTransform: map->odom = estimate * odom^-1 at the scan's odometry pose.
  map_to_odom_ = compose(estimate_, inverse(odom));
  have_estimate_ = true;
}

Pose2 Amcl::pose_at(const Pose2& odom) const {
  if (!have_estimate_) return estimate_;
  return compose(map_to_odom_, odom);
}

StepInfo Amcl::process(const Pose2& odom, const LaserScan& scan) {
  StepInfo info;
  if (!initialised_) {
    info.problem = "filter not initialised (no initial pose, no global initialisation)";
    return info;
  }
  if (!finite(odom)) {
    info.problem = "non-finite odometry pose (scan ignored)";
    info.particles = int(set_.size());
    return info;
  }
  bool force_publication = false, update = false;
  if (!pf_init_) {
    pf_odom_pose_ = odom;
    pf_init_ = true;
    update = true;
    force_publication = true;
    resample_count_ = 0;
  } else {
    const double dx = odom.x - pf_odom_pose_.x, dy = odom.y - pf_odom_pose_.y;
    const double da = angle_diff(odom.yaw, pf_odom_pose_.yaw);
    update = std::abs(dx) > cfg_.update_min_d || std::abs(dy) > cfg_.update_min_d || std::abs(da) > cfg_.update_min_a;
    if (update) motion_update(pf_odom_pose_, odom);
  }
  if (update) {
    info.updated = true;
    info.beams_used = sensor_update(scan);
    pf_odom_pose_ = odom;
    if (info.beams_used == 0) {
      // Nothing to weigh the particles with: prediction only (no resampling, which would only throw away
      // diversity). nav2 would run the update with p = 1 for every particle and resample anyway.
      info.problem = "scan has no usable beam (empty, all NaN or out of range): motion update only";
    } else if (++resample_count_ % cfg_.resample_interval == 0) {
      resample();
      info.resampled = true;
    }
  }
  if (info.resampled || force_publication) {
    publish(odom);
    info.published = true;
  }
  info.particles = int(set_.size());
  return info;
}

}  // namespace fploc::amcl
