// A negative value for an option where only > 0 means something (0 = the default) is one error naming the
// option (config::OptionError from config::check_options, the mapping the nodes run and `fploc launch
// --check` runs); it was silently taken as the default. Options whose proto comment gives negative values a
// meaning, and positions/offsets, are listed below and keep taking them.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "fploc/config/check.h"
#include "options/laser2d.pb.h"
#include "options/localization.pb.h"
#include "options/perception.pb.h"
#include "options/plandiff.pb.h"
#include "options/recording.pb.h"
#include "options/relocalization.pb.h"

namespace {

using google::protobuf::FieldDescriptor;
using google::protobuf::Message;

// BLOCK.FIELD that take a negative value on purpose (documented in the proto) or are signed quantities.
const std::set<std::string> kSigned = {
    "matcher.max_points", "matcher.prediction_sigma_m", "matcher.prediction_sigma_deg", "matcher.odom_gate_sigmas",
    "matcher.max_speed_mps", "matcher.gap_s", "relocalizer.max_speed_mps",
    "matcher.plan_diff_weight", "matcher.as_built_loss_scale_m", "optimizer.max_points",
    "optimizer.keyframe_interval_s", "optimizer.max_final_delay_s", "optimizer.plan_diff_weight",
    "optimizer.as_built_loss_scale_m", "grid2d.confirm_within_sigmas", "grid2d.far_confirm_travel_m",
    "grid2d.laser_conflict_inlier_ratio", "grid2d.global_budget_s", "grid2d.mount_x_m", "grid2d.mount_y_m", "grid2d.mount_yaw_deg", "grid2d.z_m",
    "laser2d.mount_x_m", "laser2d.mount_y_m", "laser2d.mount_yaw_deg", "laser2d.z_m",
};

// Every top-level number field of `proto` (block name `block`) set to -1: an OptionError naming it, unless
// listed above or not read by the mapping (`unread`, e.g. fields the node uses as they are).
void check_all(const Message& proto, const std::string& block, const std::set<std::string>& unread = {}) {
  const auto* d = proto.GetDescriptor();
  for (int i = 0; i < d->field_count(); ++i) {
    const FieldDescriptor* f = d->field(i);
    if (f->is_repeated()) continue;
    const std::string name = block + "." + f->name();
    std::unique_ptr<Message> m(proto.New());
    const auto* r = m->GetReflection();
    switch (f->cpp_type()) {
      case FieldDescriptor::CPPTYPE_INT32: r->SetInt32(m.get(), f, -1); break;
      case FieldDescriptor::CPPTYPE_INT64: r->SetInt64(m.get(), f, -1); break;
      case FieldDescriptor::CPPTYPE_DOUBLE: r->SetDouble(m.get(), f, -1); break;
      case FieldDescriptor::CPPTYPE_FLOAT: r->SetFloat(m.get(), f, -1); break;
      default: continue;
    }
    if (kSigned.count(name) || unread.count(f->name())) {
      EXPECT_NO_THROW(fploc::config::check_options(*m)) << name;
      continue;
    }
    try {
      fploc::config::check_options(*m);
      ADD_FAILURE() << name << " = -1 was accepted";
    } catch (const fploc::config::OptionError& e) {
      EXPECT_EQ(e.field, f->name());
      EXPECT_EQ(std::string(e.what()).rfind(name + ": must be", 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find("got -1"), std::string::npos) << e.what();
    }
  }
}

}  // namespace

TEST(NegativeOptions, LocalizationOptionsAreErrors) {
  check_all(fploc::MatcherOptions(), "matcher");
  check_all(fploc::OptimizerOptions(), "optimizer");
  check_all(fploc::OdometryOptions(), "odometry");
}

TEST(NegativeOptions, PerceptionOptionsAreErrors) {
  check_all(fploc::SegmenterOptions(), "segmenter");
  check_all(fploc::FeatureOptions(), "features");
}

TEST(NegativeOptions, RelocalizerAnd2dOptionsAreErrors) {
  check_all(fploc::RelocalizerOptions(), "relocalizer");
  check_all(fploc::Grid2dOptions(), "grid2d");
  check_all(fploc::Laser2dOptions(), "laser2d");
  check_all(fploc::CloudToScanOptions(), "cloud_to_scan");
}

TEST(NegativeOptions, PlanDiffOptionsAreErrors) { check_all(fploc::PlanDiffOptions(), "plan_diff"); }

TEST(NegativeOptions, ZeroStillMeansTheDefault) {
  fploc::OptimizerOptions o;
  o.set_window(0);
  EXPECT_NO_THROW(fploc::config::check_options(o));
  o.set_window(-3);
  try {
    fploc::config::check_options(o);
    FAIL() << "window -3 accepted";
  } catch (const fploc::config::OptionError& e) {
    EXPECT_STREQ(e.what(), "optimizer.window: must be > 0 (0 = the default), got -3");
  }
}
