// AMCL as ROS 2 nav2 runs it (nav2_amcl: Thrun, Burgard, Fox, Probabilistic Robotics ch. 4, 5, 6, 8;
// Fox 2003 for KLD-sampling), on a floor plan instead of an occupancy grid. No LCM.
//
// What one call of Amcl::process(odom, scan) does is nav2's AmclNode::laserReceived():
//  - first scan after an initialisation: remember the odometry pose, force a filter update;
//  - otherwise update only when the odometry moved |dx| or |dy| > update_min_d or |dyaw| > update_min_a
//    since the last update (per axis, as nav2's shouldUpdateFilter), then
//      motion update: sample_motion_model_odometry, nav2's "differential" model with alpha1..alpha4,
//      sensor update: likelihood field (z_hit Gaussian of the distance to the nearest plan element, capped
//        at laser_likelihood_max_dist, + z_rand / range_max), max_beams evenly spaced beams, combined with
//        nav2's p = 1 + sum pz^3; w_slow / w_fast running averages (recovery),
//      resampling every resample_interval updates: KLD-sampling (bins 0.5 m x 0.5 m x 10 deg, pf_err,
//        pf_z) between min and max particles, random poses from the free space with probability
//        max(0, 1 - w_fast / w_slow);
//  - after a resampling: clusters (connected occupied bins), estimate = mean of the cluster with the
//    largest weight (or the weighted mean of all particles), covariance = the whole set's (as nav2
//    publishes it), and the map -> odom correction. pose_at(odom) = correction * odom is what a nav2 user
//    reads from TF (map -> base) at every scan.
// Deviations from nav2 are listed in docs/notes/amcl.md.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "fploc/core/rng.h"
#include "fploc/core/pose.h"
#include "fploc/floorplan/plan.h"

namespace fploc::amcl {

// ---- small SE(2) helpers (compose / inverse / between: fploc/core/pose.h) ------------------------
inline bool finite(const Pose2& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.yaw); }

// ---- configuration (defaults = nav2's parameter defaults) ------------------------------------------
enum class Resampler { kMultinomial, kLowVariance };
enum class EstimateMode { kBestCluster, kWeightedMean };

struct Config {
  int min_particles = 500;
  int max_particles = 2000;
  // Odometry noise, nav2 "differential" model: alpha1 rot<-rot, alpha2 rot<-trans, alpha3 trans<-trans,
  // alpha4 trans<-rot.
  double alpha1 = 0.2, alpha2 = 0.2, alpha3 = 0.2, alpha4 = 0.2;
  // Likelihood field.
  double z_hit = 0.5, z_rand = 0.5, sigma_hit = 0.2;
  double laser_likelihood_max_dist = 2.0;
  int max_beams = 60;
  double laser_max_range = 100.0;  // <= 0: the scan's range_max
  double laser_min_range = -1.0;   // <= 0: the scan's range_min
  // Update thresholds.
  double update_min_d = 0.25, update_min_a = 0.2;
  int resample_interval = 1;
  // KLD-sampling: pf_err and pf_z. nav2 passes pf_z (0.99) straight in as the normal quantile z of
  // Fox's bound (it is *not* converted from a probability); kept as nav2 does.
  double pf_err = 0.05, pf_z = 0.99;
  double bin_xy = 0.5, bin_yaw = 10.0 * M_PI / 180.0;  // nav2 pf_kdtree cell size
  // Recovery (random particles): 0 = off (nav2 default).
  double recovery_alpha_slow = 0.0, recovery_alpha_fast = 0.0;
  // nav2 draws each new particle independently (its pf.c says low-variance "can't easily" be combined
  // with KLD); kLowVariance: the KLD count from a dry run, then Probabilistic Robotics' low-variance sampler.
  Resampler resampler = Resampler::kMultinomial;
  EstimateMode estimate = EstimateMode::kBestCluster;
  double converged_dist = 0.5;     // nav2 pf dist_threshold: converged = every particle within this of the mean (x and y)
  // Map: cell size of the likelihood field (distance from each cell centre to the nearest plan element).
  double map_resolution = 0.05;
  // Global initialisation / random particles: free cells = cells of the plan's bounding box whose centre
  // is farther than this from every element (<= 0: half a cell diagonal, i.e. not occupied in the map
  // `fploc map export-pgm` writes, where everything that is not a wall is free).
  double free_clearance = 0.0;
  uint64_t seed = 1;
};

