#include "fploc/config/check.h"

#include "fploc/config/amcl.h"
#include "fploc/config/laser2d.h"
#include "fploc/config/localization.h"
#include "fploc/config/perception.h"
#include "fploc/config/plandiff.h"
#include "fploc/config/recording.h"
#include "fploc/config/relocalization.h"

namespace fploc::config {

namespace {
template <class O, class F>
bool run(const google::protobuf::Message& m, F&& f) {
  const auto* o = dynamic_cast<const O*>(&m);
  if (o) f(*o);
  return o != nullptr;
}
}  // namespace

void check_options(const google::protobuf::Message& m) {
  run<MatcherOptions>(m, [](const auto& o) { localizer_config(o); }) ||
      run<OptimizerOptions>(m, [](const auto& o) { localizer_config(o); }) ||
      run<OdometryOptions>(m, [](const auto& o) { config_of(o); }) ||
      run<SegmenterOptions>(m, [](const auto& o) { config_of(o); }) ||
      run<FeatureOptions>(m, [](const auto& o) { config_of(o); }) ||
      run<RelocalizerOptions>(m, [](const auto& o) {
        config_of(o);
        schedule_of(o);
      }) ||
      run<AmclOptions>(m, [](const auto& o) { config_of(o); }) ||
      run<Grid2dOptions>(m, [](const auto& o) { config_of(o); }) ||
      run<Laser2dOptions>(m, [](const auto& o) { config_of(o); }) ||
      run<CloudToScanOptions>(m, [](const auto& o) { config_of(o); }) ||
      run<PlanDiffOptions>(m, [](const auto& o) { config_of(o); });
}

}  // namespace fploc::config
