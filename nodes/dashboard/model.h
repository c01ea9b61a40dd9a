// The dashboard's model of a running graph (no LCM transport, no HTTP here): fed with the messages from
// the node thread, it keeps the trajectory trails, the running ATE (modules/eval's OnlineAte), node health
// and stream rates, and publishes every view (views.h) into the push hub (push_hub.h) that the HTTP
// side reads. The wire types are only forward-declared here. Thread-safe (one mutex, held only to copy).
#pragma once
#include <climits>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "fploc/eval/online_ate.h"
#include "fploc/runtime/telemetry.h"
#include "push_hub.h"
#include "views.h"

namespace fploc::dashboard {

struct ModelConfig {
  double silent_after_s = 2.0;      // node shown red after this long without a heartbeat
  size_t max_trail = 50000;         // poses kept per trail (oldest dropped)
  size_t max_feature_points = 6000; // decimated above this
  double ate_match_tolerance_s = 0.002;
};

class Model {
 public:
  explicit Model(ModelConfig cfg = {});
  ~Model();

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
  void set_clients(size_t n);  // open event streams (shown in "stats")

  // ---- a fleet on the same plan: other robots' poses and node tables (their channels "R/...").
  // Streams "pose@R" and "nodes@R"; "robots" lists every robot with its colour (the own one first,
  // name "" when the graph has no robot). /api/history?robot=R gives that robot's trail.
  void set_robots(const std::string& own, const std::vector<std::string>& others);
  void on_fleet_pose(const std::string& robot, const fploc::pose_t& m, double now_s, int64_t wall_us);
  void on_fleet_status(const std::string& robot, const fploc::node_status_t& m, double now_s);
  std::string fleet_history_json(const std::string& robot, int64_t since_utime = INT64_MIN) const;
  bool has_robot(const std::string& robot) const;

  // ---- outputs (HTTP side)
  PushHub& hub() { return hub_; }
  std::string plan_json() const;
  std::string state_json() const { return hub_.state_json(); }  // {"pose":..., "nodes":..., ...}
  // Trails and plot series (entries with utime > since_utime; all by default).
  std::string history_json(int64_t since_utime = INT64_MIN) const;
  std::string info_json() const;

  // Helpers (public for tests).
  static std::string features_json(const fploc::features_t& m, size_t max_points, const std::string& pose_json) {
    return features_view(m, max_points, pose_json);
  }
  double ate_rmse() const;
  size_t ate_count() const;

 private:
  void rebuild_nodes(double now_s, int64_t wall_us);  // lock held
  void publish_features();                            // lock held
  AteFigure ate_figure(int64_t utime) const;          // lock held

  ModelConfig cfg_;
  mutable std::mutex mu_;
  PushHub hub_;
  std::string plan_json_ = "null";
  uint64_t plan_version_ = 0;
  std::map<std::string, std::string> info_;

  struct TrailPoint {
    int64_t utime;
    double x, y, z, roll, pitch, yaw;
    bool has_err;
    double err;
    std::string floor;  // the pose's floor (pose_t.floor; "" unknown, and for the ground truth)
  };
  std::deque<TrailPoint> est_, gt_;
  // The frame and pose rates at each tick, stamped with the newest pose's time (the page's rate plot axis),
  // for /api/history (`rates`): a page opened mid-run draws the rates from before it was opened.
  struct RateRow {
    int64_t utime;
    double frame_hz, pose_hz;
  };
  std::deque<RateRow> rates_;
  fploc::eval::OnlineAte ate_;

  struct NodeEntry {
    std::shared_ptr<fploc::node_status_t> status;
    double received_s = 0;
    bool seen = false;
  };
  std::map<std::string, NodeEntry> nodes_;
  rt::RateMeter frame_rate_, pose_rate_, feature_rate_;  // arrivals (wall clock)

  // Latest features and frame pose for projection (features are in the sensor frame).
  std::unique_ptr<fploc::features_t> features_;
  std::unique_ptr<fploc::frame_pose_t> frame_pose_;
  size_t clients_ = 0;

  struct FleetRobot {
    std::deque<TrailPoint> est;
    std::map<std::string, NodeEntry> nodes;
  };
  std::map<std::string, FleetRobot> fleet_;
  void rebuild_fleet_nodes(const std::string& robot, double now_s, int64_t wall_us);  // lock held
};

}  // namespace fploc::dashboard
