// fploc-grid2d: the 2D LiDAR mode's localizer on a raster map. laser_scan_t (LASER_SCAN) + wheel odometry
// (pose_t on WHEEL_ODOM; optional) -> modules/laser2d GridLocalizer (scans matched directly to the distance
// field of a map_server occupancy grid: correlative search around the odometry prediction, Ceres refinement)
// -> pose_t (FPLOC_GRID_POSE) per scan: status OK / POOR (odometry prediction kept) / LOST / 3 = no estimate (global search), covariance
// (x, y, yaw) from the fit. Without grid2d.initial_pose: global localization (LOST until one place dominates). Odometry pairing: the latest odometry pose whose utime is not after the scan's
// (`fploc import-carmen` writes it with the scan's own utime, before the scan).
#include <fploc/laser_scan_t.hpp>
#include <fploc/pose_t.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <optional>

#include "fploc/adapters/pose_t.h"
#include "fploc/floorplan/occupancy.h"
#include "fploc/laser2d/grid_localizer.h"
#include "fploc/config/floor_ref.h"
#include "fploc/config/laser2d.h"
#include "fploc/runtime/node.h"
#include "options/laser2d.pb.h"

namespace {

namespace l2 = fploc::laser2d;
using fploc::Pose2;

class Grid2dNode : public fploc::rt::Node {
 public:
  static fploc::rt::NodeSpec spec() {
    return {"grid2d", "grid2d",
            "2D LiDAR scans + wheel odometry -> localization on an occupancy grid's distance field (pose_t)",
            {fploc::rt::input<fploc::laser_scan_t>("scan", "LASER_SCAN"),
             fploc::rt::input<fploc::pose_t>("odom", "WHEEL_ODOM"),  // "" = no odometry (previous pose predicts)
             fploc::rt::output<fploc::pose_t>("pose", "FPLOC_GRID_POSE"),
             // Optional: the pose of each global lock (the first OK scan after a whole-map search), once, with its
             // covariance: wired to the matcher's initial_pose port (FPLOC_INITIAL_POSE) in graphs/lidar2d.pbtxt, so
             // the plan pipeline starts where grid2d found the robot. "" = not published.
             fploc::rt::output<fploc::pose_t>("lock", "")}};
  }

  void setup(fploc::rt::Context& ctx) override {
    ctx_ = &ctx;
    const auto& o = ctx.options<fploc::Grid2dOptions>();
    if (o.plan().file().empty()) throw std::runtime_error("grid2d.plan.file: no occupancy map (.yaml) given");
    const std::string path = ctx.resolve_path(o.plan().file());
    floor_ = fploc::config::floor_ref(o.plan(), path);
    const auto ext = path.size() >= 5 ? path.substr(path.find_last_of('.') + 1) : std::string();
    if (ext != "yaml" && ext != "yml")
      throw std::runtime_error("grid2d.plan.file: '" + path + "' is not a map_server occupancy map (.yaml)");
    const l2::GridLocalizerConfig c = fploc::config::config_of(o);
    const fploc::OccupancyGrid g = fploc::read_occupancy_map(path);
    auto field = std::make_shared<fploc::DistanceField>(g, c.field_max_m);
    loc_ = std::make_unique<l2::GridLocalizer>(field, c);
    mount_ = {o.mount_x_m(), o.mount_y_m(), o.mount_yaw_deg() * M_PI / 180};
    upside_down_ = o.upside_down();
    z_ = o.z_m();
    // Where a whole-map search may place the robot (a global start, a kidnapped robot): not needed otherwise (a map
    // without a known-free cell works from a given start pose).
    if (!o.has_initial_pose() || c.global_after_lost_scans > 0) loc_->set_free_space(g);
    std::cerr << "[" << ctx.name() << "] " << path << ": " << g.width << " x " << g.height << " cells at " << g.resolution
              << " m, " << field->occupied_cells() << " occupied; ";
    if (o.has_initial_pose()) {
      const Pose2 p0{o.initial_pose().x(), o.initial_pose().y(), o.initial_pose().yaw()};
      loc_->set_initial_pose(p0);
      std::cerr << "initial pose " << p0.x << " " << p0.y << " " << p0.yaw << " (+-" << 3 * c.initial_sigma_xy_m << " m, "
                << 3 * c.initial_sigma_yaw_rad * 180 / M_PI << " deg searched)";
    } else {
      loc_->start_global();
      std::cerr << "no initial pose: global localization (the whole map searched; LOST until one place dominates)";
    }
    std::cerr << "; odometry " << (ctx.channel("odom").empty() ? "none" : ctx.channel("odom")) << "\n";
    out_ = ctx.advertise<fploc::pose_t>("pose");
    if (!ctx.channel("lock").empty()) lock_ = ctx.advertise<fploc::pose_t>("lock");
    ctx.subscribe<fploc::laser_scan_t>("scan", [this](const fploc::laser_scan_t& m) { on_scan(m); });
    ctx.subscribe<fploc::pose_t>("odom", [this](const fploc::pose_t& m) { on_odom(m); });
  }

