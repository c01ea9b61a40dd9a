// `--fit-loss huber|cauchy|tukey` for the Radish tools (fploc-real-track, fploc-real-floor): the robust loss of
// the grid localizer's map fit (GridLocalizerConfig::fit_loss).
#pragma once
#include <CLI/CLI.hpp>
#include <string>

#include "fploc/laser2d/grid_localizer.h"

namespace fploc::bench_real {

inline void add_fit_loss_option(CLI::App& app, laser2d::FitLoss& loss) {
  app.add_option_function<std::string>(
      "--fit-loss",
      [&loss](const std::string& name) {
        const auto l = laser2d::fit_loss_from_name(name);
        if (!l) throw CLI::ValidationError("--fit-loss", "unknown loss '" + name + "' (use huber, cauchy or tukey)");
        loss = *l;
      },
      "robust loss of the map fit: huber (the default), cauchy or tukey");
}

}  // namespace fploc::bench_real
