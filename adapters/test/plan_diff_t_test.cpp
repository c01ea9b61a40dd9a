#include "fploc/adapters/plan_diff_t.h"

#include <gtest/gtest.h>

using namespace fploc;

TEST(PlanDiffAdapter, MissingMovedAndNewItems) {
  FloorPlan plan;
  Element wall;
  wall.kind = ElementKind::kSegment;
  wall.a = {0, 0};
  wall.b = {4, 0};
  plan.elements.push_back(wall);  // 0: seen where expected
  plan.elements.push_back(wall);  // 1: missing
  Element moved = wall;
  moved.a = {0, 2};
  moved.b = {0, 6};               // 2: along +y, moved 0.1 m to its left (-x)
  plan.elements.push_back(moved);
  plandiff::Diff d;
  d.frames = 12;
  d.scale_error = 0.004;
  for (int i = 0; i < 3; ++i) {
    plandiff::ElementDiff e;
    e.id = i;
    e.status = i == 0 ? plandiff::Status::kSeen : i == 1 ? plandiff::Status::kMissing : plandiff::Status::kMoved;
    e.offset_m = i == 2 ? 0.1 : 0.0;
    e.probes_expected = 10;
    e.probes_seen = i == 1 ? 0 : 9;
    d.elements.push_back(e);
  }
  plandiff::NewStructure n;
  n.a = {1, 1};
  n.b = {3, 1};
  n.rms_m = 0.01;
  d.added.push_back(n);

  const plan_diff_t m = adapters::to_msg(d, plan, 123, 4);
  EXPECT_EQ(m.utime, 123);
  EXPECT_EQ(m.seq, 4);
  EXPECT_EQ(m.frames, 12);
  EXPECT_EQ(m.elements_seen, 1);
  EXPECT_EQ(m.elements_missing, 1);
  EXPECT_EQ(m.elements_moved, 1);
  EXPECT_DOUBLE_EQ(m.scale_error, 0.004);
  ASSERT_EQ(m.num_items, 3);  // the seen wall is not an item
  EXPECT_EQ(m.kind[0], int8_t(adapters::PlanDiffKind::kMissing));
  EXPECT_EQ(m.element[0], 1);
  EXPECT_EQ(m.kind[1], int8_t(adapters::PlanDiffKind::kMoved));
  EXPECT_NEAR(m.x0[1], -0.1, 1e-6);  // drawn where it was seen
  EXPECT_NEAR(m.y1[1], 6.0, 1e-6);
  EXPECT_NEAR(m.seen_ratio[1], 0.9, 1e-6);
  EXPECT_EQ(m.kind[2], int8_t(adapters::PlanDiffKind::kNew));
  EXPECT_EQ(m.element[2], -1);
}

TEST(PlanDiffAdapter, MissingPartsExtensionsAndRefinement) {
  FloorPlan plan;
  Element wall;
  wall.kind = ElementKind::kSegment;
  wall.a = {0, 0};
  wall.b = {4, 0};
  plan.elements.push_back(wall);
  plandiff::Diff d;
  plandiff::ElementDiff e;
  e.id = 0;
  e.status = plandiff::Status::kSeen;
  d.elements.push_back(e);
  plandiff::NewStructure ext;  // the wall continued beyond b
  ext.a = {4.1, 0};
  ext.b = {4.6, 0};
  ext.extends = 0;
  d.added.push_back(ext);
  plandiff::MissingPart mp;  // a piece of it gone
  mp.element = 0;
  mp.a = {1, 0};
  mp.b = {1.5, 0};
  mp.expected = 20;
  mp.seen = 2;
  d.missing_parts.push_back(mp);
  d.refined.push_back({0, 0.02, -0.01, 40});
  const plan_diff_t m = adapters::to_msg(d, plan, 1, 1);
  ASSERT_EQ(m.num_items, 2);
  EXPECT_EQ(m.kind[0], int8_t(adapters::PlanDiffKind::kNew));
  EXPECT_EQ(m.element[0], 0);  // the element it extends
  EXPECT_EQ(m.kind[1], int8_t(adapters::PlanDiffKind::kMissingPart));
  EXPECT_EQ(m.element[1], 0);
  EXPECT_NEAR(m.x1[1], 1.5, 1e-6);
  EXPECT_NEAR(m.seen_ratio[1], 0.1, 1e-6);
  // Neither a missing part nor an extension down-weights the whole element.
  EXPECT_TRUE(adapters::flagged_elements(m).empty());
  ASSERT_EQ(m.num_refined, 1);
  const auto r = adapters::refined_offsets(m);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].element, 0);
  EXPECT_NEAR(r[0].offset_a, 0.02, 1e-6);
  EXPECT_NEAR(r[0].offset_b, -0.01, 1e-6);
}