// Throws std::invalid_argument naming the field.
void validate(const Config& c);

// ---- pieces (exposed for tests) ------------------------------------------------------------------
struct Particle {
  double x = 0, y = 0, yaw = 0, w = 0;
};

// Fox's KLD bound as nav2's pf_resample_limit: samples needed for k occupied bins (k <= 1: max_n).
int kld_limit(int k, double err, double z, int min_n, int max_n);

// Occupied (x, y, yaw) bins of a particle set and their connected components (26-neighbourhood, yaw bins
// adjacent across +-pi), as nav2's pf_kdtree does for KLD-sampling and clustering.
class BinSet {
 public:
  BinSet(double bin_xy, double bin_yaw);
  // Adds a pose; true when its bin was empty.
  bool insert(double x, double y, double yaw);
  int size() const { return int(keys_.size()); }
  void clear();
  // Cluster label per bin (in insertion order), computed by cluster(); bin_of() finds a pose's bin.
  int cluster();  // returns the number of clusters
  int cluster_of(double x, double y, double yaw) const;

 private:
  struct Key {
    int64_t i, j, k;
  };
  Key key(double x, double y, double yaw) const;
  static uint64_t hash(const Key& k);
  int find(const Key& k) const;
  double bxy_, byaw_;
  int64_t nyaw_;
  std::vector<Key> keys_;
  std::vector<int> label_;
  // open addressing, value = index into keys_ (-1 empty)
  std::vector<int> table_;
  void grow();
};

struct Cluster {
  double weight = 0;
  int count = 0;
  Pose2 mean;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
};

struct SetStats {
  Pose2 mean;                                    // weighted mean of all particles (yaw: circular)
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero(); // x, y linear; yaw = -2 ln |mean resultant| (nav2)
  std::vector<Cluster> clusters;
  int best = -1;                                 // cluster of largest weight
  bool converged = false;
};

// nav2 pf_cluster_stats on a weighted set.
SetStats cluster_stats(const std::vector<Particle>& ps, BinSet& bins, double converged_dist);

// Index i with c[i] <= r < c[i+1] in a cumulative table c[0..n] (nav2's "naive discrete event sampler").
int sample_index(const std::vector<double>& cumulative, double r);
// Probabilistic Robotics Table 4.4: m = 0..M-1 picks the particle whose cumulative weight interval holds
// (u0 + m) / M, u0 in [0, 1). Weights need not be normalised.
std::vector<int> low_variance_indices(const std::vector<double>& weights, int M, double u0);

// The likelihood field: per cell of `resolution` metres over the plan's bounding box, the distance from
// the cell centre to the nearest element (exact, via modules/annf), capped at max_dist; outside: max_dist.
class LikelihoodField {
 public:
  LikelihoodField(const FloorPlan& plan, double resolution, double max_dist);
  ~LikelihoodField();
  double distance(double x, double y) const;
  double resolution() const { return res_; }
  double max_dist() const { return max_dist_; }
  // Centres of the cells whose distance exceeds `clearance` (the free space for uniform sampling).
  std::vector<Eigen::Vector2d> free_cells(double clearance) const;
  // pz^3 table for one (z_hit, z_rand / range_max, sigma) (built lazily, reused while they stay the same).
  const std::vector<float>& pz3_table(double z_hit, double z_rand_term, double sigma_hit) const;
  float pz3(const std::vector<float>& table, double x, double y) const {
    const double fx = (x - ox_) * inv_, fy = (y - oy_) * inv_;
    if (!(fx >= 0 && fy >= 0 && fx < double(nx_) && fy < double(ny_))) return table.back();
    return table[size_t(uint32_t(fy)) * nx_ + uint32_t(fx)];
  }

