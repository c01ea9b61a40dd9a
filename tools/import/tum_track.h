// A trajectory out of a recording as a TUM file ("t x y z qx qy qz qw", t in seconds): either the
// transform parent -> child from tf, or the poses of a nav_msgs/Odometry topic.
// tf: every transform of every edge is kept (stamp, translation, rotation); at close() the pose is
// written at each stamp of an edge between the two frames (joined at their first common ancestor),
// every edge INTERPOLATED at that time (translation linear, rotation slerp) between its two bracketing
// samples, so a sparse edge (map -> odom at 1 Hz beside odom -> base_link at 50 Hz) does not hold a stale
// value. Outside an edge's sampled span its nearest sample holds (a single sample = a static edge);
// no pose before every edge on the path has a sample.
#pragma once
#include <Eigen/Geometry>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "fploc/recording/ros_msgs.h"

namespace fploc::import {

class TumTrack {
 public:
  bool open(const std::string& path, const std::string& parent, const std::string& child);
  void tf(const rec::Transform& t);  // each transform of a tf message
  void odometry(const rec::Odometry& o);
  void close();  // writes the tf trajectory
  uint64_t poses() const { return poses_; }

  struct Sample {
    int64_t t_ns;
    Eigen::Vector3d p;
    Eigen::Quaterniond q;
  };
  struct Edge {
    std::string parent;
    std::vector<Sample> samples;
  };
  // T_parent_child of an edge at time t (interpolated; nearest sample outside the span).
  static Eigen::Isometry3d at(const Edge& e, int64_t t_ns);

 private:
  void write(int64_t t_ns, const Eigen::Isometry3d& T);
  std::FILE* f_ = nullptr;
  std::string parent_, child_;
  std::map<std::string, Edge> edges_;  // by child frame
  uint64_t poses_ = 0;
  int64_t last_t_ = -1;
};

}  // namespace fploc::import
