// fploc-segmenter: OS1_SCAN (+ OS1_IMU gravity prior) -> ceiling/ground planes, roll/pitch/z, wall points
// -> FPLOC_SEGMENTS. The paper's ring-seeded M-estimator (modules/segmentation).
#include "segmenter_node_impl.h"

namespace {
struct RingTraits {
  static constexpr const char* kType = "segmenter";
  static constexpr const char* kExecutable = "segmenter";
  static constexpr const char* kAlgorithm = "rings";
  static constexpr const char* kOther = "fploc-segmenter-ransac for 'ransac'";
  static constexpr const char* kDescription = "ceiling/ground planes (ring seeds + M-estimator) -> roll, pitch, z; wall points";
  static std::unique_ptr<fploc::seg::Segmenter> make(const fploc::SegmenterOptions& o) {
    return std::make_unique<fploc::seg::RingSegmenter>(fploc::config::config_of(o));
  }
};
using SegmenterNode = fploc::SegmenterNodeT<RingTraits>;
}  // namespace
FPLOC_REGISTER_NODE(SegmenterNode)
