// fploc-segmenter-ransac: the swappable baseline. Same ports, message and options field as
// fploc-segmenter; the plane fit is PCL's SACSegmentation (RANSAC, perpendicular-plane model).
#include "segmenter_node_impl.h"
#include "fploc/segmentation/ransac_segmenter.h"

namespace {
struct RansacTraits {
  static constexpr const char* kType = "segmenter_ransac";
  static constexpr const char* kExecutable = "segmenter-ransac";
  static constexpr const char* kAlgorithm = "ransac";
  static constexpr const char* kOther = "fploc-segmenter for 'rings'";
  static constexpr const char* kDescription = "ceiling/ground planes (PCL RANSAC) -> roll, pitch, z; wall points";
  static std::unique_ptr<fploc::seg::Segmenter> make(const fploc::SegmenterOptions& o) {
    return std::make_unique<fploc::seg::RansacSegmenter>(
        fploc::config::config_of(o), o.ransac_max_iterations() > 0 ? o.ransac_max_iterations() : 200);
  }
};
using SegmenterRansacNode = fploc::SegmenterNodeT<RansacTraits>;
}  // namespace
FPLOC_REGISTER_NODE(SegmenterRansacNode)
