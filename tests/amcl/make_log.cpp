// Writes an LCM log of FPLOC_FEATURES + FPLOC_ODOM_POSE for the AMCL node test: ray-cast features in the
// synthetic room (modules/matcher/test/synthetic.h) along a path, wheel odometry with errors, and
// defects at known scans: non-finite features, empty scans, an odometry jump, a non-finite odometry pose,
// a missing odometry pose, an odometry pose going back in time. Also writes the plan (JSON) and the
// ground truth (TUM).
//   amcl_make_log OUT_DIR  -> OUT_DIR/log.lcm, OUT_DIR/plan.json, OUT_DIR/gt.tum, stdout: one line per defect
#include <fploc/features_t.hpp>
#include <fploc/pose_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <vector>

#include "fploc/amcl/odometry.h"
#include "fploc/core/pose.h"
#include "fploc/floorplan/io.h"
#include "synthetic.h"
#include "fploc/runtime/log_writer.h"

using namespace fploc;

namespace {

template <class Msg>
void write(lcm::LogFile& log, const std::string& channel, int64_t utime, const Msg& m) {
  std::vector<uint8_t> buf;
  rt::write_event(log, utime, channel, m, buf);
}

pose_t pose_msg(int64_t utime, int64_t seq, const Pose2& p) {
  pose_t m{};
  m.utime = utime;
  m.seq = seq;
  m.final_estimate = true;
  m.floor_index = 0;
  m.floor = "0";
  m.position[0] = p.x;
  m.position[1] = p.y;
  m.position[2] = 1.2;
  m.orientation[0] = m.orientation[1] = 0;
  m.orientation[2] = std::sin(p.yaw / 2);
  m.orientation[3] = std::cos(p.yaw / 2);
  for (double& c : m.covariance) c = 0;
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  const bool clean = argc == 3 && std::string(argv[2]) == "--clean";
  // --odom-between: no defects, and the odometry at its own times, halfway between the scans (as a robot's
  // odometry at its own rate): AMCL interpolates it at each scan.
  const bool between_scans = argc == 3 && std::string(argv[2]) == "--odom-between";
  if (argc != 2 && !clean && !between_scans) {
    std::cerr << "usage: amcl_make_log OUT_DIR [--clean | --odom-between]   (--clean: no defects; --odom-between: no "
                 "defects, odometry halfway between the scans)\n";
    return 2;
  }
  const std::string dir = argv[1];
  const FloorPlan plan = testing::room_with_pillars();
  save_floor_plan(plan, dir + "/plan.json");
  // Path: along the room's south side and up the east side, 0.05 m per scan (0.5 m/s at 10 Hz), turning
  // in place at the corner.
  std::vector<Pose2> path;
  for (double x = 3; x < 17; x += 0.05) path.push_back({x, 2.5, 0});
  for (double a = 0.1; a < M_PI / 2; a += 0.1) path.push_back({17, 2.5, a});
  for (double y = 2.5; y < 7.5; y += 0.05) path.push_back({17, y, M_PI / 2});
  lcm::LogFile log(dir + "/log.lcm", "w");
  if (!log.good()) {
    std::cerr << "cannot write " << dir << "/log.lcm\n";
    return 1;
  }
  std::ofstream gt(dir + "/gt.tum");
  amcl::WheelOdometrySim odo;  // defaults: 2 % scale, 1 deg/m drift, noise
  odo.set_start(path[0]);
  testing::SynthOptions so;
  so.noise_sigma = 0.02;
  so.clutter_fraction = 0.2;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const int64_t t0 = 1700000000000000;
  int64_t fseq = 0, oseq = 0;
  std::vector<Pose2> odom;  // the wheel odometry at each scan
  for (const Pose2& p : path) odom.push_back(odo.update(p));
  if (between_scans) write(log, "FPLOC_ODOM_POSE", t0 - 50000, pose_msg(t0 - 50000, oseq++, odom[0]));
  for (size_t k = 0; k < path.size(); ++k) {
    const int64_t utime = t0 + int64_t(k) * 100000;
    StampedPose sp = StampedPose::from_rpy(double(utime) * 1e-6, Eigen::Vector3d(path[k].x, path[k].y, 1.2), 0, 0, path[k].yaw);
    gt << tum_line(sp) << "\n";
    so.seed = uint32_t(k + 1);
    const FeatureFrame f = testing::synth_frame(plan, path[k], so);
    features_t m{};
    m.utime = utime;
    m.seq = fseq++;
    m.scan_seq = int64_t(k);
    m.z = 1.2;
    m.roll_pitch_sigma = 0.001;
    m.z_sigma = 0.01;
    const bool empty = !clean && !between_scans && k >= 51 && k <= 55;
    for (size_t i = 0; !empty && i < f.points.size(); ++i) {
      float x = float(f.points[i].p.x()), y = float(f.points[i].p.y());
      if (!clean && !between_scans && (k == 50 || (k == 80 && i % 2 == 0))) x = y = nan;
      m.x.push_back(x);
      m.y.push_back(y);
      m.kind.push_back(int8_t(f.points[i].kind));
      m.group.push_back(f.points[i].group);
      m.t_offset_s.push_back(0.f);
    }
    m.num_points = int32_t(m.x.size());
    m.status = m.num_points ? 0 : 1;
    write(log, "FPLOC_FEATURES", utime, m);
    Pose2 o = odom[k];
    if (between_scans) {
      const Pose2 mid = k + 1 < path.size() ? interpolate(o, odom[k + 1], 0.5) : o;
      write(log, "FPLOC_ODOM_POSE", utime + 50000, pose_msg(utime + 50000, oseq++, mid));
      continue;
    }
    if (clean) {
      write(log, "FPLOC_ODOM_POSE", utime, pose_msg(utime, oseq++, o));
      continue;
    }
    if (k >= 120) o.x += 5.0;  // the odometry frame jumps by 5 m (e.g. an odometry reset)
    if (k == 150) o.y = std::numeric_limits<double>::quiet_NaN();
    if (k >= 170 && k <= 172) continue;  // no odometry for these scans: 0.4 s between the samples around them
    write(log, "FPLOC_ODOM_POSE", utime, pose_msg(utime, oseq++, o));
    if (k == 200) write(log, "FPLOC_ODOM_POSE", utime, pose_msg(utime - 300000, oseq++, o));  // back in time
  }
  std::cout << path.size() << " scans; defects: 50 non-finite features, 51-55 empty, 80 half non-finite, "
            << "120 odometry jump 5 m, 150 non-finite odometry, 170-172 no odometry, 200 odometry back in time\n";
  return 0;
}
