// Options (proto/options/localization.proto) -> the localization configs. Zero / empty options mean
// "the default", and the defaults are the Config structs' own (written once, there); the comments of
// the proto state them and config_defaults_test checks that they agree.
#pragma once
#include "fploc/localizer/localizer.h"
#include "fploc/odometry/odometry.h"
#include "options/localization.pb.h"

namespace fploc::config {

matcher::MatcherConfig config_of(const MatcherOptions& o);
optimizer::OptimizerConfig config_of(const OptimizerOptions& o);
odometry::OdometryConfig config_of(const OdometryOptions& o);
// The Localizer of a matcher node (SFR step: matcher, IMU, initial search) and of an optimizer node (WO step).
localizer::Config localizer_config(const MatcherOptions& o);
localizer::Config localizer_config(const OptimizerOptions& o);

}  // namespace fploc::config
