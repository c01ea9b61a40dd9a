#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include "fploc/annf/ablation.h"
#include "fploc/annf/annf.h"
#include "fploc/floorplan/io.h"

using namespace fploc;
using namespace fploc::annf;

namespace {
bool have_shared() { return std::filesystem::exists(std::string(FPLOC_SHARED_DIR) + "/data/floorplans"); }

// A small synthetic plan with every element kind, corners, a pillar and a curved wall.
FloorPlan synthetic() {
  FloorPlan p;
  p.source = "synthetic";
  const int w = p.layer_index("walls"), c = p.layer_index("cols");
  p.elements.push_back(Element::segment({0, 0}, {12, 0}, w));
  p.elements.push_back(Element::segment({12, 0}, {12, 8}, w));
  p.elements.push_back(Element::segment({12, 8}, {0, 8}, w));
  p.elements.push_back(Element::segment({0, 8}, {0, 0}, w));
  p.elements.push_back(Element::segment({5, 0}, {5, 3.5}, w));
  p.elements.push_back(Element::circle({8, 4}, 0.3, c));
  p.elements.push_back(Element::circle({3, 5}, 0.25, c));
  p.elements.push_back(Element::arc({9, 8}, 1.5, M_PI, 2 * M_PI, w));
  p.elements.push_back(Element::arc({2, 2}, 1.0, 0.2, 1.5, w));
  return p;
}

double exact_rate(const Annf& a, const FloorPlan& plan, int n, uint32_t seed) {
  std::mt19937 rng(seed);
  const Box2 b = plan.bounds();
  std::uniform_real_distribution<double> ux(b.min.x(), b.max.x()), uy(b.min.y(), b.max.y());
  int hits = 0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d p(ux(rng), uy(rng));
    double d_true, d;
    nearest_element_brute_force(plan, p, &d_true);
    a.nearest(p, &d);
    hits += std::abs(d - d_true) <= 1e-9;
  }
  return double(hits) / n;
}
}  // namespace

TEST(Annf, ExactModeIsExactOnSynthetic) {
  const auto plan = synthetic();
  AnnfOptions o;
  o.mode = AnnfMode::kExact;
  o.root_length = 4;
  o.max_depth = 8;
  const Annf a = Annf::build(plan, o);
  EXPECT_EQ(exact_rate(a, plan, 100000, 1), 1.0);
  // Distance and closest point agree with the model.
  double d;
  Eigen::Vector2d q;
  const int id = a.nearest({6, 2}, &d, &q);
  EXPECT_EQ(id, 4);
  EXPECT_NEAR(d, 1.0, 1e-12);
  EXPECT_NEAR(q.x(), 5.0, 1e-12);
}

TEST(Annf, PaperModeDepthImprovesAndLookupIsConsistent) {
  const auto plan = synthetic();
  AnnfOptions o;
  o.root_length = 4;
  o.max_depth = 2;
  const double coarse = exact_rate(Annf::build(plan, o), plan, 20000, 2);
  o.max_depth = 8;
  const Annf fine = Annf::build(plan, o);
  const double r = exact_rate(fine, plan, 20000, 2);
  EXPECT_GT(r, coarse);
  // The reading that keeps the two elements nearest to the centre among all elements (not only
  // those passing through the field) is the more accurate one.
  AnnfOptions all = o;
  all.paper_candidates = AnnfOptions::Candidates::kAll;
  all.paper_distinct_distances = false;
  EXPECT_GT(exact_rate(Annf::build(plan, all), plan, 20000, 2), 0.9);
  int n;
  const uint32_t* ids = fine.lookup({6, 1}, &n);
  ASSERT_NE(ids, nullptr);
  EXPECT_GE(n, 1);
  EXPECT_LE(n, 2);
  EXPECT_EQ(fine.lookup({-100, 0}, &n), nullptr);
  EXPECT_EQ(n, 0);
  // Outside: nearest falls back to brute force.
  double d;
  EXPECT_EQ(fine.nearest({-100, 4}, &d), 3);
  EXPECT_NEAR(d, 100.0, 1e-9);
}

