// fploc eval --gt GT.tum --est EST.tum [--plot FILE.svg] [--json] [--align none|se2|se3]
//            [--max-dt S] [--offset S] [--delta D] [--delta-unit s|f]
// ATE and RPE as in Sturm et al. 2012 (see modules/eval). No alignment by default: fploc poses are in
// the floor-plan frame, like the ground truth. JSON on stdout with --json, a summary on stderr.
#include <cmath>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "fploc/eval/eval.h"

using namespace fploc;

static void usage() {
  std::cerr << "usage: fploc eval --gt GT.tum --est EST.tum [--plot FILE.svg] [--json]\n"
               "       [--align none|se2|se3] (default none: both in the floor-plan frame)\n"
               "       [--max-dt S] (association, default 0.02) [--offset S] (added to est times)\n"
               "       [--delta D] [--delta-unit s|f] (RPE delta, default 1 s; f = frames)\n";
}

int main(int argc, char** argv) {
  std::string gt_path, est_path, plot, align_s = "none", unit = "s";
  bool json = false;
  double max_dt = 0.02, offset = 0, delta = 1.0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "fploc eval: " << a << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    try {
      if (a == "--gt") gt_path = next();
      else if (a == "--est") est_path = next();
      else if (a == "--plot") plot = next();
      else if (a == "--json") json = true;
      else if (a == "--align") align_s = next();
      else if (a == "--max-dt") max_dt = std::stod(next());
      else if (a == "--offset") offset = std::stod(next());
      else if (a == "--delta") delta = std::stod(next());
      else if (a == "--delta-unit") unit = next();
      else if (a == "-h" || a == "--help") { usage(); return 0; }
      else { std::cerr << "fploc eval: unexpected argument '" << a << "'\n"; usage(); return 2; }
    } catch (const std::exception&) {
      std::cerr << "fploc eval: " << a << ": not a number\n";
      return 2;
    }
  }
  if (gt_path.empty() || est_path.empty() || (unit != "s" && unit != "f") || !(delta > 0) || !(max_dt >= 0)) {
    usage();
    return 2;
  }
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
      std::ofstream out(plot);
      out << eval::plot_svg(gt, est, "ATE RMSE " + std::to_string(a.trans.rmse).substr(0, 6) + " m (" +
                                         (align_s == "none" ? std::string("no") : align_s) + " alignment), " +
                                         std::to_string(pairs.size()) + " poses", a.S);
      if (!out) throw std::runtime_error(plot + ": cannot write");
    }
    auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };
    nlohmann::json j{{"ate_rmse_m", num(a.trans.rmse)},
                     {"ate_mean_m", num(a.trans.mean)},
                     {"ate_median_m", num(a.trans.median)},
                     {"ate_max_m", num(a.trans.max)},
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
    std::cerr << "fploc eval: " << pairs.size() << " associated poses (gt " << gt.size() << ", est " << est.size()
              << "); ATE rmse " << a.trans.rmse << " m, mean " << a.trans.mean << " m, max " << a.trans.max
              << " m; RPE/" << delta << unit << " mean " << r.trans.mean << " m, " << r.rot_deg.mean << " deg ("
              << r.trans.n << " pairs)\n";
    if (r.trans.n == 0) std::cerr << "fploc eval: warning: no pose pair " << delta << unit << " apart: RPE is 0\n";
    if (json) std::cout << j.dump() << std::endl;
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "fploc eval: " << e.what() << "\n";
    return 1;
  }
}
