// Test producer for the backbone integration tests: publishes a synthetic circle on FPLOC_POSE at 20 Hz
// (timestamps from its own counter, so the stream is deterministic), and obeys test commands sent to it
// on FPLOC_CONTROL (node_command_t with node = its name): "test-hang" blocks its loop forever,
// "test-crash" aborts.
#include <fploc/node_command_t.hpp>
#include <fploc/pose_t.hpp>
#include <unistd.h>

#include <cmath>
#include <cstdlib>

#include "fploc/runtime/node.h"

namespace {

class TestPoseSource : public fploc::rt::Node {
 public:
  static fploc::rt::NodeSpec spec() {
    return {"test_pose_source", "", "test producer: a circle on FPLOC_POSE at 20 Hz",
            {fploc::rt::output<fploc::pose_t>("pose", "FPLOC_POSE"),
             fploc::rt::input<fploc::node_command_t>("control", "FPLOC_CONTROL")}};
  }
  void setup(fploc::rt::Context& ctx) override {
    out_ = ctx.advertise<fploc::pose_t>("pose");
    name_ = ctx.name();
    ctx.subscribe<fploc::node_command_t>("control", [this](const fploc::node_command_t& c) {
      if (c.node != name_) return;
      if (c.action == "test-hang")
        for (;;) ::pause();
      if (c.action == "test-crash") std::abort();
    });
    if (!ctx.composed()) ctx.every(0.05, [this] { tick(); });
  }

 private:
  void tick() {
    fploc::pose_t m{};
    const double t = 0.05 * double(seq_);
    m.utime = 1'000'000'000'000 + int64_t(seq_) * 50'000;
    m.seq = seq_++;
    m.final_estimate = true;
    m.floor_index = 0;
    m.floor = "0";
    m.position[0] = 2.0 * std::cos(0.2 * t);
    m.position[1] = 2.0 * std::sin(0.2 * t);
    m.position[2] = 0.5;
    m.orientation[2] = std::sin(0.1 * t + M_PI / 4);
    m.orientation[3] = std::cos(0.1 * t + M_PI / 4);
    m.covariance[0] = 0.01;
    out_.publish(m);
  }
  fploc::rt::Publisher<fploc::pose_t> out_;
  std::string name_;
  int64_t seq_ = 0;
};

}  // namespace

FPLOC_REGISTER_NODE(TestPoseSource)
