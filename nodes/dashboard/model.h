// The dashboard's view of a running graph (no LCM, no HTTP here): latest value per stream as
// ready-to-send JSON, the trajectory trails, ATE so far, node health. Fed from the node thread,
// read by the HTTP threads; every method is thread-safe (one mutex, held only to copy strings).
#pragma once
#include <fploc/features_t.hpp>
#include <fploc/frame_pose_t.hpp>
#include <fploc/ground_truth_t.hpp>
#include <fploc/node_status_t.hpp>
#include <fploc/pose_t.hpp>

#include <array>
#include <condition_variable>
#include <climits>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace fploc::dashboard {

// One stream's latest value. `version` grows on every update (0 = never set).
struct Slot {
  uint64_t version = 0;
  std::string json;
};

// What one SSE client has already received (per stream version).
struct ClientCursor {
  std::map<std::string, uint64_t> sent;
  std::map<std::string, double> last_sent_s;  // steady clock [s] of the last event per stream
  uint64_t seen_global = 0;
  bool greeted = false;
};

struct ModelConfig {
  double silent_after_s = 2.0;      // node shown red after this long without a heartbeat
  size_t max_trail = 50000;         // poses kept per trail (oldest dropped)
  size_t max_feature_points = 6000; // decimated above this
  double ate_match_tolerance_s = 0.002;
};

class Model {
 public:
  explicit Model(ModelConfig cfg = {});

  // ---- inputs (node thread); `now_s` is a steady clock, `wall_us` the wall clock at receipt.
  void on_pose(const fploc::pose_t& m, double now_s, int64_t wall_us);
  void on_frame_pose(const fploc::frame_pose_t& m, double now_s, int64_t wall_us);
  void on_features(const fploc::features_t& m, double now_s, int64_t wall_us);
  void on_ground_truth(const fploc::ground_truth_t& m, double now_s, int64_t wall_us);
  void on_status(const fploc::node_status_t& m, double now_s);
  // The latest plan diff (FPLOC_PLAN_DIFF, as JSON: plan_diff_json.h), pushed as stream "plan_diff".
  void on_plan_diff(std::string json);
  // A node of the graph that must be listed even before its first heartbeat (red after silent_after_s).
  void expect_node(const std::string& name, const std::string& executable, double now_s);
  // Re-evaluates node health (silence) and stream rates; call at a few Hz.
  void tick(double now_s, int64_t wall_us);
  // The plan as JSON (served at /api/plan and not pushed).
  void set_plan_json(std::string json);
  void set_info(const std::string& key, const std::string& json);  // extra constant info for /api/info

  // ---- outputs (HTTP threads)
  std::string plan_json() const;
  std::string state_json() const;    // {"pose":..., "nodes":..., ...} latest of every stream
  // Trails and plot series (entries with utime > since_utime; all by default).
  std::string history_json(int64_t since_utime = INT64_MIN) const;
  std::string info_json() const;
  // Blocks until a stream has a value the client has not seen and that stream's rate cap (max_hz
  // events per second per stream) allows it, then returns the SSE text to send ("" after keepalive_s
  // without anything -> send a keep-alive comment). Returns false when
  // the model is shutting down.
  bool next_push(ClientCursor& c, double max_hz, double keepalive_s, std::string& out);
  void stop();
  void client_count(int delta);
  uint64_t pushes() const;

  // Helpers (public for tests).
  static std::string features_json(const fploc::features_t& m, size_t max_points, const std::string& pose_json);
  double ate_rmse() const;
  size_t ate_count() const;

 private:
  void set_slot(const std::string& name, std::string json);  // lock held
  void rebuild_nodes(double now_s, int64_t wall_us);          // lock held
  void ate_update_est(int64_t t, double x, double y, double z);
  void ate_update_gt(int64_t t, double x, double y, double z);
  void publish_features(); // lock held

  ModelConfig cfg_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  bool stopping_ = false;
  uint64_t global_version_ = 0;
  std::map<std::string, Slot> slots_;
  std::string plan_json_ = "null";
  std::map<std::string, std::string> info_;

  struct TrailPoint {
    int64_t utime;
    double x, y, z, roll, pitch, yaw;
    bool has_err;
    double err;
  };
  std::deque<TrailPoint> est_, gt_;
  // ATE: position per utime for both, squared errors of matched estimates.
  std::map<int64_t, std::array<double, 3>> est_pos_, gt_pos_;
  std::map<int64_t, double> err_sq_;
  double err_sum_ = 0;

  struct NodeEntry {
    fploc::node_status_t status;
    double received_s = 0;
    bool seen = false;
  };
  std::map<std::string, NodeEntry> nodes_;
  std::deque<double> frame_times_, pose_times_, feature_times_;

  // Latest features and frame pose for projection (features are in the sensor frame).
  bool have_features_ = false;
  fploc::features_t features_;
  bool have_frame_pose_ = false;
  fploc::frame_pose_t frame_pose_;
  uint64_t pushes_ = 0;
  int clients_ = 0;
};

}  // namespace fploc::dashboard
