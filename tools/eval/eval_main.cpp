// fploc eval --gt GT.tum --est EST.tum [--plot FILE.svg [--plan P [--floor NAME] [--layers A,B] [--units U]]] [--json]
//            [--align none|se2|se3] [--max-dt S] [--offset S] [--delta D] [--delta-unit s|f]
//            [--uncertainty EST.unc [--false-ok-m M]] [--hat THIRD.tum [--hat-lag N]]
//            [--asbuilt-bound SIGMA --features LOG --plan P [--features-channel CH] [--bound-window S]]
// ATE and RPE as in Sturm et al. 2012 (see modules/eval). No alignment by default: fploc poses are in
// the floor-plan frame, like the ground truth. With --uncertainty (fploc-pose-logger's uncertainty_file):
// NEES of x, y, yaw and the false-OK count (modules/eval/uncertainty.h). JSON on stdout with --json, a
// summary on stderr. With --hat: the three-cornered hat of GT, EST and a third trajectory (e.g. wheel odometry):
// each one's increment noise, i.e. how noisy the reference itself is (modules/eval/reference_noise.h).
// With --asbuilt-bound SIGMA --features LOG --plan P: the as-built bound of the run (modules/eval/asbuilt_bound.h):
// each scan's features (features_t on --features-channel) at the ground-truth pose, the expected error of the best
// per-scan estimate when every vertex of the plan stands N(0, SIGMA^2) off; its rms beside the ATE. --bound-window S:
// the same with the scans within S/2 s of each sharing its pose error (exact odometry over the window).
#include <fploc/features_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <iostream>
#include <sstream>
#include <nlohmann/json.hpp>

#include "fploc/adapters/features_t.h"
#include "fploc/core/text_out.h"
#include "fploc/eval/asbuilt_bound.h"
#include "fploc/eval/eval.h"
#include "fploc/eval/reference_noise.h"
#include "fploc/eval/uncertainty.h"
#include "fploc/floorplan/building.h"
#include "fploc/floorplan/io.h"
#include "fploc/runtime/log_reader.h"

using namespace fploc;

static void usage() {
  std::cerr << "usage: fploc eval --gt GT.tum --est EST.tum [--plot FILE.svg] [--json]   (--plot: SVG only)\n"
               "       [--align none|se2|se3] (default none: both in the floor-plan frame)\n"
               "       [--max-dt S] (association, default 0.02) [--offset S] (added to est times)\n"
               "       [--delta D] [--delta-unit s|f] (RPE delta, default 1 s; f = frames)\n"
               "       [--plan FILE [--floor NAME] [--layers A,B] [--units U]] (drawn under the trajectories of --plot;\n"
               "       --floor: a building's (.pbtxt, .ifc) floor, default the first listed; the legend names it)\n"
               "       [--plot-frame all|trajectories] (the plot's axes frame the trajectories and the whole plan\n"
               "       (default), or the trajectories with a 3 m margin, the plan clipped: a map with stray specks)\n"
               "       [--uncertainty FILE] (status + x/y/yaw covariance per pose: NEES and false OK)\n"
               "       [--false-ok-m M] (horizontal error of a false OK, default 0.3)\n"
               "       [--hat THIRD.tum [--hat-lag N]] (three-cornered hat of gt, est and THIRD: the noise of each,\n"
               "       the reference's own included, from their increments N poses of gt apart, default 1)\n"
               "       [--asbuilt-bound SIGMA --features LOG --plan FILE [--features-channel CH]] (the expected error of\n"
               "       the best per-scan estimate when each plan vertex stands N(0, SIGMA^2) off, from LOG's features at\n"
               "       the gt poses; JSON asbuilt_bound) [--bound-window S] (also each scan's bound with the scans within\n"
               "       S/2 seconds sharing its pose error, as with exact odometry: what smoothing over S could reach)\n";
}

