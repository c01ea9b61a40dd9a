// A trajectory out of a recording as a TUM file ("t x y z qx qy qz qw", t in seconds): either the
// transform parent -> child from tf (written at close(), at each stamp of an edge between the two frames, each
// edge interpolated at that time: tf_tree.h; no pose before every edge on the path has a sample), or the poses
// of a nav_msgs/Odometry topic.
#pragma once
#include <Eigen/Geometry>
#include <cstdio>
#include <string>

#include "fploc/recording/ros_msgs.h"
#include "tf_tree.h"

namespace fploc::import {

class TumTrack {
 public:
  bool open(const std::string& path, const std::string& parent, const std::string& child);
  void tf(const rec::Transform& t);  // each transform of a tf message
  void odometry(const rec::Odometry& o);
  void close();  // writes the tf trajectory
  uint64_t poses() const { return poses_; }

 private:
  void write(int64_t t_ns, const Eigen::Isometry3d& T);
  std::FILE* f_ = nullptr;
  std::string parent_, child_;
  TfTree tree_;
  uint64_t poses_ = 0;
  int64_t last_t_ = -1;
};

}  // namespace fploc::import
