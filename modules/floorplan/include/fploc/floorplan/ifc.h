// IFC (IFC2x3 / IFC4, .ifc) as a building. The model is read by web-ifc (npm, run by Node) in
// tools/ifc/ifc2plan.mjs, which cuts walls, curtain walls (plates, members), columns, windows and
// doors at `cut_height` above each storey's floor into segments on layers named by IFC class
// (IfcWall, IfcColumn, ...), and gives storey elevations, storey ceiling heights (slab undersides)
// and IfcSpace footprints with their heights. This file runs the script and turns its JSON into a
// Building (fploc/floorplan/building.h): one floor per storey, lowest first.
//
// Needs `node` (FPLOC_NODE overrides the binary) and web-ifc installed in tools/ifc/node_modules
// (scripts/setup-web.sh). FPLOC_IFC2PLAN overrides the script's path.
// Elements whose representation items web-ifc gives no geometry for (IfcBlock, IfcBoundingBox, ...)
// are left out with one warning each in Building::warnings ("m.ifc:29: #63=IFCWALL: warning: ..."),
// printed on stderr unless quiet.
// Errors: one std::runtime_error, e.g. "model.ifc:812: truncated file: entity #4711=IFCWALL (line 812)
// is not finished" or "model.ifc: #123=IFCWALL: geometry has non-finite coordinates".
#pragma once
#include <string>

#include "fploc/floorplan/building.h"

namespace fploc {

struct IfcReadOptions {
  double cut_height = 1.0;  // metres above each storey's floor
  bool quiet = false;
};

Building read_ifc_building(const std::string& path, const IfcReadOptions& options = {});
// The script's JSON output as a building (exposed for tests); `source` names the IFC file.
Building building_from_ifc_json(const std::string& json_text, const std::string& source);
// Path of tools/ifc/ifc2plan.mjs used by read_ifc_building.
std::string ifc2plan_script();

}  // namespace fploc
