// Options (proto/options/perception.proto) -> the perception configs (defaults: the Config structs').
#pragma once
#include "fploc/features/features.h"
#include "fploc/segmentation/segmenter.h"
#include "options/perception.pb.h"

namespace fploc::config {

seg::SegmenterConfig config_of(const SegmenterOptions& o);
feat::FeatureConfig config_of(const FeatureOptions& o);

}  // namespace fploc::config
