// Options (proto/options/laser2d.proto) -> the 2D mode's grid localizer config (defaults: the struct's own,
// modules/laser2d/grid_localizer.h; zero in the options = the default). Throws std::runtime_error naming the
// option for an unknown fit_loss ("grid2d.fit_loss: unknown loss 'x' (use ...)").
#pragma once
#include "fploc/laser2d/grid_localizer.h"
#include "options/laser2d.pb.h"

namespace fploc::config {

laser2d::GridLocalizerConfig config_of(const Grid2dOptions& o);

}  // namespace fploc::config
