// `--fit-loss huber|cauchy|tukey` for the Radish tools (fploc-real-track, fploc-real-floor): the robust loss of
// the grid localizer's map fit (GridLocalizerConfig::fit_loss).
#pragma once
#include <CLI/CLI.hpp>
#include <map>
#include <string>

#include "fploc/laser2d/grid_localizer.h"

namespace fploc::bench_real {

inline void add_fit_loss_option(CLI::App& app, laser2d::FitLoss& loss) {
  static const std::map<std::string, laser2d::FitLoss> names{
      {"huber", laser2d::FitLoss::kHuber}, {"cauchy", laser2d::FitLoss::kCauchy}, {"tukey", laser2d::FitLoss::kTukey}};
  app.add_option("--fit-loss", loss, "robust loss of the map fit (huber: the default)")
      ->transform(CLI::CheckedTransformer(names, CLI::ignore_case));
}

}  // namespace fploc::bench_real
