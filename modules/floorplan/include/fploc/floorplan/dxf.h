// ASCII DXF reader (a focused reader written for fploc: dxflib is GPL-2 and does neither block
// expansion nor extrusion).
//
// Reads from ENTITIES (and BLOCKS for INSERT): LINE, LWPOLYLINE and POLYLINE/VERTEX (bulges become
// arcs, closed flag honoured), CIRCLE, ARC, ELLIPSE and SPLINE (approximated by segments within
// PlanLoadOptions::curve_tolerance), INSERT (expanded recursively with scale, rotation, mirroring,
// column/row arrays; entities on layer "0" take the INSERT's layer), extrusion direction (OCS ->
// WCS by the arbitrary-axis algorithm, so (0,0,-1) mirrors x). Units from $INSUNITS (1 in, 2 ft,
// 4 mm, 5 cm, 6 m; 0/absent = metres) unless PlanLoadOptions::units_override is set. Robust
// extents: entities far away from the bulk are dropped and listed on stderr.
// Text: layer and block names are converted to UTF-8 (glibc iconv) from the file's $DWGCODEPAGE
// (ANSI_1252 -> CP1252, DOS850 -> CP850, ISO8859-n, ...) when $ACADVER is before AC1021 (R2007); R2007 and
// later, and files without a code page, are UTF-8 (a name that is not valid UTF-8 in an R2007+ file with a
// code page is read in the code page: such writers exist). Bytes that do not convert (an unknown code page,
// invalid UTF-8 without a code page) become "\xNN" with a warning on stderr. \U+XXXX escapes are decoded.
// Binary DXF ("AutoCAD Binary DXF" sentinel) is rejected with a clear error.
// Errors name "FILE:LINE: ..." (group-code level) or "FILE:LINE: ENTITY: ..." (entity level).
#pragma once
#include <string>

#include "fploc/floorplan/io.h"

namespace fploc {

FloorPlan read_plan_dxf(const std::string& text, const std::string& source, const PlanLoadOptions& options = {});

// What the last read dropped / skipped (for tools that want to report it).
struct DxfStats {
  int entities_read = 0;        // entities in ENTITIES (before expansion)
  int elements = 0;             // elements produced
  int inserts_expanded = 0;
  int outliers_dropped = 0;
  int unsupported = 0;          // TEXT, HATCH, DIMENSION, ... (ignored)
  double unit_scale = 1.0;      // metres per drawing unit used
};
FloorPlan read_plan_dxf(const std::string& text, const std::string& source, const PlanLoadOptions& options,
                        DxfStats* stats);

}  // namespace fploc