 private:
  double ox_ = 0, oy_ = 0, res_ = 0.05, inv_ = 20, max_dist_ = 2;
  uint32_t nx_ = 0, ny_ = 0;
  std::vector<float> dist_;  // capped distance per cell
  mutable std::vector<float> pz3_;
  mutable double pz3_key_[3] = {-1, -1, -1};
};

// ---- the scan ----------------------------------------------------------------------------------
// A planar laser scan as sensor_msgs/LaserScan: ranges[i] at bearing angle_min + i * angle_increment
// (sensor frame). Readings >= range_max, <= range_min or NaN are not used (nav2).
struct LaserScan {
  double angle_min = -M_PI;
  double angle_increment = 2 * M_PI / 360;
  double range_min = 0.0;
  double range_max = 100.0;
  std::vector<float> ranges;
};

// 2D points (sensor frame, e.g. the features) -> LaserScan the way pointcloud_to_laserscan does it: `bins`
// beams over [-pi, pi), each the nearest point within half a bin of its bearing, no point = +inf. Non-finite points are skipped
// (*skipped counts them and the points outside [range_min, range_max]).
LaserScan points_to_scan(const std::vector<Eigen::Vector2d>& points, int bins, double range_min, double range_max,
                         int* skipped = nullptr);

// ---- the filter --------------------------------------------------------------------------------
struct StepInfo {
  bool updated = false;     // motion + sensor update ran
  bool resampled = false;
  bool published = false;   // a new estimate (nav2 publishes amcl_pose only then)
  int beams_used = 0;       // valid beams of the scan the sensor model used
  int particles = 0;
  std::string problem;      // non-empty: what was wrong with the input (the step still completed)
};

class Amcl {
 public:
  Amcl(const FloorPlan& plan, Config cfg);
  ~Amcl();
  Amcl(const Amcl&) = delete;
  Amcl& operator=(const Amcl&) = delete;

  // nav2 pf_init: max_particles particles from N(mean, cov) (cov 3x3 x, y, yaw).
  void init_pose(const Pose2& mean, const Eigen::Matrix3d& cov);
  // nav2 global localisation: max_particles particles uniform over the free cells, yaw uniform.
  void init_global();

  // One scan with the odometry pose at its time (any fixed odometry frame).
  StepInfo process(const Pose2& odom, const LaserScan& scan);

  // Estimate at a scan: map -> odom correction of the last estimate applied to this odometry pose.
  Pose2 pose_at(const Pose2& odom) const;
  const SetStats& stats() const { return stats_; }
  Pose2 estimate() const;               // last published estimate (map frame, at its update)
  const std::vector<Particle>& particles() const { return set_; }
  bool initialised() const { return initialised_; }
  size_t free_cells() const { return free_.size(); }
  const Config& config() const { return cfg_; }
  const LikelihoodField& field() const { return *field_; }
  double w_slow() const { return w_slow_; }
  double w_fast() const { return w_fast_; }

  // Steps (public for tests).
  void motion_update(const Pose2& old_odom, const Pose2& new_odom);
  // Returns the number of beams used (0: weights unchanged).
  int sensor_update(const LaserScan& scan);
  void resample();

 private:
  Particle random_pose();
  void start_from_set();
  void compute_stats();
  Pose2 select_estimate() const;
  void publish(const Pose2& odom);

  Config cfg_;
  std::unique_ptr<LikelihoodField> field_;
  std::vector<Eigen::Vector2d> free_;
  PolarRng rng_;
  std::vector<Particle> set_, next_;
  BinSet bins_;
  SetStats stats_;
  std::vector<double> cumulative_;
  double w_slow_ = 0, w_fast_ = 0;
  bool initialised_ = false;   // a distribution exists
  bool pf_init_ = false;       // nav2 pf_init_: odometry reference taken
  Pose2 pf_odom_pose_;
  int resample_count_ = 0;
  Pose2 map_to_odom_;
  bool have_estimate_ = false;
  Pose2 estimate_;
};

}  // namespace fploc::amcl
