// segments_t <-> seg::Segmentation (planes, attitude, wall points). Pure mappings.
#pragma once
#include <fploc/segments_t.hpp>

#include "fploc/segmentation/segmenter.h"

namespace fploc::adapters {

void to_msg(const seg::Segmentation& s, int64_t seq, segments_t& m);
// Throws std::runtime_error naming the field when the message is inconsistent.
void from_msg(const segments_t& m, seg::Segmentation& s);

}  // namespace fploc::adapters