TEST(Annf, SaveLoadRoundTrip) {
  const auto plan = synthetic();
  AnnfOptions o;
  o.mode = AnnfMode::kExact;
  o.root_length = 4;
  o.max_depth = 7;
  const Annf a = Annf::build(plan, o);
  const std::string path = testing::TempDir() + "/annf_roundtrip.fpmap";
  a.save(path);
  const Annf b = Annf::load(path);
  EXPECT_EQ(b.plan().elements.size(), plan.elements.size());
  EXPECT_EQ(b.stats().bytes, a.stats().bytes);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-1, 13);
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector2d p(U(rng), U(rng) * 0.7);
    int n1, n2;
    const uint32_t* c1 = a.lookup(p, &n1);
    const uint32_t* c2 = b.lookup(p, &n2);
    ASSERT_EQ(n1, n2);
    for (int k = 0; k < n1; ++k) EXPECT_EQ(c1[k], c2[k]);
  }
  // The plan inside the map loads through the generic loader.
  EXPECT_EQ(load_floor_plan(path).elements.size(), plan.elements.size());
  // A corrupted file is a clear error, not a crash.
  std::string bytes;
  {
    std::ifstream f(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(f), {});
  }
  for (size_t cut : {size_t(4), size_t(20), bytes.size() / 2, bytes.size() - 3}) {
    const std::string bad = testing::TempDir() + "/annf_bad.fpmap";
    std::ofstream(bad, std::ios::binary).write(bytes.data(), std::streamsize(cut));
    EXPECT_THROW(Annf::load(bad), std::runtime_error) << cut;
  }
  std::string flipped = bytes;
  flipped[bytes.size() - 20] ^= 0x5a;
  const std::string bad = testing::TempDir() + "/annf_flip.fpmap";
  std::ofstream(bad, std::ios::binary).write(flipped.data(), std::streamsize(flipped.size()));
  EXPECT_THROW(Annf::load(bad), std::runtime_error);
  std::string old = bytes;
  old[8] = 99;  // version
  std::ofstream(bad, std::ios::binary).write(old.data(), std::streamsize(old.size()));
  try {
    Annf::load(bad);
    FAIL() << "old version accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("version 99"), std::string::npos) << e.what();
  }
}

TEST(Annf, ExactOnCorridorPlan) {
  if (!have_shared()) GTEST_SKIP() << "no ../shared/data";
  const auto plan = load_floor_plan(std::string(FPLOC_SHARED_DIR) + "/data/floorplans/annf-demo-corridor-lines.csv", {}, "cm");
  AnnfOptions o;
  o.mode = AnnfMode::kExact;
  o.max_depth = 9;
  const Annf a = Annf::build(plan, o);
  EXPECT_EQ(exact_rate(a, plan, 50000, 4), 1.0);
}

TEST(Annf, BatchEqualsSingle) {
  const auto plan = synthetic();
  for (AnnfMode mode : {AnnfMode::kPaper, AnnfMode::kExact}) {
    AnnfOptions o;
    o.mode = mode;
    o.root_length = 4;
    o.max_depth = 7;
    const Annf a = Annf::build(plan, o);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> U(-3, 15);  // includes points outside the field
    std::vector<Eigen::Vector2d> pts(1000), closest(1000);
    for (auto& p : pts) p = {U(rng), U(rng) * 0.7};
    std::vector<int> ids(pts.size());
    std::vector<double> d(pts.size());
    a.nearest_batch(pts.data(), pts.size(), ids.data(), d.data(), closest.data());
    std::vector<const uint32_t*> recs(pts.size());
    std::vector<int> counts(pts.size());
    a.lookup_batch(pts.data(), pts.size(), recs.data(), counts.data());
    std::vector<int> ids_no_closest(pts.size());
    std::vector<double> d_no_closest(pts.size());
    a.nearest_batch(pts.data(), pts.size(), ids_no_closest.data(), d_no_closest.data());
    for (size_t i = 0; i < pts.size(); ++i) {
      double d1;
      Eigen::Vector2d c1;
      ASSERT_EQ(a.nearest(pts[i], &d1, &c1), ids[i]) << i;
      EXPECT_EQ(d1, d[i]);
      EXPECT_EQ(c1, closest[i]);
      EXPECT_EQ(ids_no_closest[i], ids[i]);
      EXPECT_EQ(d_no_closest[i], d[i]);
      int n1;
      const uint32_t* c = a.lookup(pts[i], &n1);
      ASSERT_EQ(recs[i], c);
      ASSERT_EQ(counts[i], n1);
    }
  }
}