 private:
  void on_odom(const fploc::pose_t& m) {
    const Pose2 p = fploc::adapters::pose2_of(m);
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.yaw)) {
      ctx_->error("odometry seq " + std::to_string(m.seq) + ": non-finite pose (ignored)");
      return;
    }
    odom_ = p;
    odom_utime_ = m.utime;
  }

  void on_scan(const fploc::laser_scan_t& m) {
    if (!std::isfinite(m.angle_increment) || m.angle_increment == 0 || m.ranges.empty()) {
      ctx_->error("scan utime " + std::to_string(m.utime) + ": bad geometry (angle_increment " +
                  std::to_string(m.angle_increment) + ", " + std::to_string(m.ranges.size()) + " ranges)");
      return;
    }
    const auto& c = loc_->config();
    const double rmin = std::max<double>(c.min_range_m, m.range_min);
    const double rmax = m.range_max > 0 ? std::min<double>(c.max_range_m, m.range_max) : c.max_range_m;
    const auto pts = l2::scan_points(m.ranges, m.angle_min, m.angle_increment, rmin, rmax, mount_, upside_down_);
    std::optional<Pose2> odom;
    if (odom_ && odom_utime_ <= m.utime) odom = odom_;
    const l2::GridResult r = loc_->update(pts, odom, double(m.utime) * 1e-6);
    if (debug_)
      std::cerr << "[grid2d] " << seq_ << " " << r.pose.x << " " << r.pose.y << " " << r.pose.yaw * 180 / M_PI << " status "
                << int(r.status) << " inl " << r.inlier_ratio << " n " << r.num_points << " win " << r.search_xy_m << " m "
                << r.search_yaw_rad * 180 / M_PI << " deg score " << r.score << "\n";
    say_status(r, c);
    say_global(r, c);
    // While the whole map is searched there is no estimate: the pose is a placeholder (the map's centre), published
    // with status 3 (NOT_INITIALISED, "no estimate", as frame_pose_t's) so that loggers and scores leave it out.
    const int8_t status = r.global && r.status != l2::GridStatus::kOk ? int8_t(l2::GridStatus::kNotInitialised) : int8_t(r.status);
    const auto msg = fploc::adapters::make_pose_msg(m.utime, seq_++, r.pose, 0, 0, z_, r.covariance, 0.01, 0.01, status,
                                                    true, true, floor_.index, floor_.name);
    out_.publish(msg);
    if (r.global) searching_ = true;
    if (searching_ && r.status == l2::GridStatus::kOk) {
      searching_ = false;
      if (!ctx_->channel("lock").empty()) {
        // Its position searched within 3 sigma by the matcher: at least 0.5 m (the scan it registers next may be the
        // next one, up to a metre on: the lock is taken where the plan pipeline then searches, not a fit's centimetres).
        auto seed = msg;
        for (int i : {0, 7}) seed.covariance[i] = std::max(seed.covariance[i], 0.25);
        lock_.publish(seed);
        std::cerr << "[" << ctx_->name() << "] scan " << seq_ - 1 << ": global lock at " << r.pose.x << " " << r.pose.y << " "
                  << r.pose.yaw << " published on " << ctx_->channel("lock") << "\n";
      }
    }
  }

  // Each change of status (OK / POOR / LOST) with its reason (Context::status_changed: on stderr, the first 200, and
  // telemetry's detail), and LOST as an error (last_error, count) as the matcher says it.
  void say_status(const l2::GridResult& r, const l2::GridLocalizerConfig& c) {
    if (r.status == l2::GridStatus::kOk) bad_run_ = 0;
    else ++bad_run_;
    if (r.status == said_status_) return;
    said_status_ = r.status;
    const char* names[] = {"OK", "POOR", "LOST", "NOT_INITIALISED"};
    char why[320];
    const int pct = int(std::lround(100 * r.inlier_ratio)), need = int(std::lround(100 * c.min_inlier_ratio));
    if (r.status == l2::GridStatus::kOk)
      std::snprintf(why, sizeof why, "%smap fit, %d %% of %d returns within the inlier distance", r.reacquired ? "re-acquired: " : "",
                    pct, r.num_points);
    else if (r.global)
      std::snprintf(why, sizeof why, "global localization: %d place(s) of the whole map still match, none dominates yet "
                    "(the leader: %d %% of %d returns inliers)", r.hypotheses, pct, r.num_points);
    else if (r.num_points < 10)
      std::snprintf(why, sizeof why, "%d returns in range, too few to fit; odometry prediction kept", r.num_points);
    else
      std::snprintf(why, sizeof why,
                    "no map fit trusted for %d scan(s) (best: %d %% of %d returns inliers, %d %% needed; searched +-%.2f m, "
                    "+-%.1f deg)%s", bad_run_, pct, r.num_points, need, r.search_xy_m, r.search_yaw_rad * 180 / M_PI,
                    r.status == l2::GridStatus::kLost ? "; re-acquiring" : "; odometry prediction kept");
    const std::string line = "scan " + std::to_string(seq_) + ": " + names[int(r.status)] + ": " + why;
    bool printed = false;
    // (Searching the whole map is what a start without a pose does, not an error.)
    if (r.status == l2::GridStatus::kLost && !r.global) printed = ctx_->error("LOST at scan " + std::to_string(seq_) + ": " + why);
    ctx_->status_changed(line, true, !printed);
  }

  // Global localization: its progress in telemetry's detail on every scan (and on stderr every 30 s of sensor time),
  // and once, when it runs out of global_budget_s, that it gave up (an error: the node will not localize by itself).
  void say_global(const l2::GridResult& r, const l2::GridLocalizerConfig& c) {
    char line[400];
    if (r.global_gave_up) {
      if (said_gave_up_) return;
      said_gave_up_ = true;
      std::snprintf(line, sizeof line,
                    "global localization gave up after %.1f s of sensor time (grid2d.global_budget_s %.0f s): no place of "
                    "the whole map dominated (%zu still matched); LOST until restarted with grid2d.initial_pose "
                    "(or a longer budget)", r.global_elapsed_s, c.global_budget_s, r.places.size());
      const bool printed = ctx_->error("scan " + std::to_string(seq_) + ": " + line);
      ctx_->status_changed("scan " + std::to_string(seq_) + ": LOST: " + line, true, !printed);
      return;
    }
    if (!r.global) return;
    said_gave_up_ = false;
    const l2::GridPlace* lead = r.places.empty() ? nullptr : &r.places.front();
    char budget[64] = "no budget";
    if (c.global_budget_s > 0) std::snprintf(budget, sizeof budget, "budget %.0f s", c.global_budget_s);
    if (lead)
      std::snprintf(line, sizeof line, "global localization: %.1f s searched (%s), %zu place(s) tracked; the leader "
                    "(%.2f, %.2f, %.0f deg) matched %d scan(s), %.0f %% inliers on average, over %.1f m",
                    r.global_elapsed_s, budget, r.places.size(), lead->pose.x, lead->pose.y, lead->pose.yaw * 180 / M_PI,
                    lead->hits, 100 * lead->mean_inlier_ratio, lead->travel_m);
    else
      std::snprintf(line, sizeof line, "global localization: %.1f s searched (%s), no place of the whole map matches yet",
                    r.global_elapsed_s, budget);
    ctx_->set_detail(line);
    if (r.global_elapsed_s >= next_progress_s_) {
      next_progress_s_ = r.global_elapsed_s + 30;
      std::cerr << "[" << ctx_->name() << "] scan " << seq_ << ": " << line << "\n";
    }
  }

  fploc::rt::Context* ctx_ = nullptr;
  bool said_gave_up_ = false;
  double next_progress_s_ = 30;  // the first progress line after 30 s (the status line says the start)
  l2::GridStatus said_status_ = l2::GridStatus::kNotInitialised;  // the first scan's status is said too
  int bad_run_ = 0;
  std::unique_ptr<l2::GridLocalizer> loc_;
  fploc::rt::Publisher<fploc::pose_t> out_, lock_;
  bool searching_ = false;  // a whole-map search has not locked yet
  std::optional<Pose2> odom_;
  int64_t odom_utime_ = 0;
  Pose2 mount_;
  bool upside_down_ = false;
  double z_ = 0;
  int64_t seq_ = 0;
  fploc::config::FloorRef floor_;
  bool debug_ = std::getenv("FPLOC_GRID2D_DEBUG") != nullptr;
};

}  // namespace
FPLOC_REGISTER_NODE(Grid2dNode)
