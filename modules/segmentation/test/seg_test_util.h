#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

#include "fploc/segmentation/segmenter.h"
#include "fploc/segmentation/synthetic.h"

namespace fploc::seg::test_util {

struct WallStats {
  double precision = 0, recall = 0;
  size_t returned = 0, plan_walls = 0;
};

// Precision: returned wall points that are not ceiling/floor returns. Recall: plan wall/pillar returns
// kept. Needs the segmenter's per-pixel labels (set_keep_labels(true)).
inline WallStats wall_stats(const Segmentation& out, const std::vector<uint8_t>& truth) {
  WallStats s;
  size_t bad = 0, kept = 0;
  for (size_t i = 0; i < truth.size() && i < out.label.size(); ++i) {
    const bool wall = out.label[i] == 3;
    if (wall) {
      ++s.returned;
      bad += truth[i] == synth::kCeiling || truth[i] == synth::kFloor;
    }
    if (truth[i] == synth::kWall) {
      ++s.plan_walls;
      kept += wall;
    }
  }
  s.precision = s.returned ? 1.0 - double(bad) / s.returned : 0.0;
  s.recall = s.plan_walls ? double(kept) / s.plan_walls : 0.0;
  return s;
}

// 16 x 12 m room, 3.2 m high; for x < x_split the ceiling is 0.6 m lower (a drop ceiling: a solid box labelled
// ceiling).
inline synth::Room two_height_room(double x_split) {
  synth::Room room;
  room.height = 3.2;
  synth::Box drop;
  drop.lo = Eigen::Vector3d(-8.0, -6.0, 2.6);
  drop.hi = Eigen::Vector3d(x_split, 6.0, 3.2);
  drop.label = synth::kCeiling;
  room.boxes.push_back(drop);
  return room;
}

// A walk's height and attitude against the truth, scan by scan (the height estimator's tests): the largest z and
// roll/pitch errors, the largest step (z's change between scans less the true change) and the scans by z source.
struct HeightTally {
  double max_z_err = 0, max_rp_err = 0, max_step = 0;
  int ground = 0, ceiling = 0, predicted = 0;
  // `score` false: a scan that only learns (counted by source, no errors); `step` false: no step from the previous.
  void add(const Segmentation& out, const synth::SensorPose& pose, bool score = true, bool step = true) {
    if (score) {
      max_z_err = std::max(max_z_err, std::abs(out.z - pose.z));
      max_rp_err = std::max({max_rp_err, std::abs(out.roll - pose.roll), std::abs(out.pitch - pose.pitch)});
      if (step) max_step = std::max(max_step, std::abs((out.z - prev_z_) - (pose.z - prev_true_)));
    }
    prev_z_ = out.z;
    prev_true_ = pose.z;
    ground += out.z_source == HeightSource::kGround;
    ceiling += out.z_source == HeightSource::kCeiling;
    predicted += out.z_source == HeightSource::kPredicted;
  }

 private:
  double prev_z_ = NAN, prev_true_ = NAN;
};

}  // namespace fploc::seg::test_util
