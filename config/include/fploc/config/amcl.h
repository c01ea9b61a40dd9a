// Options (proto/options/amcl.proto) -> the AMCL baseline's Settings (defaults: the structs' own).
#pragma once
#include "fploc/amcl/settings.h"
#include "options/amcl.pb.h"

namespace fploc::config {

// Throws std::runtime_error naming the option (e.g. "amcl.resampler: 'x' (use ...)").
amcl::Settings config_of(const AmclOptions& o);

}  // namespace fploc::config
