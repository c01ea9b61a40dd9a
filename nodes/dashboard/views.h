// The dashboard's views: one message (or the node table) -> the JSON the page reads. Pure functions; the
// LCM types are only forward-declared here (their headers are included by views.cpp alone).
#pragma once
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>

namespace fploc {
class pose_t;
class frame_pose_t;
class features_t;
class ground_truth_t;
class node_status_t;
}  // namespace fploc

namespace fploc::dashboard {

struct Rpy {
  double roll = 0, pitch = 0, yaw = 0;
};
// ZYX roll/pitch/yaw of a quaternion x y z w (core's StampedPose::rpy); all 0 for a zero quaternion.
Rpy rpy_of(const double q[4]);

struct AteFigure {
  std::optional<double> err;  // this estimate's error, once matched
  double rmse = 0;            // NaN before the first match
  size_t n = 0;
};

std::string pose_view(const fploc::pose_t& m, const Rpy& r, const AteFigure& ate, int64_t rx_wall_us);
std::string ground_truth_view(const fploc::ground_truth_t& m, const Rpy& r, const AteFigure& ate, int64_t rx_wall_us);
std::string frame_pose_view(const fploc::frame_pose_t& m, double frame_rate_hz, int64_t rx_wall_us);
// Features in the sensor frame, decimated to at most max_points, with the frame pose to project them.
std::string features_view(const fploc::features_t& m, size_t max_points, const std::string& pose_json);
std::string frame_pose_for_features(const fploc::frame_pose_t& fp, int64_t features_scan_seq);

// One row of the node table: its latest status, how long ago it arrived, and health.
struct NodeRow {
  const fploc::node_status_t* status = nullptr;
  double age_s = 0;
  bool seen = false;
};
std::string nodes_view(const std::map<std::string, NodeRow>& rows, double silent_after_s, int64_t wall_us);

// JSON numbers: finite values only (NaN/inf become null); rounded to micro-units.
double r6(double v);

}  // namespace fploc::dashboard
