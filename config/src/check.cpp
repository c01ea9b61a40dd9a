#include "fploc/config/check.h"

#include <algorithm>
#include <options/ndt.pb.h>

#include "fploc/config/amcl.h"
#include "fploc/config/laser2d.h"
#include "fploc/config/localization.h"
#include "fploc/config/perception.h"
#include "fploc/config/plandiff.h"
#include "fploc/config/recording.h"
#include "fploc/config/relocalization.h"
#include "fploc/matcher/map.h"

namespace fploc::config {

namespace {
template <class O, class F>
bool run(const google::protobuf::Message& m, F&& f) {
  const auto* o = dynamic_cast<const O*>(&m);
  if (o) f(*o);
  return o != nullptr;
}
}  // namespace

void check_lookup(const std::string& lookup, const char* block) {
  const auto& names = matcher::lookup_names();
  if (lookup.empty() || std::find(names.begin(), names.end(), lookup) != names.end()) return;
  std::string use;
  for (size_t i = 0; i < names.size(); ++i)
    use += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + ("\"" + names[i] + "\"");
  throw OptionError(block, "lookup", "unknown look-up '" + lookup + "' (use " + use + ")");
}

void check_plan_given(const PlanSource& plan, const char* block) {
  if (plan.file().empty()) throw OptionError(block, "plan.file", "no floor plan given");
}

void check_options(const google::protobuf::Message& m) {
  run<MatcherOptions>(m, [](const auto& o) {
    localizer_config(o);
    check_lookup(o.lookup(), "matcher");
  }) ||
      run<OptimizerOptions>(m, [](const auto& o) {
        localizer_config(o);
        check_lookup(o.lookup(), "optimizer");
      }) ||
      run<OdometryOptions>(m, [](const auto& o) { config_of(o); }) ||
      run<SegmenterOptions>(m, [](const auto& o) { config_of(o); }) ||
      run<FeatureOptions>(m, [](const auto& o) { config_of(o); }) ||
      run<RelocalizerOptions>(m, [](const auto& o) {
        config_of(o);
        schedule_of(o);
        check_lookup(o.lookup(), "relocalizer");
      }) ||
      run<AmclOptions>(m, [](const auto& o) { config_of(o); }) ||
      run<Grid2dOptions>(m, [](const auto& o) { config_of(o); }) ||
      run<Laser2dOptions>(m, [](const auto& o) { config_of(o); }) ||
      run<CloudToScanOptions>(m, [](const auto& o) { config_of(o); }) ||
      run<PlanDiffOptions>(m, [](const auto& o) { config_of(o); });
}

void check_plan_required(const google::protobuf::Message& m) {
  run<MatcherOptions>(m, [](const auto& o) { check_plan_given(o.plan(), "matcher"); }) ||
      run<OptimizerOptions>(m, [](const auto& o) { check_plan_given(o.plan(), "optimizer"); }) ||
      run<RelocalizerOptions>(m, [](const auto& o) { check_plan_given(o.plan(), "relocalizer"); }) ||
      run<NdtOptions>(m, [](const auto& o) { check_plan_given(o.plan(), "ndt"); }) ||
      run<AmclOptions>(m, [](const auto& o) { check_plan_given(o.plan(), "amcl"); }) ||
      run<Grid2dOptions>(m, [](const auto& o) { check_plan_given(o.plan(), "grid2d"); }) ||
      run<PlanDiffOptions>(m, [](const auto& o) { check_plan_given(o.plan(), "plan_diff"); });
}

}  // namespace fploc::config
