// The accuracy bound of localizing against a plan whose walls stand a little off their drawn place ("as built").
//
// Model (the one the simulator's as-built worlds are drawn from, modules/sim perturb.h): every plan vertex (the
// joint of the walls that meet there) is displaced by an independent N(0, sigma^2 I) in x and y; the walls stay
// straight and joined; a pillar's centre moves likewise. A scan sees points on the world's walls. Anything that
// knows only the plan cannot tell the scan's pose error from the displacements of the walls it sees, so even the
// best estimator of a scan's pose (knowing the model and sigma exactly, with the displacements as unknowns under
// their prior) is off by an error whose covariance, for this linear Gaussian model, is exactly
//   ( J'J/s_p^2  -  J'A/s_p^2 (A'A/s_p^2 + I/sigma^2)^-1 A'J/s_p^2 )^-1
// with J the points' normal residuals' derivatives by the pose (x, y, yaw about the sensor), A by the vertex
// displacements and s_p the points' own noise. Its rms over a run is the ATE a localizer cannot beat scan by scan
// on that world's plan.
//
// A window of scans whose poses are known exactly relative to each other (perfect odometry) shares one pose
// error and sees the same walls from several places: its bound is lower, and is what a localizer that smooths
// over that window could reach at best.
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <map>
#include <tuple>
#include <vector>

#include "fploc/floorplan/plan.h"

namespace fploc::eval {

struct AsBuiltBoundOptions {
  double vertex_sigma_m = 0.02;  // each plan vertex (and pillar centre) off by N(0, sigma^2) in x and in y
  double point_sigma_m = 0.01;   // the points' own noise along the element's normal
  double gate_m = 0;             // a point belongs to the nearest element within this; 0: max(0.08, 4 sigma)
};

struct ScanBound {
  Eigen::Matrix3d cov = Eigen::Matrix3d::Constant(std::numeric_limits<double>::quiet_NaN());  // x, y [m], yaw [rad]
  int points = 0;    // points on an element
  int elements = 0;  // elements seen
  bool ok() const { return cov.allFinite(); }
  double xy_rms_m() const { return std::sqrt(cov(0, 0) + cov(1, 1)); }  // expected horizontal error
};

class AsBuiltBound {
 public:
  // Throws std::invalid_argument when vertex_sigma_m or point_sigma_m is not > 0.
  AsBuiltBound(const FloorPlan& plan, const AsBuiltBoundOptions& o = {});
  // One scan: `pose` its true pose in the plan frame (x, y, yaw), `points` its 2D points in the sensor frame (e.g.
  // the features). Points farther than the gate from every element are left out (clutter). Returns its index.
  int add_scan(const Eigen::Vector3d& pose, const std::vector<Eigen::Vector2d>& points);
  int scans() const { return int(scans_.size()); }
  // The bound of the scans first..last (inclusive) sharing one pose error, expressed at scan `at`'s position.
  // Not ok() when their points leave a direction of the pose unconstrained.
  ScanBound bound(int first, int last, int at) const;
  ScanBound bound(int scan) const { return bound(scan, scan, scan); }

 private:
  struct Scan {
    Eigen::Vector2d sensor;
    std::vector<int> disp;   // global displacement ids of the local blocks
    Eigen::Matrix3d hpp;     // information, pose about the sensor
    Eigen::MatrixXd hpv;     // 3 x 2 disp.size()
    Eigen::MatrixXd hvv;     // 2 disp.size() square
    int points = 0;
    std::vector<int> elements;
  };
  const FloorPlan& plan_;
  AsBuiltBoundOptions o_;
  double gate_;
  std::map<std::tuple<int, long, long>, int> index_;  // a displacement's id (joint or pillar)
  std::vector<Scan> scans_;
};

// One scan on its own (AsBuiltBound with that scan alone).
ScanBound asbuilt_scan_bound(const FloorPlan& plan, const Eigen::Vector3d& pose,
                             const std::vector<Eigen::Vector2d>& points, const AsBuiltBoundOptions& o = {});

}  // namespace fploc::eval
