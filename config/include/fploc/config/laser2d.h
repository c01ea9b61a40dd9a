// Options (proto/options/laser2d.proto) -> the 2D mode's configs: fploc-laser2d's front end and the grid
// localizer (defaults: the structs' own, modules/laser2d; zero in the options = the default). Throws
// OptionError naming the option for a negative value where only > 0 means something and for an unknown
// fit_loss ("grid2d.fit_loss: unknown loss 'x' (use ...)").
#pragma once
#include "fploc/laser2d/grid_localizer.h"
#include "fploc/laser2d/laser2d.h"
#include "options/laser2d.pb.h"

namespace fploc::config {

laser2d::Laser2dConfig config_of(const Laser2dOptions& o);
laser2d::GridLocalizerConfig config_of(const Grid2dOptions& o);

}  // namespace fploc::config
