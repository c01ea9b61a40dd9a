// Pose logger: every fploc.pose_t on its `pose` port (or fploc.frame_pose_t on its optional `frame_pose`
// port: single-frame registration results, 6-DoF from x, y, yaw + roll, pitch, z; or fploc.ground_truth_t on
// its optional `ground_truth` port, to record the simulator's truth of a live run) becomes one TUM line (core `tum_line`, so the
// formatting is deterministic). Each line is handed to the kernel with a single write(2) as soon as the
// pose arrives: nothing is buffered in the process, so no processed pose is lost on SIGINT or a crash.
// A pose_t or frame_pose_t with status 3 (NOT_INITIALISED: no estimate yet, e.g. grid2d's global search) is not written.
// With `uncertainty_file`, each pose_t / frame_pose_t also gives one line "t status xx xy xyaw yy yyaw yawyaw"
// (its status and x/y/yaw covariance, modules/eval/uncertainty.h) for `fploc eval --uncertainty`.
// With `floor_file`, each pose_t / frame_pose_t also gives one line "t floor_index floor" (the floor it is on).
#include <fcntl.h>
#include <fploc/frame_pose_t.hpp>
#include <fploc/ground_truth_t.hpp>
#include <fploc/pose_t.hpp>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "fploc/core/pose.h"
#include "fploc/eval/uncertainty.h"
#include "fploc/runtime/node.h"
#include "options/tools.pb.h"

namespace {

class PoseLoggerNode : public fploc::rt::Node {
 public:
  static fploc::rt::NodeSpec spec() {
    return {"pose_logger", "pose_logger", "writes FPLOC_POSE to a TUM trajectory file (one flushed line per pose)",
            {fploc::rt::input<fploc::pose_t>("pose", "FPLOC_POSE"),
             // Not connected unless the graph maps it (e.g. to FPLOC_FRAME_POSE); map `pose` to "" then.
             fploc::rt::input<fploc::frame_pose_t>("frame_pose", ""),
             fploc::rt::input<fploc::ground_truth_t>("ground_truth", "")}};
  }

