// Every floor's plan of the dashboard's `plan` option, as the page's JSON: GET /api/floors lists them
// ({"floors":[{"index":0,"name":"ground","elevation":0}],"initial":"ground"}), GET /api/plan?floor=NAME
// serves one (the map shows the pose's floor, pose_t.floor, or the one the viewer picks). A single plan
// file is one floor named "0".
#pragma once
#include <map>
#include <string>
#include <vector>

namespace fploc::dashboard {

struct FloorPlans {
  std::map<std::string, std::string> plan_json;  // floor name -> plan JSON (plan_json.h)
  std::string floors_json;
  std::string initial;                            // the option's floor ("" = the first)
};

// Throws std::runtime_error naming the file (and floor).
FloorPlans load_floor_plans(const std::string& path, const std::vector<std::string>& layers, const std::string& units,
                            const std::string& floor);

}  // namespace fploc::dashboard
