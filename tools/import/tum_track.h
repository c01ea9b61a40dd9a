// A trajectory out of a recording as a TUM file ("t x y z qx qy qz qw", t in seconds): either the
// transform parent -> child from tf (composed along the tf tree when the two are not directly linked,
// using the latest transform of every other edge), or the poses of a nav_msgs/Odometry topic.
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
  // Each transform of a tf message; writes a pose when parent -> child is known at this time.
  void tf(const rec::Transform& t);
  void odometry(const rec::Odometry& o);
  void close();
  uint64_t poses() const { return poses_; }

 private:
  void write(int64_t t_ns, const Eigen::Isometry3d& T);
  bool lookup(const std::string& from, const std::string& to, Eigen::Isometry3d& T) const;
  std::FILE* f_ = nullptr;
  std::string parent_, child_;
  std::map<std::string, std::pair<std::string, Eigen::Isometry3d>> edges_;  // child -> (parent, T_parent_child)
  uint64_t poses_ = 0;
  int64_t last_t_ = -1;
};

}  // namespace fploc::import
