// Floor plan loading for the dashboard and its JSON form for the page:
// {"units":"m","source":...,"bounds":[minx,miny,maxx,maxy],"elements":[{"type":"segment","a":[x,y],"b":[x,y]},
//  {"type":"circle","c":[x,y],"r":r},{"type":"arc","c":[x,y],"r":r,"a0":rad,"a1":rad}]}
#pragma once
#include <string>
#include <vector>

#include "fploc/floorplan/plan.h"

namespace fploc::dashboard {

// Uses fploc/floorplan/io.h (every plan format) when the floorplan module has it, else reads the
// JSON plan format only. Throws std::runtime_error naming the file.
// `floor`: a building (.pbtxt) or IFC file's floor ("" = the first).
FloorPlan load_plan_file(const std::string& path, const std::vector<std::string>& layers, const std::string& units,
                         const std::string& floor = "");
std::string plan_to_json(const FloorPlan& plan);

}  // namespace fploc::dashboard
