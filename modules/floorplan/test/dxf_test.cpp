#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <fstream>
#include <sstream>

#include "fploc/floorplan/dxf.h"
#include "fploc/floorplan/io.h"

using namespace fploc;

namespace {
std::string shared(const std::string& rel) { return std::string(FPLOC_SHARED_DIR) + "/data/" + rel; }
bool have_shared() { return std::filesystem::exists(std::string(FPLOC_SHARED_DIR) + "/data/floorplans"); }

// Builds a DXF from "code value" pairs.
struct Dxf {
  std::ostringstream s;
  Dxf& g(int code, const std::string& v) {
    s << "  " << code << "\n" << v << "\n";
    return *this;
  }
  Dxf& g(int code, double v) {
    std::ostringstream t;
    t.precision(17);
    t << v;
    return g(code, t.str());
  }
  Dxf& header(int insunits) { return g(0, "SECTION").g(2, "HEADER").g(9, "$INSUNITS").g(70, insunits).g(0, "ENDSEC"); }
  Dxf& line(double x1, double y1, double x2, double y2, const std::string& layer = "walls") {
    return g(0, "LINE").g(8, layer).g(10, x1).g(20, y1).g(11, x2).g(21, y2);
  }
  std::string str() const { return s.str(); }
};

PlanLoadOptions quiet() {
  PlanLoadOptions o;
  o.quiet = true;
  return o;
}

std::string error_of(const std::string& text, PlanLoadOptions o = quiet()) {
  try {
    read_plan_dxf(text, "t.dxf", o);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(Dxf, LinesCirclesArcsAndUnits) {
  Dxf d;
  d.header(4).g(0, "SECTION").g(2, "ENTITIES");
  d.line(0, 0, 1000, 0);
  d.g(0, "CIRCLE").g(8, "cols").g(10, 2000.0).g(20, 500.0).g(40, 300.0);
  d.g(0, "ARC").g(8, "walls").g(10, 0.0).g(20, 0.0).g(40, 1000.0).g(50, 0.0).g(51, 90.0);
  d.g(0, "ENDSEC").g(0, "EOF");
  auto p = read_plan_dxf(d.str(), "t.dxf", quiet());
  ASSERT_EQ(p.elements.size(), 3u);
  EXPECT_NEAR(p.elements[0].b.x(), 1.0, 1e-12);
  EXPECT_EQ(p.elements[1].kind, ElementKind::kCircle);
  EXPECT_NEAR(p.elements[1].r, 0.3, 1e-12);
  EXPECT_NEAR(distance(p.elements[2], {0, 2}), 1.0, 1e-9);   // (0,1) is on the arc
  EXPECT_NEAR(distance(p.elements[2], {-2, 0}), std::hypot(2, 1), 1e-9);  // arc is the 1st quadrant only
  auto o = quiet();
  o.units_override = "m";
  EXPECT_NEAR(read_plan_dxf(d.str(), "t.dxf", o).elements[0].b.x(), 1000.0, 1e-9);
}

TEST(Dxf, ExtrusionMinusZMirrorsX) {
  Dxf d;
  d.g(0, "SECTION").g(2, "ENTITIES");
  d.g(0, "CIRCLE").g(8, "c").g(10, 5.0).g(20, 1.0).g(40, 0.5).g(210, 0.0).g(220, 0.0).g(230, -1.0);
  // OCS arc 0..90 deg mirrored: WCS 90..180 deg around (-5, 1).
  d.g(0, "ARC").g(8, "c").g(10, 5.0).g(20, 1.0).g(40, 2.0).g(50, 0.0).g(51, 90.0).g(210, 0.0).g(220, 0.0).g(230, -1.0);
  d.g(0, "ENDSEC").g(0, "EOF");
  auto p = read_plan_dxf(d.str(), "t.dxf", quiet());
  ASSERT_EQ(p.elements.size(), 2u);
  EXPECT_NEAR(p.elements[0].c.x(), -5.0, 1e-12);
  EXPECT_NEAR(distance(p.elements[1], {-7, 1}), 0.0, 1e-9);
  EXPECT_NEAR(distance(p.elements[1], {-5, 3}), 0.0, 1e-9);
  EXPECT_GT(distance(p.elements[1], {-3, 1}), 1.0);
}

TEST(Dxf, LwpolylineBulgeIsAnArc) {
  Dxf d;
  d.g(0, "SECTION").g(2, "ENTITIES");
  // (0,0) -> (2,0) with bulge 1: half circle, counter-clockwise, centre (1,0), bulging to y < 0.
  d.g(0, "LWPOLYLINE").g(8, "w").g(90, 2).g(70, 0).g(10, 0.0).g(20, 0.0).g(42, 1.0).g(10, 2.0).g(20, 0.0);
  d.g(0, "ENDSEC").g(0, "EOF");
  auto p = read_plan_dxf(d.str(), "t.dxf", quiet());
  ASSERT_EQ(p.elements.size(), 1u);
  EXPECT_EQ(p.elements[0].kind, ElementKind::kArc);
  EXPECT_NEAR(p.elements[0].r, 1.0, 1e-12);
  EXPECT_NEAR(distance(p.elements[0], {1, -1}), 0.0, 1e-9);
  EXPECT_NEAR(distance(p.elements[0], {1, 1}), std::sqrt(2.0), 1e-9);
}

TEST(Dxf, InsertScaledRotatedMirroredNestedWithLayerInheritance) {
  Dxf d;
  d.g(0, "SECTION").g(2, "BLOCKS");
  d.g(0, "BLOCK").g(8, "0").g(2, "INNER").g(10, 0.0).g(20, 0.0);
  d.line(0, 0, 1, 0, "0");
  d.g(0, "ENDBLK").g(8, "0");
  d.g(0, "BLOCK").g(8, "0").g(2, "OUTER").g(10, 1.0).g(20, 0.0);
  d.g(0, "INSERT").g(8, "0").g(2, "INNER").g(10, 1.0).g(20, 0.0);
  d.g(0, "CIRCLE").g(8, "own").g(10, 1.0).g(20, 1.0).g(40, 0.5);
  d.g(0, "ENDBLK").g(8, "0");
  d.g(0, "ENDSEC");
  d.g(0, "SECTION").g(2, "ENTITIES");
  // Mirror in x (scale -2, 2), rotate 90 deg, insert at (10, 10).
  d.g(0, "INSERT").g(8, "A-WALL").g(2, "OUTER").g(10, 10.0).g(20, 10.0).g(41, -2.0).g(42, 2.0).g(50, 90.0);
  d.g(0, "ENDSEC").g(0, "EOF");
  auto p = read_plan_dxf(d.str(), "t.dxf", quiet());
  ASSERT_EQ(p.elements.size(), 2u);
  // Block-local line (1,0)-(2,0) in OUTER -> minus base (0,0)-(1,0) -> scale (0,0)-(-2,0) -> rot90 (0,0)-(0,-2)
  const auto& s = p.elements[0];
  EXPECT_EQ(p.layers[s.layer], "A-WALL");
  EXPECT_NEAR((s.a - Eigen::Vector2d(10, 10)).norm(), 0.0, 1e-9);
  EXPECT_NEAR((s.b - Eigen::Vector2d(10, 8)).norm(), 0.0, 1e-9);
  const auto& c = p.elements[1];
  EXPECT_EQ(p.layers[c.layer], "own");
  EXPECT_EQ(c.kind, ElementKind::kCircle);
  EXPECT_NEAR(c.r, 1.0, 1e-9);
  // (1,1) - base -> (0,1) -> scale (0,2) -> rot90 (-2,0) -> +ins (8,10)
  EXPECT_NEAR((c.c - Eigen::Vector2d(8, 10)).norm(), 0.0, 1e-9);
}

TEST(Dxf, EllipseAndSplineAreApproximated) {
  Dxf d;
  d.g(0, "SECTION").g(2, "ENTITIES");
  d.g(0, "ELLIPSE").g(8, "e").g(10, 0.0).g(20, 0.0).g(11, 2.0).g(21, 0.0).g(40, 0.5).g(41, 0.0).g(42, 2 * M_PI);
  d.g(0, "SPLINE").g(8, "s").g(71, 2).g(72, 6).g(73, 3);
  for (double k : {0.0, 0.0, 0.0, 1.0, 1.0, 1.0}) d.g(40, k);
  d.g(10, 10.0).g(20, 0.0).g(10, 11.0).g(20, 2.0).g(10, 12.0).g(20, 0.0);
  d.g(0, "ENDSEC").g(0, "EOF");
  auto p = read_plan_dxf(d.str(), "t.dxf", quiet());
  double emax = 0;
  int ne = 0, ns = 0;
  for (const auto& e : p.elements) {
    EXPECT_EQ(e.kind, ElementKind::kSegment);
    if (p.layers[e.layer] == "e") {
      ++ne;
      const Eigen::Vector2d m = (e.a + e.b) / 2;  // chord midpoint: error to the true ellipse
      const double t = std::atan2(m.y() / 1.0, m.x() / 2.0);
      emax = std::max(emax, (m - Eigen::Vector2d(2 * std::cos(t), std::sin(t))).norm());
    } else {
      ++ns;
    }
  }
  EXPECT_GT(ne, 8);
  EXPECT_LT(emax, 0.02);
  EXPECT_GT(ns, 4);
  // Quadratic Bezier midpoint (11, 1) lies on the approximation.
  FloorPlan s;
  for (const auto& e : p.elements)
    if (p.layers[e.layer] == "s") s.elements.push_back(e);
  double d_mid;
  nearest_element_brute_force(s, {11, 1}, &d_mid);
  EXPECT_LT(d_mid, 0.02);
}

TEST(Dxf, BadInputsGiveOneClearError) {
  Dxf ok;
  ok.g(0, "SECTION").g(2, "ENTITIES");
  ok.line(0, 0, 1, 0);
  ok.line(0, 0, 0, 1);
  const std::string body = ok.str();
  // Truncated in the middle of the section.
  EXPECT_NE(error_of(body).find("t.dxf:"), std::string::npos);
  EXPECT_NE(error_of(body).find("truncated"), std::string::npos) << error_of(body);
  EXPECT_NE(error_of(body.substr(0, body.size() - 3)).find("truncated"), std::string::npos);
  // NaN coordinate names the line.
  Dxf nan;
  nan.g(0, "SECTION").g(2, "ENTITIES").g(0, "LINE").g(8, "w").g(10, "0").g(20, "nan").g(11, "1").g(21, "1");
  nan.g(0, "ENDSEC").g(0, "EOF");
  const std::string e = error_of(nan.str());
  EXPECT_NE(e.find("t.dxf:11: LINE"), std::string::npos) << e;
  // Binary DXF.
  EXPECT_NE(error_of(std::string("AutoCAD Binary DXF\r\n\x1a\0", 22)).find("binary DXF"), std::string::npos);
  // Garbage group code.
  EXPECT_NE(error_of("  0\nSECTION\nfoo\nbar\n").find("t.dxf:3"), std::string::npos);
  // Empty layer selection lists the layers.
  Dxf full;
  full.g(0, "SECTION").g(2, "ENTITIES");
  full.line(0, 0, 1, 0, "A-WALL");
  full.g(0, "ENDSEC").g(0, "EOF");
  auto o = quiet();
  o.layer_globs = {"*COLS*"};
  const std::string le = error_of(full.str(), o);
  EXPECT_NE(le.find("no elements on layers matching '*COLS*'"), std::string::npos) << le;
  EXPECT_NE(le.find("A-WALL"), std::string::npos) << le;
  // Recursive block.
  Dxf rec;
  rec.g(0, "SECTION").g(2, "BLOCKS").g(0, "BLOCK").g(2, "B").g(10, 0.0).g(20, 0.0);
  rec.line(0, 0, 1, 0);
  rec.g(0, "INSERT").g(8, "0").g(2, "B").g(10, 1.0).g(20, 0.0);
  rec.g(0, "ENDBLK").g(0, "ENDSEC").g(0, "SECTION").g(2, "ENTITIES").g(0, "INSERT").g(8, "w").g(2, "B");
  rec.g(0, "ENDSEC").g(0, "EOF");
  EXPECT_NE(error_of(rec.str()).find("nesting"), std::string::npos) << error_of(rec.str());
}

TEST(Dxf, StrayFarAwayEntitiesAreDropped) {
  Dxf d;
  d.g(0, "SECTION").g(2, "ENTITIES");
  for (int i = 0; i < 40; ++i) d.line(i * 0.5, 0, i * 0.5, 10);
  d.line(5e6, 5e6, 5e6 + 1, 5e6);
  d.g(0, "ENDSEC").g(0, "EOF");
  DxfStats st;
  auto p = read_plan_dxf(d.str(), "t.dxf", quiet(), &st);
  EXPECT_EQ(p.elements.size(), 40u);
  EXPECT_EQ(st.outliers_dropped, 1);
  EXPECT_LT(p.bounds().size().maxCoeff(), 50);
}

TEST(Dxf, RealBarcelonaPavilion) {
  if (!have_shared()) GTEST_SKIP() << "no ../shared/data";
  PlanLoadOptions o = quiet();
  auto p = load_floor_plan(shared("floorplans/barcelona_pavilion_plan.dxf"), o);
  std::map<ElementKind, int> k;
  for (const auto& e : p.elements) ++k[e.kind];
  EXPECT_EQ(k[ElementKind::kSegment], 954);  // LINE 954, CIRCLE 188, ARC 69 (data README)
  EXPECT_EQ(k[ElementKind::kCircle], 188);
  EXPECT_EQ(k[ElementKind::kArc], 69);
  const auto b = p.bounds().size();
  EXPECT_GT(b.x(), 30);
  EXPECT_LT(b.x(), 100);
  o.layer_globs = {"Walls", "Columns"};
  auto w = load_floor_plan(shared("floorplans/barcelona_pavilion_plan.dxf"), o);
  EXPECT_GT(w.elements.size(), 10u);
  EXPECT_LT(w.elements.size(), p.elements.size());
}

TEST(Dxf, RealShanghaiTechColumnsInsideBlocks) {
  if (!have_shared()) GTEST_SKIP() << "no ../shared/data";
  PlanLoadOptions o = quiet();
  o.layer_globs = {"*COLS-I"};
  DxfStats st;
  std::ifstream f(shared("floorplans/shanghaitech_SIST-F4-filtered.dxf"), std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(f)), {});
  auto p = read_plan_dxf(text, "sist.dxf", o, &st);
  int circles = 0;
  for (const auto& e : p.elements) circles += e.kind == ElementKind::kCircle;
  EXPECT_EQ(circles, 138);
  EXPECT_GT(st.inserts_expanded, 0);
  EXPECT_NEAR(st.unit_scale, 0.001, 1e-15);
  for (const auto& e : p.elements)
    if (e.kind == ElementKind::kCircle) {
      EXPECT_GT(e.r, 0.1);
      EXPECT_LT(e.r, 1.0);
    }
  o.layer_globs = {"*WALL*", "*COLS*"};
  auto all = read_plan_dxf(text, "sist.dxf", o);
  const auto b = all.bounds().size();
  EXPECT_GT(b.x(), 50);
  EXPECT_LT(b.x(), 400);
  EXPECT_LT(b.y(), 400);
}

namespace {
// A plan with one line on `layer`, the header giving $ACADVER / $DWGCODEPAGE when not empty.
std::string with_codepage(const std::string& acadver, const std::string& codepage, const std::string& layer) {
  Dxf d;
  d.g(0, "SECTION").g(2, "HEADER");
  if (!acadver.empty()) d.g(9, "$ACADVER").g(1, acadver);
  if (!codepage.empty()) d.g(9, "$DWGCODEPAGE").g(3, codepage);
  d.g(0, "ENDSEC").g(0, "SECTION").g(2, "ENTITIES").line(0, 0, 1, 0, layer).line(0, 1, 1, 1, "other");
  return d.g(0, "ENDSEC").g(0, "EOF").str();
}
std::string first_layer(const std::string& text) {
  const FloorPlan p = read_plan_dxf(text, "t.dxf", quiet());
  return p.layers[p.elements[0].layer];
}
}  // namespace

// Layer names in the file's code page were kept as raw bytes ('W\xe4nde'), so --layers 'Wände' matched nothing.
TEST(Dxf, NamesInTheFilesCodePageAreUtf8) {
  const std::string latin1 = "W\xe4nde";  // "Wände" in Windows-1252
  EXPECT_EQ(first_layer(with_codepage("AC1015", "ANSI_1252", latin1)), "W\u00e4nde");
  EXPECT_EQ(first_layer(with_codepage("AC1015", "DOS850", "W\x84nde")), "W\u00e4nde");           // CP850 0x84
  EXPECT_EQ(first_layer(with_codepage("AC1015", "ANSI_1251", "\xd1\xf2\xe5\xed\xe0")), "\u0421\u0442\u0435\u043d\u0430");
  // R2007 and later are UTF-8 whatever $DWGCODEPAGE says; a name that is not UTF-8 there (a writer that declares
  // AC1027 and writes the code page, as in the user's file) is read in the code page.
  EXPECT_EQ(first_layer(with_codepage("AC1021", "ANSI_1252", "W\u00e4nde")), "W\u00e4nde");
  EXPECT_EQ(first_layer(with_codepage("AC1027", "ANSI_1252", latin1)), "W\u00e4nde");
  // Invalid UTF-8 without a code page, and an unknown code page: the bytes escaped, not raw.
  EXPECT_EQ(first_layer(with_codepage("AC1027", "", latin1)), "W\\xE4nde");
  EXPECT_EQ(first_layer(with_codepage("AC1015", "ANSI_99999", latin1)), "W\\xE4nde");
  PlanLoadOptions o = quiet();
  o.layer_globs = {"W\u00e4nde"};
  EXPECT_EQ(read_plan_dxf(with_codepage("AC1015", "ANSI_1252", latin1), "t.dxf", o).elements.size(), 1u);
}

// The note about a dropped far-away entity printed its coordinates with %.1f: ~300 digits for 5e300.
TEST(Dxf, DroppedEntityNoteKeepsLargeCoordinatesShort) {
  Dxf d;
  d.g(0, "SECTION").g(2, "ENTITIES");
  for (int i = 0; i < 40; ++i) d.line(i * 0.5, 0, i * 0.5, 10);
  d.line(5e300, 5e300, 5e300, 6e300);
  d.line(12345.25, 0, 12345.25, 1);
  d.g(0, "ENDSEC").g(0, "EOF");
  PlanLoadOptions o;
  testing::internal::CaptureStderr();
  read_plan_dxf(d.str(), "t.dxf", o);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("near (5e+300, 5.5e+300) m"), std::string::npos) << err;
  EXPECT_NE(err.find("near (12345.2, 0.5) m"), std::string::npos) << err;  // ordinary ones as before
  EXPECT_LT(err.size(), 600u) << err;
}
