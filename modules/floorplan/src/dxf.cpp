#include "fploc/floorplan/dxf.h"

#include <stdexcept>

namespace fploc {

FloorPlan read_plan_dxf(const std::string& text, const std::string& source, const PlanLoadOptions& options) {
  return read_plan_dxf(text, source, options, nullptr);
}

FloorPlan read_plan_dxf(const std::string& text, const std::string& source, const PlanLoadOptions& options,
                        DxfStats* stats) {
  throw std::runtime_error(source + ": DXF reader not implemented yet");
}

}  // namespace fploc
