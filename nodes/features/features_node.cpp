// fploc-features: FPLOC_SEGMENTS -> LOAM corner/surface features, gravity-compensated, projected to 2D,
// PCA line groups -> FPLOC_FEATURES (paper IV-B).
#include <fploc/features_t.hpp>
#include <fploc/segments_t.hpp>

#include "fploc/features/features.h"
#include "fploc/adapters/features_t.h"
#include "fploc/adapters/segments_t.h"
#include "fploc/config/perception.h"
#include "fploc/runtime/node.h"

namespace {

class FeaturesNode : public fploc::rt::Node {
 public:
  static fploc::rt::NodeSpec spec() {
    return {"features", "features", "LOAM corner/surface wall features projected to 2D with PCA line groups",
            {fploc::rt::input<fploc::segments_t>("segments", "FPLOC_SEGMENTS"),
             fploc::rt::output<fploc::features_t>("features", "FPLOC_FEATURES")}};
  }

  void setup(fploc::rt::Context& ctx) override {
    ctx_ = &ctx;
    fx_ = std::make_unique<fploc::feat::FeatureExtractor>(fploc::config::config_of(ctx.options<fploc::FeatureOptions>()));
    out_ = ctx.advertise<fploc::features_t>("features");
    ctx.subscribe<fploc::segments_t>("segments", [this](const fploc::segments_t& m) { on_segments(m); });
  }

 private:
  void on_segments(const fploc::segments_t& m) {
    fploc::features_t msg;
    try {
      fploc::adapters::from_msg(m, seg_);
    } catch (const std::exception& e) {
      ctx_->error(std::string("segments: ") + e.what());
      fploc::FeatureFrame bad;
      bad.utime = m.utime;
      bad.scan_seq = m.scan_seq;
      bad.status = fploc::FeatureStatus::kBadInput;
      fploc::adapters::to_msg(bad, seq_++, msg);
      out_.publish(msg);
      return;
    }
    const auto& f = fx_->process(seg_);
    const bool upstream_bad = seg_.status == fploc::seg::SegStatus::kBadInput || seg_.status == fploc::seg::SegStatus::kEmpty;
    // A bad scan is the segmenter's error (in its telemetry); here only what is wrong with this message.
    if (f.status == fploc::FeatureStatus::kBadInput && !upstream_bad)
      ctx_->error("segments seq " + std::to_string(m.seq) + ": bad input (non-finite roll/pitch)");
    fploc::adapters::to_msg(f, seq_++, msg);
    out_.publish(msg);
  }

  fploc::rt::Context* ctx_ = nullptr;
  std::unique_ptr<fploc::feat::FeatureExtractor> fx_;
  fploc::rt::Publisher<fploc::features_t> out_;
  fploc::seg::Segmentation seg_;
  int64_t seq_ = 0;
};

}  // namespace
FPLOC_REGISTER_NODE(FeaturesNode)
