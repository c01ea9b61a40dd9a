// features_t <-> FeatureFrame (fploc/core/feature_frame.h). Pure mappings.
#pragma once
#include <fploc/features_t.hpp>

#include "fploc/core/feature_frame.h"

namespace fploc::adapters {

// scan_seq from the frame; seq: the publisher's message counter.
void to_msg(const FeatureFrame& f, int64_t seq, features_t& m);
// Non-finite points are dropped (counted in *dropped); non-finite roll/pitch/z become 0 (with their
// sigmas as sent). Throws std::runtime_error naming the fields when the arrays disagree with num_points.
FeatureFrame from_msg(const features_t& m, int* dropped = nullptr);

}  // namespace fploc::adapters
