#include "fploc/matcher/map.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "fploc/floorplan/io.h"
#include "fploc/floorplan/occupancy.h"
#include "fploc/annf/annf.h"
#include "fploc/annf/cache.h"

namespace fploc::matcher {

namespace {

// Candidates from the ANNF leaf. Leaves with more candidates than the caller takes (exact mode at
// max depth) and points outside the covered area use Annf::nearest (exact).
class AnnfLookup : public NearestLookup {
 public:
  AnnfLookup(std::shared_ptr<const annf::Annf> annf, bool first_only, std::string name)
      : annf_(std::move(annf)), first_only_(first_only), name_(std::move(name)) {}
  const std::vector<Element>& targets() const override { return annf_->plan().elements; }
  int candidates(const Eigen::Vector2d& p, int* out, int max) const override {
    if (max <= 0) return 0;
    int n = 0;
    const uint32_t* ids = annf_->lookup(p, &n);
    if (n > 0 && (first_only_ || n <= max)) {
      const int k = first_only_ ? 1 : n;
      for (int i = 0; i < k; ++i) out[i] = int(ids[i]);
      return k;
    }
    const int id = annf_->nearest(p);
    if (id < 0) return 0;
    out[0] = id;
    return 1;
  }
  std::string name() const override { return name_; }

 private:
  std::shared_ptr<const annf::Annf> annf_;
  bool first_only_;
  std::string name_;
};

}  // namespace

const std::vector<std::string>& lookup_names() {
  static const std::vector<std::string> n = {"annf-exact", "annf-paper", "annf-paper-first", "kdtree", "brute-force"};
  return n;
}


namespace {

LocalizationMap finish(LocalizationMap m, const std::string& lookup, std::shared_ptr<const void> annf_in) {
  if (std::find(lookup_names().begin(), lookup_names().end(), lookup) == lookup_names().end())
    throw std::runtime_error("unknown look-up '" + lookup + "' (annf-exact, annf-paper, annf-paper-first, kdtree, brute-force)");
  if (m.plan->elements.empty()) throw std::runtime_error(m.plan->source + ": the floor plan has no elements");
  if (lookup == "kdtree") {
    m.lookup = std::make_unique<KdTreeLookup>(*m.plan);
    return m;
  }
  if (lookup == "brute-force") {
    m.lookup = std::make_unique<BruteForceLookup>(*m.plan);
    return m;
  }
  const annf::AnnfMode mode = lookup == "annf-exact" ? annf::AnnfMode::kExact : annf::AnnfMode::kPaper;
  auto annf = std::static_pointer_cast<const annf::Annf>(annf_in);
  if (!annf || annf->options().mode != mode) {
    annf::AnnfOptions o;
    o.mode = mode;
    std::string how;
    annf = annf::cached_annf(*m.plan, o, &how);  // built once per plan and options, shared (fploc/annf/cache.h)
    m.note += std::string(m.note.empty() ? "" : "; ") + how;
  }
  m.annf = annf;
  m.lookup = std::make_unique<AnnfLookup>(annf, lookup == "annf-paper-first", lookup);
  return m;
}

bool ends_with(std::string s, const std::string& suf) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s.size() >= suf.size() && s.compare(s.size() - suf.size(), suf.size(), suf) == 0;
}

}  // namespace

void add_occupancy_extras(LocalizationMap& m, const std::string& path) {
  if (!ends_with(path, ".yaml") && !ends_with(path, ".yml")) return;
  const OccupancyGrid grid = read_occupancy_map(path);
  m.free_space = std::make_shared<const FreeSpace>(grid);
  m.map_sigma_m = grid.resolution / std::sqrt(12.0);
}

LocalizationMap make_localization_map(FloorPlan plan, const std::string& lookup) {
  LocalizationMap m;
  m.plan = std::make_shared<const FloorPlan>(std::move(plan));
  return finish(std::move(m), lookup, nullptr);
}

LocalizationMap load_localization_map(const std::string& path, const std::vector<std::string>& layers,
                                      const std::string& units, const std::string& lookup) {
  LocalizationMap m;
  std::shared_ptr<const void> annf;
  if (ends_with(path, ".fpmap")) {
    auto a = std::make_shared<const annf::Annf>(annf::Annf::load(path));
    m.plan = std::make_shared<const FloorPlan>(a->plan());
    m.note = "loaded " + path;
    annf = a;
    return finish(std::move(m), lookup, annf);
  }
  m.plan = std::make_shared<const FloorPlan>(load_floor_plan(path, layers, units));
  m.note = "loaded " + path;
  add_occupancy_extras(m, path);
  return finish(std::move(m), lookup, annf);
}

}  // namespace fploc::matcher