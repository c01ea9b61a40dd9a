// The tf frames of a recording: every transform of every edge kept (stamp, translation, rotation), and the
// transform between two frames at a time, joined at their first common ancestor, each edge interpolated at
// that time (translation linear, rotation slerp) between its two bracketing samples; outside an edge's sampled
// span its nearest sample holds (a single sample = a static edge). Frame names: a leading '/' is ignored.
#pragma once
#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "fploc/recording/ros_msgs.h"

namespace fploc::import {

class TfTree {
 public:
  struct Sample {
    int64_t t_ns;
    Eigen::Vector3d p;
    Eigen::Quaterniond q;
  };
  struct Edge {
    std::string parent;
    std::vector<Sample> samples;  // by time once sorted
    // With a sample gap: the newest time the last kept value was published again (repeats are not kept, but how long a
    // value held is: kept as a sample of that value at this time when the value changes, and by sort()).
    int64_t held_until_ns = INT64_MIN;
  };
  // The edges between two frames: from each up to their first common ancestor.
  struct Path {
    std::vector<const Edge*> up_parent, up_child;
    int64_t start_ns = 0;        // the first time every edge has a sample
    std::set<int64_t> times_ns;  // every sample time of the path's edges
  };

  // min_sample_gap_ns > 0: an edge keeps a sample only that long after its last one, and only when it differs from
  // it (bounded memory over long recordings, for uses that do not need every stamp). A value published again and
  // again is kept as two samples, its first and its last time before it changed (or the last time, at sort()): the
  // edge holds it all that time, not drifting towards the next value from its first stamp on.
  explicit TfTree(int64_t min_sample_gap_ns = 0) : gap_ns_(min_sample_gap_ns) {}
  void add(const rec::Transform& t);
  // Sorts each edge's samples by time (call after the last add, before path/at); with a sample gap, first keeps each
  // edge's last value until the last time it was published.
  void sort();
  bool has(const std::string& frame) const;
  std::set<std::string> frames() const;
  // The path from parent to child; nullopt when they are not connected (or a frame is unknown).
  std::optional<Path> path(const std::string& parent, const std::string& child) const;
  // T_parent_child at t.
  static Eigen::Isometry3d at(const Path& p, int64_t t_ns);
  // T_parent_child of one edge at t (interpolated; the nearest sample outside the span).
  static Eigen::Isometry3d at(const Edge& e, int64_t t_ns);
  static std::string bare(const std::string& frame);  // "/odom" -> "odom"

 private:
  std::map<std::string, Edge> edges_;  // by child frame
  int64_t gap_ns_ = 0;
};

}  // namespace fploc::import