  void setup(fploc::rt::Context& ctx) override {
    const auto& opt = ctx.options<fploc::PoseLoggerOptions>();
    path_ = opt.file().empty() ? std::string("poses.tum") : opt.file();
    final_only_ = opt.final_only();
    fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd_ < 0) throw std::runtime_error("cannot write '" + path_ + "': " + std::strerror(errno));
    ctx_ = &ctx;
    if (!opt.uncertainty_file().empty()) {
      unc_path_ = opt.uncertainty_file();
      unc_fd_ = ::open(unc_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
      if (unc_fd_ < 0) throw std::runtime_error("cannot write '" + unc_path_ + "': " + std::strerror(errno));
      write_line(unc_fd_, unc_path_, "# t status xx xy xyaw yy yyaw yawyaw (x, y, yaw covariance; status 0 OK 1 POOR 2 LOST)\n");
    }
    if (!opt.floor_file().empty()) {
      floor_path_ = opt.floor_file();
      floor_fd_ = ::open(floor_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
      if (floor_fd_ < 0) throw std::runtime_error("cannot write '" + floor_path_ + "': " + std::strerror(errno));
      write_line(floor_fd_, floor_path_, "# t floor_index floor (index in the building's floor list, -1 unknown)\n");
    }
    if (!ctx.channel("pose").empty())
      ctx.subscribe<fploc::pose_t>("pose", [this](const fploc::pose_t& m) { on_pose(m); });
    if (!ctx.channel("frame_pose").empty())
      ctx.subscribe<fploc::frame_pose_t>("frame_pose", [this](const fploc::frame_pose_t& m) { on_frame_pose(m); });
    if (!ctx.channel("ground_truth").empty())
      ctx.subscribe<fploc::ground_truth_t>("ground_truth", [this](const fploc::ground_truth_t& m) {
        write_pose(m.utime, m.seq, m.position, m.orientation, "ground_truth");
      });
  }

  void shutdown() override {
    if (floor_fd_ >= 0) {
      ::fsync(floor_fd_);
      ::close(floor_fd_);
      floor_fd_ = -1;
    }
    if (unc_fd_ >= 0) {
      ::fsync(unc_fd_);
      ::close(unc_fd_);
      unc_fd_ = -1;
    }
    if (fd_ >= 0) {
      ::fsync(fd_);
      ::close(fd_);
      fd_ = -1;
    }
  }
  ~PoseLoggerNode() override { shutdown(); }

 private:
  void on_frame_pose(const fploc::frame_pose_t& m) {
    if (m.status == 3) return;  // NOT_INITIALISED: no pose yet
    const auto p = fploc::StampedPose::from_rpy(double(m.utime) * 1e-6, Eigen::Vector3d(m.x, m.y, m.z), m.roll,
                                                m.pitch, m.yaw);
    if (!p.p.allFinite() || !p.q.coeffs().allFinite()) {
      ctx_->error("frame_pose seq " + std::to_string(m.seq) + ": non-finite pose (skipped)");
      return;
    }
    write_line(fploc::tum_line(p) + "\n");
    write_floor(m.utime, m.floor_index, m.floor);
    if (unc_fd_ >= 0) {
      fploc::eval::PoseUncertainty u;
      u.t = p.t;
      u.status = m.status;
      for (int i = 0; i < 9; ++i) u.cov(i / 3, i % 3) = m.covariance[i];
      write_line(unc_fd_, unc_path_, fploc::eval::uncertainty_line(u) + "\n");
    }
  }

  void on_pose(const fploc::pose_t& m) {
    if (final_only_ && !m.final_estimate) return;
    if (m.status == 3) return;  // no estimate yet (grid2d searching the whole map: its pose is a placeholder)
    if (!write_pose(m.utime, m.seq, m.position, m.orientation, "pose")) return;
    write_floor(m.utime, m.floor_index, m.floor);
    if (unc_fd_ < 0) return;
    fploc::eval::PoseUncertainty u;
    u.t = double(m.utime) * 1e-6;
    u.status = m.status;
    const int ix[3] = {0, 1, 5};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) u.cov(i, j) = m.covariance[ix[i] * 6 + ix[j]];
    write_line(unc_fd_, unc_path_, fploc::eval::uncertainty_line(u) + "\n");
  }

  // position x y z, orientation quaternion x y z w (pose_t and ground_truth_t share the layout).
  bool write_pose(int64_t utime, int64_t seq, const double* position, const double* q, const char* port) {
    fploc::StampedPose p;
    p.t = double(utime) * 1e-6;
    p.p = Eigen::Vector3d(position[0], position[1], position[2]);
    const double n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
    if (!p.p.allFinite() || !std::isfinite(n2) || n2 < 1e-12) {
      ctx_->error(std::string(port) + " seq " + std::to_string(seq) + ": non-finite position or zero quaternion (skipped)");
      return false;
    }
    p.q = Eigen::Quaterniond(q[3], q[0], q[1], q[2]);
    write_line(fploc::tum_line(p) + "\n");
    return true;
  }

  void write_floor(int64_t utime, int floor_index, const std::string& floor) {
    if (floor_fd_ < 0) return;
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6f %d ", double(utime) * 1e-6, floor_index);
    write_line(floor_fd_, floor_path_, buf + (floor.empty() ? std::string("-") : floor) + "\n");
  }

  void write_line(const std::string& line) { write_line(fd_, path_, line); }
  void write_line(int fd, const std::string& path, const std::string& line) {
    size_t off = 0;
    while (off < line.size()) {
      const ssize_t w = ::write(fd, line.data() + off, line.size() - off);
      if (w < 0) {
        if (errno == EINTR) continue;
        ctx_->error("write '" + path + "': " + std::strerror(errno));
        return;
      }
      off += size_t(w);
    }
  }

  fploc::rt::Context* ctx_ = nullptr;
  std::string path_, unc_path_, floor_path_;
  bool final_only_ = false;
  int fd_ = -1, unc_fd_ = -1, floor_fd_ = -1;
};

}  // namespace

FPLOC_REGISTER_NODE(PoseLoggerNode)
