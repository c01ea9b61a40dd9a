#include "plan_diff_json.h"

#include <cmath>
#include <nlohmann/json.hpp>
#include "fploc/core/text_out.h"

namespace fploc::dashboard {

std::string plan_diff_json(const fploc::plan_diff_t& m) {
  static const char* kinds[] = {"?", "missing", "moved", "new", "missing", "low"};  // 4: a missing part; 5: low structure
  auto r4 = [](double v) { return std::isfinite(v) ? std::round(v * 1e4) / 1e4 : 0.0; };
  nlohmann::json items = nlohmann::json::array();
  for (int i = 0; i < m.num_items; ++i) {
    const int k = m.kind[size_t(i)];
    items.push_back({{"kind", kinds[k >= 1 && k <= 5 ? k : 0]},
                     {"element", m.element[size_t(i)]},
                     {"circle", bool(m.circle[size_t(i)])},
                     {"x0", r4(m.x0[size_t(i)])},
                     {"y0", r4(m.y0[size_t(i)])},
                     {"x1", r4(m.x1[size_t(i)])},
                     {"y1", r4(m.y1[size_t(i)])},
                     {"offset_m", r4(m.offset_m[size_t(i)])}});
  }
  return fploc::json_text(nlohmann::json{{"utime", m.utime},          {"frames", m.frames},
                                         {"seen", m.elements_seen},    {"missing", m.elements_missing},
                                         {"moved", m.elements_moved},  {"unobserved", m.elements_unobserved},
                                         {"scale_error", m.scale_error}, {"scale_sigma", m.scale_sigma},
                                         {"items", items}});
}

}  // namespace fploc::dashboard