// The bottom-up rule withdraws a division only where every max-depth field below has the same
// first element, so a look-up's first element equals the one of the full (never stopped) tree,
// while the tree is smaller.
TEST(Annf, CollapseFirstKeepsTheFullTreesFirstElement) {
  const auto plan = synthetic();
  AnnfOptions o;
  o.root_length = 4;
  o.max_depth = 7;
  o.paper_rule = PaperRule::kFull;
  const Annf full = Annf::build(plan, o);
  o.paper_rule = PaperRule::kCollapseFirst;
  const Annf collapsed = Annf::build(plan, o);
  EXPECT_LT(collapsed.stats().leaves, full.stats().leaves / 2);
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> U(-1, 13);
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector2d p(U(rng), U(rng) * 0.7);
    ASSERT_EQ(collapsed.first_candidate(p), full.first_candidate(p)) << p.transpose();
  }
}

// "Passing through": a leaf stores only elements that pass through one of its ancestors' fields
// (its own when any passes through it).
TEST(Annf, PassingCandidatesPassThroughTheField) {
  const auto plan = synthetic();
  for (auto cand : {AnnfOptions::Candidates::kPassingElseAll, AnnfOptions::Candidates::kPassingInherit}) {
    AnnfOptions o;
    o.root_length = 4;
    o.max_depth = 6;
    o.paper_candidates = cand;
    const Annf a = Annf::build(plan, o);
    size_t checked = 0;
    a.for_each_leaf([&](const Box2& box, int, const uint32_t* ids, int n) {
      bool any = false;
      for (const auto& e : plan.elements) any = any || min_distance(e, box) <= 0;
      if (!any) return;
      ++checked;
      for (int k = 0; k < n; ++k) EXPECT_LE(min_distance(plan.elements[ids[k]], box), 0.0);
    });
    EXPECT_GT(checked, 10u);
  }
}

