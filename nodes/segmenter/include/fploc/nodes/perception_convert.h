// LCM <-> perception types (segments_t, features_t) and options -> configs, shared by fploc-segmenter,
// fploc-segmenter-ransac and fploc-features.
#pragma once
#include <fploc/features_t.hpp>
#include <fploc/segments_t.hpp>

#include "fploc/features/features.h"
#include "fploc/segmentation/segmenter.h"
#include "options/perception.pb.h"

namespace fploc {

void to_msg(const seg::Segmentation& s, int64_t seq, segments_t& m);
// Throws std::runtime_error naming the field when the message is inconsistent.
void from_msg(const segments_t& m, seg::Segmentation& s);
void to_msg(const FeatureFrame& f, int64_t seq, features_t& m);

seg::SegmenterConfig config_of(const SegmenterOptions& o);
feat::FeatureConfig config_of(const FeatureOptions& o);

}  // namespace fploc
