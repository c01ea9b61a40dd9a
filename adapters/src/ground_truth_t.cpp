#include "fploc/adapters/ground_truth_t.h"


namespace fploc::adapters {

ground_truth_t ground_truth_msg(int64_t utime, int64_t seq, const StampedPose& p, const Eigen::Vector3d& v,
                                const Eigen::Vector3d& w, const std::string& scenario) {
  ground_truth_t g;
  g.utime = utime;
  g.seq = seq;
  for (int i = 0; i < 3; ++i) {
    g.position[i] = p.p[i];
    g.linear_velocity[i] = v[i];
    g.angular_velocity[i] = w[i];
  }
  g.orientation[0] = p.q.x();
  g.orientation[1] = p.q.y();
  g.orientation[2] = p.q.z();
  g.orientation[3] = p.q.w();
  g.scenario = scenario;
  return g;
}

}  // namespace fploc::adapters