// Exact mode leaves out elements another element covers (duplicates, collinear pieces, arcs on a
// circle) and refines candidate sets; both keep every look-up exact, and the covered elements never
// appear in a leaf.
TEST(Annf, ExactWithCoveredElementsAndRefinement) {
  FloorPlan p = synthetic();
  const size_t n0 = p.elements.size();
  p.elements.push_back(p.elements[0]);                                   // duplicate of wall 0
  p.elements.push_back(Element::segment({12, 8}, {12, 0}));              // wall 1 reversed
  p.elements.push_back(Element::segment({2, 0}, {4, 0}));                // piece of wall 0
  p.elements.push_back(Element::arc({8, 4}, 0.3, 0.5, 2.0));             // on circle 5
  p.elements.push_back(Element::segment({6.5, 6}, {7.5, 6.4}));          // not covered
  for (int refine : {0, 1, 3}) {
    for (int mc : {1, 2, 4}) {
      AnnfOptions o;
      o.mode = AnnfMode::kExact;
      o.root_length = 4;
      o.max_depth = 8;
      o.exact_max_candidates = mc;
      o.exact_refine_levels = refine;
      const Annf a = Annf::build(p, o);
      EXPECT_EQ(exact_rate(a, p, 30000, 7 + refine), 1.0) << "refine " << refine << " mc " << mc;
      a.for_each_leaf([&](const Box2&, int, const uint32_t* ids, int k) {
        for (int i = 0; i < k; ++i) {
          EXPECT_TRUE(ids[i] < n0 || ids[i] == n0 + 4) << ids[i];
        }
      });
    }
  }
  // Refinement gives subsets of the simple bound's sets on the same fields (no subdivision here),
  // strictly smaller in total.
  AnnfOptions o;
  o.mode = AnnfMode::kExact;
  o.root_length = 2;
  o.max_depth = 1;
  o.exact_refine_levels = 0;
  std::vector<std::vector<uint32_t>> simple, refined;
  Annf::build(p, o).for_each_leaf([&](const Box2&, int, const uint32_t* ids, int k) {
    simple.emplace_back(ids, ids + k);
  });
  o.exact_refine_levels = 3;
  Annf::build(p, o).for_each_leaf([&](const Box2&, int, const uint32_t* ids, int k) {
    refined.emplace_back(ids, ids + k);
  });
  ASSERT_EQ(simple.size(), refined.size());
  size_t ns = 0, nr = 0;
  for (size_t i = 0; i < simple.size(); ++i) {
    ns += simple[i].size();
    nr += refined[i].size();
    for (uint32_t id : refined[i]) EXPECT_NE(std::find(simple[i].begin(), simple[i].end(), id), simple[i].end());
  }
  EXPECT_LT(nr, ns);
}

// The fast path (records of up to 4 candidates, two per SSE2 op) and the general path (longer
// records, arcs) agree with brute force on distance and closest point.
TEST(Annf, FastAndGeneralPathsAgreeWithBruteForce) {
  const auto plan = synthetic();
  for (int mc : {1, 3, 4, 6}) {
    AnnfOptions o;
    o.mode = AnnfMode::kExact;
    o.root_length = 4;
    o.max_depth = mc == 6 ? 3 : 7;  // shallow: long records
    o.exact_max_candidates = mc;
    o.exact_refine_levels = 0;
    const Annf a = Annf::build(plan, o);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> U(-1, 13);
    for (int i = 0; i < 20000; ++i) {
      const Eigen::Vector2d q(U(rng), U(rng) * 0.7);
      double d_true, d;
      Eigen::Vector2d c;
      nearest_element_brute_force(plan, q, &d_true);
      const int id = a.nearest(q, &d, &c);
      ASSERT_GE(id, 0);
      ASSERT_NEAR(d, d_true, 1e-9) << q.transpose() << " mc " << mc;
      EXPECT_NEAR((c - q).norm(), d, 1e-9);
      EXPECT_NEAR(distance(plan.elements[id], q), d, 1e-9);
    }
  }
}

// A drawing in mm read as metres (the Barcelona pavilion's DXF with $INSUNITS 0: 52 x 23 km) built 33 million root
// fields for minutes in the matcher, silent after the loader's warning. Now one error naming the plan, its extents and
// the units; a large real site (the synthetic plan x 50: 600 x 400 m) still builds.
TEST(Annf, APlanInTheWrongUnitsIsRefused) {
  FloorPlan mm = synthetic();
  scale_plan(mm, 1000);
  mm.source = "plan_mm.dxf";
  try {
    (void)Annf::build(mm, AnnfOptions{});
    FAIL() << "a 12 x 8 km plan was built";
  } catch (const std::runtime_error& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("plan_mm.dxf: plan of 12000 x 8000 m is too large"), std::string::npos) << w;
    EXPECT_NE(w.find("check the units"), std::string::npos) << w;
  }
  FloorPlan site = synthetic();
  scale_plan(site, 50);
  EXPECT_NO_THROW((void)Annf::build(site, AnnfOptions{}));
}