namespace {
double rms_of(const std::vector<double>& v) {
  double e2 = 0;
  for (double e : v) e2 += e * e;
  return std::sqrt(e2 / double(v.size()));
}

double median_of(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// The as-built bound over a recorded run (see the file comment); with window_s > 0 also each scan's bound when
// the scans within window_s / 2 of it share its pose error (exact odometry over the window). A log cut short (or
// damaged part way): the bound of the events read, and "features_problem" says why (main exits 1).
nlohmann::json asbuilt_bound_of(const FloorPlan& plan, const Trajectory& gt, const std::string& log_path,
                                const std::string& channel, double sigma, double window_s, double max_dt) {
  rt::LogReader log(log_path);
  if (!log.good()) throw std::runtime_error(log_path + ": cannot read the LCM log");
  eval::AsBuiltBoundOptions o;
  o.vertex_sigma_m = sigma;
  eval::AsBuiltBound bound(plan, o);
  std::vector<double> times;
  int64_t events = 0, frames = 0, undecoded = 0, unmatched = 0;
  std::vector<Eigen::Vector2d> pts;
  while (const lcm::LogEvent* ev = log.next()) {
    ++events;
    if (ev->channel != channel) continue;
    features_t m;
    if (m.decode(ev->data, 0, ev->datalen) < 0) {
      if (undecoded++ == 0)
        std::cerr << "fploc eval: " << log_path << ": event " << events << " on " << channel
                  << " does not decode as features_t (skipped)\n";
      continue;
    }
    ++frames;
    const FeatureFrame f = adapters::from_msg(m);
    const double t = double(f.utime) * 1e-6;
    const auto it = std::lower_bound(gt.begin(), gt.end(), t, [](const StampedPose& p, double v) { return p.t < v; });
    const StampedPose* best = nullptr;
    for (auto j : {it, it == gt.begin() ? it : std::prev(it)})
      if (j != gt.end() && std::abs(j->t - t) <= max_dt && (!best || std::abs(j->t - t) < std::abs(best->t - t))) best = &*j;
    if (!best || (!times.empty() && best->t <= times.back())) {  // no gt pose, or not after the last scan's
      ++unmatched;
      continue;
    }
    pts.clear();
    for (const auto& q : f.points) pts.push_back(q.p);
    bound.add_scan(Eigen::Vector3d(best->p.x(), best->p.y(), best->rpy().z()), pts);
    times.push_back(best->t);
  }
  const std::string problem = log.problem();
  if (frames == 0)
    throw std::runtime_error("--features " + (problem.empty() ? log_path : problem) + ": no " + channel +
                             " (features_t) events among " + std::to_string(events));
  std::vector<double> err, werr;
  int64_t open = 0;
  for (int k = 0; k < bound.scans(); ++k) {
    const auto b = bound.bound(k);
    if (b.ok()) err.push_back(b.xy_rms_m());
    else ++open;
    if (window_s > 0) {
      const int a = int(std::lower_bound(times.begin(), times.end(), times[size_t(k)] - window_s / 2) - times.begin());
      const int z = int(std::upper_bound(times.begin(), times.end(), times[size_t(k)] + window_s / 2) - times.begin()) - 1;
      const auto w = bound.bound(a, z, k);
      if (w.ok()) werr.push_back(w.xy_rms_m());
    }
  }
  if (err.empty())
    throw std::runtime_error("--features " + log_path + ": none of its " + std::to_string(frames) +
                             " scans lies within --max-dt of a ground-truth pose and constrains the pose");
  const double rms = rms_of(err), median = median_of(err);
  std::cerr << "fploc eval: as-built bound (each plan vertex off by N(0, " << sigma << " m)): expected horizontal error of "
            << "the best per-scan estimate rms " << rms << " m, median " << median << " m over " << err.size()
            << " scans (" << open << " leave a direction open, " << unmatched << " without a gt pose)";
  nlohmann::json j{{"vertex_sigma_m", sigma}, {"rms_m", rms}, {"median_m", median}, {"scans", err.size()},
                   {"scans_open", open}, {"scans_without_gt", unmatched}, {"features", log_path}, {"channel", channel}};
  if (window_s > 0 && !werr.empty()) {
    j["window_s"] = window_s;
    j["window_rms_m"] = rms_of(werr);
    j["window_median_m"] = median_of(werr);
    std::cerr << "; with the scans within " << window_s / 2 << " s sharing the pose error (exact odometry): rms "
              << rms_of(werr) << " m";
  }
  std::cerr << "\n";
  if (!problem.empty()) {
    j["features_problem"] = problem;
    std::cerr << "fploc eval: --features " << problem << "; the bound is of the events read\n";
  }
  return j;
}
}  // namespace

int main(int argc, char** argv) {
  std::string gt_path, est_path, plot, align_s = "none", unit = "s", plan_path, layers, units, unc_path, hat_path, floor;
  std::string plot_frame = "all", features_path, features_channel = "FPLOC_FEATURES";
  double bound_sigma = 0, bound_window = 0;
  int hat_lag = 1;
  bool json = false;
  double max_dt = 0.02, offset = 0, delta = 1.0, false_ok_m = 0.3;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "fploc eval: " << a << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    // A whole, finite number ("1x", "nan", "inf" are not: a NaN --offset associated nothing and blamed --max-dt).
    auto number = [&]() {
      const std::string v = next();
      size_t used = 0;
      const double d = std::stod(v, &used);
      if (used != v.size() || !std::isfinite(d)) throw std::invalid_argument(v);
      return d;
    };
    try {
      if (a == "--gt") gt_path = next();
      else if (a == "--est") est_path = next();
      else if (a == "--plot") plot = next();
      else if (a == "--json") json = true;
      else if (a == "--align") align_s = next();
      else if (a == "--max-dt") max_dt = number();
      else if (a == "--offset") offset = number();
      else if (a == "--delta") delta = number();
      else if (a == "--delta-unit") unit = next();
      else if (a == "--plan") plan_path = next();
      else if (a == "--floor") floor = next();
      else if (a == "--plot-frame") plot_frame = next();
      else if (a == "--layers") layers = next();
      else if (a == "--units") units = next();
      else if (a == "--uncertainty") unc_path = next();
      else if (a == "--false-ok-m") false_ok_m = number();
      else if (a == "--hat") hat_path = next();
      else if (a == "--asbuilt-bound") bound_sigma = number();
      else if (a == "--bound-window") bound_window = number();
      else if (a == "--features") features_path = next();
      else if (a == "--features-channel") features_channel = next();
      else if (a == "--hat-lag") {
        const std::string v = next();
        size_t used = 0;
        hat_lag = std::stoi(v, &used);
        if (used != v.size() || hat_lag < 1) {
          std::cerr << "fploc eval: --hat-lag " << v << ": not a whole number >= 1\n";
          return 2;
        }
      }
      else if (a == "-h" || a == "--help") { usage(); return 0; }
      else { std::cerr << "fploc eval: unexpected argument '" << a << "'\n"; usage(); return 2; }
    } catch (const std::exception&) {
      std::cerr << "fploc eval: " << a << " " << argv[i] << ": not a number\n";
      return 2;
    }
  }
  // Each problem named on its own line, then the usage.
  std::string wrong;
  if (gt_path.empty()) wrong += "fploc eval: --gt GT.tum is missing\n";
  if (est_path.empty()) wrong += "fploc eval: --est EST.tum is missing\n";
  if (unit != "s" && unit != "f") wrong += "fploc eval: --delta-unit " + unit + ": s (seconds) or f (frames)\n";
  auto num = [](double v) { std::ostringstream o; o << v; return o.str(); };
  if (!(delta > 0)) wrong += "fploc eval: --delta " + num(delta) + ": the RPE delta must be > 0\n";
  if (!(max_dt >= 0)) wrong += "fploc eval: --max-dt " + num(max_dt) + ": the association window must be >= 0 [s]\n";
  if (!(false_ok_m > 0)) wrong += "fploc eval: --false-ok-m " + num(false_ok_m) + ": must be > 0 [m]\n";
  // The plot is SVG only: a .png name got SVG bytes (viewers refused it or showed nothing).
  if (!plot.empty()) {
    const auto dot = plot.find_last_of('.'), slash = plot.find_last_of('/');
    std::string ext = dot == std::string::npos || (slash != std::string::npos && dot < slash) ? "" : plot.substr(dot);
    for (auto& ch : ext) ch = char(std::tolower(static_cast<unsigned char>(ch)));
    if (ext != ".svg")
      wrong += "fploc eval: --plot " + plot + ": the plot is written as SVG only; give a file name ending in .svg\n";
  }
  if (!wrong.empty()) {
    std::cerr << wrong;
    usage();
    return 2;
  }
  if (bound_sigma != 0 && (!(bound_sigma > 0) || features_path.empty() || plan_path.empty())) {
    std::cerr << "fploc eval: --asbuilt-bound needs a SIGMA > 0 [m], --features LOG and --plan FILE\n";
    return 2;
  }
  if (bound_sigma == 0 && (!features_path.empty() || bound_window != 0)) {
    std::cerr << "fploc eval: --features and --bound-window are read for --asbuilt-bound SIGMA only\n";
    return 2;
  }
  if (!(bound_window >= 0)) {
    std::cerr << "fploc eval: --bound-window " << bound_window << ": a window in seconds >= 0\n";
    return 2;
  }
  if (!floor.empty() && plan_path.empty()) {
    std::cerr << "fploc eval: --floor needs --plan (a building .pbtxt or .ifc)\n";
    return 2;
  }
  if (hat_lag != 1 && hat_path.empty()) {
    std::cerr << "fploc eval: --hat-lag needs --hat THIRD.tum\n";
    return 2;
  }
  // The plan of --floor (a building's; a single plan has only floor "0"); an unknown floor is an error listing
  // the building's floors. floor_drawn: the floor's name, for the plot's legend ("" for a single plan).
  std::string floor_drawn;
  auto load_plan = [&]() -> FloorPlan {
    if (!is_building_file(plan_path)) return load_floor_plan(plan_path, {layers}, units, floor);
    const Building b = load_building(plan_path);
    const BuildingFloor& f = b.floor(floor);
    floor_drawn = f.name;
    PlanLoadOptions o;
    if (!layers.empty()) o.layer_globs = {layers};
    o.units_override = units;
    return load_floor_plan(b, f.name, o);
  };
  try {
    const auto align = eval::parse_align(align_s);
    const Trajectory gt = read_tum(gt_path), est = read_tum(est_path);
    const auto pairs = eval::associate(gt, est, max_dt, offset);
    if (pairs.empty()) {
      std::cerr << "fploc eval: no pose of " << est_path << " (" << est.size() << " poses) is within " << max_dt
                << " s of one of " << gt_path << " (" << gt.size() << " poses); check --offset / --max-dt\n";
      return 1;
    }
    const auto a = eval::ate(gt, est, pairs, align);
    const auto r = eval::rpe(gt, est, pairs, delta, unit == "f");
    if (!plot.empty()) {
      eval::PlotOptions po;
      if (plot_frame != "all" && plot_frame != "trajectories")
        throw std::runtime_error("--plot-frame: '" + plot_frame + "' is not one of all, trajectories");
      po.frame_trajectories = plot_frame == "trajectories";
      if (!plan_path.empty()) {
        const FloorPlan plan = load_plan();
        if (!floor_drawn.empty()) po.plan_label = "floor plan: floor '" + floor_drawn + "'";
        for (const auto& e : plan.elements) {
          std::vector<Eigen::Vector2d> l;
          if (e.kind == ElementKind::kSegment) {
            l = {e.a, e.b};
          } else {
            const double a0 = e.kind == ElementKind::kCircle ? 0.0 : e.a0, a1 = e.kind == ElementKind::kCircle ? 2 * M_PI : e.a1;
            const int n = std::max(8, int(std::ceil((a1 - a0) * 16 / M_PI)));
            for (int k = 0; k <= n; ++k) {
              const double t = a0 + (a1 - a0) * k / n;
              l.push_back(e.c + e.r * Eigen::Vector2d(std::cos(t), std::sin(t)));
            }
          }
          po.plan.push_back(std::move(l));
        }
      }
      po.est_error = eval::pose_errors(gt, est, pairs, a.S);
      std::ofstream out(plot);
      out << eval::plot_svg(gt, est, "ATE RMSE " + std::to_string(a.trans.rmse).substr(0, 6) + " m (" +
                                         (align_s == "none" ? std::string("no") : align_s) + " alignment), " +
                                         std::to_string(pairs.size()) + " poses", a.S, po);
      if (!out) throw std::runtime_error(plot + ": cannot write");
    }
    auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };
    nlohmann::json j{{"ate_rmse_m", num(a.trans.rmse)},
                     {"ate_mean_m", num(a.trans.mean)},
                     {"ate_median_m", num(a.trans.median)},
                     {"ate_max_m", num(a.trans.max)},
                     {"ate_xy_rmse_m", num(a.trans_xy.rmse)},
                     {"ate_xy_max_m", num(a.trans_xy.max)},
                     {"rpe_mean_m", num(r.trans.mean)},
                     {"rpe_rmse_m", num(r.trans.rmse)},
                     {"rpe_rot_mean_deg", num(r.rot_deg.mean)},
                     {"rpe_pairs", r.trans.n},
                     {"rpe_delta", delta},
                     {"rpe_delta_unit", unit},
                     {"poses", pairs.size()},
                     {"gt_poses", gt.size()},
                     {"est_poses", est.size()},
                     {"align", align_s}};
    if (!unc_path.empty()) {
      const auto u = eval::read_uncertainty(unc_path);
      const auto c = eval::consistency(gt, est, pairs, u, false_ok_m, a.S);
      if (c.poses == 0)
        throw std::runtime_error(unc_path + ": no record at the time of an associated pose of " + est_path);
      j["uncertainty_poses"] = c.poses;
      j["nees_poses"] = c.nees_poses;
      j["nees_mean"] = num(c.nees.mean);
      j["nees_median"] = num(c.nees.median);
      j["nees_x_median"] = num(c.nees_x.median);
      j["nees_y_median"] = num(c.nees_y.median);
      j["nees_yaw_median"] = num(c.nees_yaw.median);
      j["ok_poses"] = c.ok;
      j["false_ok_poses"] = c.false_ok;
      j["false_ok_share"] = c.false_ok_share;
      j["false_ok_m"] = c.false_ok_m;
      std::cerr << "fploc eval: uncertainty of " << c.poses << " poses: NEES (x, y, yaw; 3 if consistent) median "
                << c.nees.median << ", mean " << c.nees.mean << " over " << c.nees_poses << "; 1-DoF medians x "
                << c.nees_x.median << ", y " << c.nees_y.median << ", yaw " << c.nees_yaw.median << "; " << c.ok
                << " OK, " << c.false_ok << " false OK (horizontal error > " << c.false_ok_m << " m)\n";
    }
    if (bound_sigma > 0)
      j["asbuilt_bound"] = asbuilt_bound_of(load_plan(), gt, features_path,
                                            features_channel, bound_sigma, bound_window, max_dt);
    if (!hat_path.empty()) {
      const Trajectory third = read_tum(hat_path);
      eval::HatResult h;
      try {
        h = eval::three_cornered_hat(gt, est, third, max_dt, hat_lag, offset);
      } catch (const std::invalid_argument& e) {
        throw std::runtime_error("--hat " + hat_path + " (" + std::to_string(third.size()) + " poses): " + e.what());
      }
      // A negative variance estimate (the hat's assumptions fail: correlated errors, too few increments) is no
      // noise level: the JSON keeps the signed value under its key and says so in xy_resolvable / yaw_resolvable;
      // the text says "not resolvable". A NaN estimate (an input whose increments overflow a double, e.g. coordinates
      // of 1e200) is no number at all: the JSON's value is null, *_resolvable false, and the text says "NaN", not
      // "negative".
      auto src = [&](const eval::HatSource& s) {
        return nlohmann::json{{"increment_sigma_xy_m", num(eval::signed_sqrt(s.increment_var_xy_m2))},
                              {"increment_sigma_yaw_rad", num(eval::signed_sqrt(s.increment_var_yaw_rad2))},
                              {"pose_sigma_xy_m", num(s.pose_sigma_xy_m)},
                              {"pose_sigma_yaw_rad", num(s.pose_sigma_yaw_rad)},
                              {"xy_resolvable", s.increment_var_xy_m2 >= 0},
                              {"yaw_resolvable", s.increment_var_yaw_rad2 >= 0}};
      };
      j["hat"] = {{"third_file", hat_path}, {"lag", hat_lag}, {"increments", h.increments},
                  {"gt", src(h.ref)}, {"est", src(h.est)}, {"third", src(h.third)}};
      auto noise = [](const eval::HatSource& s) {
        std::ostringstream o;
        auto part = [&](const char* what, double var, double shown, const char* unit) {
          if (std::isnan(var)) o << what << " not computed (the variance estimate is NaN)";
          else if (var >= 0) o << shown << " " << unit;
          else o << what << " not resolvable (negative variance estimate)";
        };
        part("xy", s.increment_var_xy_m2, s.pose_sigma_xy_m, "m");
        o << " / ";
        part("yaw", s.increment_var_yaw_rad2, s.pose_sigma_yaw_rad * 180 / M_PI, "deg");
        return o.str();
      };
      std::cerr << "fploc eval: three-cornered hat over " << h.increments << " increments (lag " << hat_lag
                << "): per-pose noise (if white) gt " << noise(h.ref) << ", est " << noise(h.est) << ", " << hat_path
                << " " << noise(h.third) << "\n";
      bool negative = false, nan = false;
      for (const eval::HatSource* s : {&h.ref, &h.est, &h.third})
        for (const double v : {s->increment_var_xy_m2, s->increment_var_yaw_rad2}) negative |= v < 0, nan |= std::isnan(v);
      if (negative)
        std::cerr << "fploc eval: a negative variance estimate: the hat's assumptions fail (errors correlated between "
                     "two of the trajectories, or too few increments)\n";
      if (nan)
        std::cerr << "fploc eval: a variance estimate is NaN: the increments' differences overflow a double (coordinates "
                     "far too large, another unit or a corrupt file?)\n";
    }
    std::cerr << "fploc eval: " << pairs.size() << " associated poses (gt " << gt.size() << ", est " << est.size()
              << "); ATE rmse " << a.trans.rmse << " m, mean " << a.trans.mean << " m, max " << a.trans.max
              << " m (horizontal: rmse " << a.trans_xy.rmse << " m, max " << a.trans_xy.max << " m); RPE/" << delta << unit << " mean " << r.trans.mean << " m, " << r.rot_deg.mean << " deg ("
              << r.trans.n << " pairs)\n";
    if (r.trans.n == 0) std::cerr << "fploc eval: warning: no pose pair " << delta << unit << " apart: RPE is 0\n";
    if (json) std::cout << fploc::json_text(j) << std::endl;
    return j.contains("asbuilt_bound") && j["asbuilt_bound"].contains("features_problem") ? 1 : 0;
  } catch (const std::exception& e) {
    std::cerr << "fploc eval: " << e.what() << "\n";
    return 1;
  }
}
