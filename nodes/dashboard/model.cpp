#include "model.h"

#include <fploc/features_t.hpp>
#include <fploc/frame_pose_t.hpp>
#include <fploc/ground_truth_t.hpp>
#include <fploc/node_status_t.hpp>
#include <fploc/pose_t.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include "fploc/core/text_out.h"

namespace fploc::dashboard {

using nlohmann::json;

namespace {
json num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
// An /api/history est row: utime, x, y, z, roll, pitch, yaw, err (null without one), floor (null when unknown).
const json kEstFields = {"utime", "x", "y", "z", "roll", "pitch", "yaw", "err", "floor"};
template <class TrailPoint>
json est_row(const TrailPoint& p) {
  return {p.utime, num(r6(p.x)), num(r6(p.y)), num(r6(p.z)), num(r6(p.roll)), num(r6(p.pitch)), num(r6(p.yaw)),
          p.has_err ? num(r6(p.err)) : json(nullptr), p.floor.empty() ? json(nullptr) : json(p.floor)};
}
}  // namespace

Model::Model(ModelConfig cfg) : cfg_(cfg), ate_(cfg.ate_match_tolerance_s, cfg.max_trail * 2) {}
Model::~Model() = default;

void Model::on_plan_diff(std::string j) {
  std::lock_guard<std::mutex> lk(mu_);
  hub_.set("plan_diff", std::move(j));
}

void Model::set_plan_json(std::string j) {
  std::lock_guard<std::mutex> lk(mu_);
  plan_json_ = std::move(j);
  hub_.set("plan_changed", "{\"version\":" + std::to_string(++plan_version_) + "}");
}

void Model::set_info(const std::string& key, const std::string& j) {
  std::lock_guard<std::mutex> lk(mu_);
  info_[key] = j;
}

void Model::set_clients(size_t n) {
  std::lock_guard<std::mutex> lk(mu_);
  clients_ = n;
}

double Model::ate_rmse() const {
  std::lock_guard<std::mutex> lk(mu_);
  return ate_.rmse();
}
size_t Model::ate_count() const {
  std::lock_guard<std::mutex> lk(mu_);
  return ate_.count();
}

AteFigure Model::ate_figure(int64_t utime) const { return {ate_.error(utime), ate_.rmse(), ate_.count()}; }

// ---- inputs ---------------------------------------------------------------------------------------
void Model::on_pose(const fploc::pose_t& m, double now_s, int64_t wall_us) {
  const Rpy r = rpy_of(m.orientation);
  std::lock_guard<std::mutex> lk(mu_);
  pose_rate_.add(now_s);
  ate_.add_estimate(m.utime, m.position[0], m.position[1], m.position[2]);
  const AteFigure a = ate_figure(m.utime);
  TrailPoint p{m.utime, m.position[0], m.position[1], m.position[2], r.roll, r.pitch, r.yaw, bool(a.err),
               a.err.value_or(0.0), m.floor};
  // The optimiser re-publishes poses inside its window: replace the entry with the same time.
  bool replaced = false;
  for (size_t k = 0; k < est_.size() && k < 200; ++k) {
    auto& q = est_[est_.size() - 1 - k];
    if (q.utime == m.utime) {
      q = p;
      replaced = true;
      break;
    }
    if (q.utime < m.utime) break;
  }
  if (!replaced) {
    est_.push_back(p);
    // Keep the trail sorted when an older pose arrives late.
    for (size_t i = est_.size() - 1; i > 0 && est_[i - 1].utime > est_[i].utime; --i) std::swap(est_[i - 1], est_[i]);
    while (est_.size() > cfg_.max_trail) est_.pop_front();
  }
  hub_.set("pose", pose_view(m, r, a, wall_us));
}

void Model::on_ground_truth(const fploc::ground_truth_t& m, double, int64_t wall_us) {
  const Rpy r = rpy_of(m.orientation);
  std::lock_guard<std::mutex> lk(mu_);
  ate_.add_truth(m.utime, m.position[0], m.position[1], m.position[2]);
  TrailPoint p{m.utime, m.position[0], m.position[1], m.position[2], r.roll, r.pitch, r.yaw, false, 0, {}};
  if (!gt_.empty() && gt_.back().utime == m.utime) gt_.back() = p;
  else if (gt_.empty() || gt_.back().utime < m.utime) gt_.push_back(p);
  while (gt_.size() > cfg_.max_trail) gt_.pop_front();
  hub_.set("gt", ground_truth_view(m, r, {std::nullopt, ate_.rmse(), ate_.count()}, wall_us));
}

void Model::on_frame_pose(const fploc::frame_pose_t& m, double now_s, int64_t wall_us) {
  std::lock_guard<std::mutex> lk(mu_);
  frame_rate_.add(now_s);
  frame_pose_ = std::make_unique<fploc::frame_pose_t>(m);
  hub_.set("frame_pose", frame_pose_view(m, frame_rate_.rate_hz(now_s), wall_us));
  // The features of this scan arrived first (the matcher consumes them): re-project them now.
  if (features_ && features_->scan_seq == m.scan_seq) publish_features();
}

void Model::on_features(const fploc::features_t& m, double now_s, int64_t) {
  std::lock_guard<std::mutex> lk(mu_);
  feature_rate_.add(now_s);
  features_ = std::make_unique<fploc::features_t>(m);
  publish_features();
}

void Model::publish_features() {
  const std::string pose = frame_pose_ ? frame_pose_for_features(*frame_pose_, features_->scan_seq) : "null";
  hub_.set("features", features_view(*features_, cfg_.max_feature_points, pose));
}

// The launcher's answer to a refused control request (state "rejected", for `fploc node` to print) carries the
// requested name, which may be no node at all: it is neither a node nor a node's state.
static bool is_control_answer(const fploc::node_status_t& m) { return m.state == "rejected"; }

void Model::on_status(const fploc::node_status_t& m, double now_s) {
  if (is_control_answer(m)) return;
  std::lock_guard<std::mutex> lk(mu_);
  auto& e = nodes_[m.node];
  e.status = std::make_shared<fploc::node_status_t>(m);
  e.received_s = now_s;
  e.seen = true;
  const int64_t wall = std::chrono::duration_cast<std::chrono::microseconds>(
                           std::chrono::system_clock::now().time_since_epoch()).count();
  rebuild_nodes(now_s, wall);
}

void Model::expect_node(const std::string& name, const std::string& executable, double now_s) {
  std::lock_guard<std::mutex> lk(mu_);
  if (nodes_.count(name)) return;
  auto& e = nodes_[name];
  e.status = std::make_shared<fploc::node_status_t>();
  e.status->node = name;
  e.status->executable = executable;
  e.status->state = "not seen";
  e.status->reporter = "graph";
  e.received_s = now_s;
}

void Model::tick(double now_s, int64_t wall_us) {
  std::lock_guard<std::mutex> lk(mu_);
  rebuild_nodes(now_s, wall_us);
  for (auto& [r, f] : fleet_) rebuild_fleet_nodes(r, now_s, wall_us);
  const double frame_hz = frame_rate_.rate_hz(now_s), pose_hz = pose_rate_.rate_hz(now_s);
  if (!est_.empty() && (rates_.empty() || rates_.back().utime < est_.back().utime)) {
    rates_.push_back({est_.back().utime, frame_hz, pose_hz});
    while (rates_.size() > cfg_.max_trail) rates_.pop_front();
  }
  json s = {{"frame_rate_hz", num(r6(frame_hz))},
            {"pose_rate_hz", num(r6(pose_hz))},
            {"features_rate_hz", num(r6(feature_rate_.rate_hz(now_s)))},
            {"clients", clients_},
            {"pushes", hub_.pushes()},
            {"ate_rmse", num(r6(ate_.rmse()))},
            {"ate_n", ate_.count()},
            {"wall_us", wall_us}};
  hub_.set("stats", fploc::json_text(s));
}

// ---- fleet -----------------------------------------------------------------------------------------
void Model::set_robots(const std::string& own, const std::vector<std::string>& others) {
  static const char* kColours[] = {"#1f6feb", "#d97706", "#7c3aed", "#059669", "#db2777", "#0891b2", "#65a30d"};
  std::lock_guard<std::mutex> lk(mu_);
  json list = json::array();
  list.push_back({{"name", own}, {"color", kColours[0]}, {"own", true}});
  size_t k = 1;
  for (const auto& r : others) {
    if (r == own || fleet_.count(r)) continue;
    fleet_[r];
    list.push_back({{"name", r}, {"color", kColours[k++ % 7]}, {"own", false}});
  }
  hub_.set("robots", fploc::json_text(list));
}

bool Model::has_robot(const std::string& robot) const {
  std::lock_guard<std::mutex> lk(mu_);
  return fleet_.count(robot) > 0;
}

void Model::on_fleet_pose(const std::string& robot, const fploc::pose_t& m, double, int64_t wall_us) {
  const Rpy r = rpy_of(m.orientation);
  std::lock_guard<std::mutex> lk(mu_);
  auto it = fleet_.find(robot);
  if (it == fleet_.end()) return;
  auto& est = it->second.est;
  TrailPoint p{m.utime, m.position[0], m.position[1], m.position[2], r.roll, r.pitch, r.yaw, false, 0, m.floor};
  if (!est.empty() && est.back().utime == m.utime) est.back() = p;
  else if (est.empty() || est.back().utime < m.utime) est.push_back(p);
  while (est.size() > cfg_.max_trail) est.pop_front();
  hub_.set("pose@" + robot, pose_view(m, r, {std::nullopt, NAN, 0}, wall_us));
}

void Model::on_fleet_status(const std::string& robot, const fploc::node_status_t& m, double now_s) {
  if (is_control_answer(m)) return;
  std::lock_guard<std::mutex> lk(mu_);
  auto it = fleet_.find(robot);
  if (it == fleet_.end()) return;
  auto& e = it->second.nodes[m.node];
  e.status = std::make_shared<fploc::node_status_t>(m);
  e.received_s = now_s;
  e.seen = true;
  rebuild_fleet_nodes(robot, now_s, std::chrono::duration_cast<std::chrono::microseconds>(
                                        std::chrono::system_clock::now().time_since_epoch()).count());
}

void Model::rebuild_fleet_nodes(const std::string& robot, double now_s, int64_t wall_us) {
  std::map<std::string, NodeRow> rows;
  for (const auto& [name, e] : fleet_[robot].nodes) rows[name] = {e.status.get(), now_s - e.received_s, e.seen};
  std::string text = nodes_view(rows, cfg_.silent_after_s, wall_us);
  if (hub_.get("nodes@" + robot) != text) hub_.set("nodes@" + robot, std::move(text));
}

std::string Model::fleet_history_json(const std::string& robot, int64_t since) const {
  std::lock_guard<std::mutex> lk(mu_);
  json est = json::array();
  auto it = fleet_.find(robot);
  if (it != fleet_.end())
    for (const auto& p : it->second.est)
      if (p.utime > since)
        est.push_back(est_row(p));
  json j = {{"robot", robot}, {"fields_est", kEstFields},
            {"est", est}, {"gt", json::array()}};
  return fploc::json_text(j);
}

void Model::rebuild_nodes(double now_s, int64_t wall_us) {
  std::map<std::string, NodeRow> rows;
  for (const auto& [name, e] : nodes_) rows[name] = {e.status.get(), now_s - e.received_s, e.seen};
  std::string text = nodes_view(rows, cfg_.silent_after_s, wall_us);
  // Only the ages change between heartbeats; push when health or content changed.
  if (hub_.get("nodes") != text) hub_.set("nodes", std::move(text));
}

// ---- outputs --------------------------------------------------------------------------------------
std::string Model::plan_json() const {
  std::lock_guard<std::mutex> lk(mu_);
  return plan_json_;
}

std::string Model::history_json(int64_t since) const {
  std::lock_guard<std::mutex> lk(mu_);
  json est = json::array(), gt = json::array();
  for (const auto& p : est_)
    if (p.utime > since)
      est.push_back(est_row(p));
  for (const auto& p : gt_)
    if (p.utime > since)
      gt.push_back({p.utime, num(r6(p.x)), num(r6(p.y)), num(r6(p.z)), num(r6(p.roll)), num(r6(p.pitch)), num(r6(p.yaw))});
  json rates = json::array();
  for (const auto& r : rates_)
    if (r.utime > since) rates.push_back({r.utime, num(r6(r.frame_hz)), num(r6(r.pose_hz))});
  json j = {{"fields_est", kEstFields},
            {"fields_gt", {"utime", "x", "y", "z", "roll", "pitch", "yaw"}},
            {"est", est},
            {"gt", gt},
            {"fields_rates", {"utime", "frame_rate_hz", "pose_rate_hz"}},
            {"rates", rates},
            {"ate_rmse", num(ate_.rmse())},
            {"ate_n", ate_.count()}};
  return fploc::json_text(j);
}

std::string Model::info_json() const {
  std::lock_guard<std::mutex> lk(mu_);
  std::string out = "{";
  bool first = true;
  for (const auto& [k, v] : info_) {
    out += (first ? "\"" : ",\"") + k + "\":" + v;
    first = false;
  }
  return out + "}";
}

}  // namespace fploc::dashboard
