#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "fploc/floorplan/io.h"

using namespace fploc;

namespace {
std::string shared(const std::string& rel) { return std::string(FPLOC_SHARED_DIR) + "/data/" + rel; }
bool have_shared() { return std::filesystem::exists(std::string(FPLOC_SHARED_DIR) + "/data/floorplans"); }

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(PlanIo, CsvWithHeaderAndUnits) {
  std::istringstream in("x1,y1,x2,y2\n0,0,100,0\n\n# comment\n100,0,100,250\n");
  PlanLoadOptions o;
  o.units_override = "cm";
  auto plan = read_plan_csv(in, "t.csv", o);
  ASSERT_EQ(plan.elements.size(), 2u);
  EXPECT_NEAR(plan.elements[1].b.y(), 2.5, 1e-12);
  EXPECT_NEAR(plan.elements[0].b.x(), 1.0, 1e-12);
}

TEST(PlanIo, CsvBadRowNamesFileAndLine) {
  std::istringstream in("x1,y1,x2,y2\n0,0,1,0\n0,0,abc,1\n");
  const std::string err = error_of([&] { read_plan_csv(in, "bad.csv", {}); });
  EXPECT_NE(err.find("bad.csv:3:"), std::string::npos) << err;
}

TEST(PlanIo, CsvNanIsAnError) {
  std::istringstream in("0,0,1,0\n0,nan,1,1\n");
  const std::string err = error_of([&] { read_plan_csv(in, "nan.csv", {}); });
  EXPECT_NE(err.find("nan.csv:2:"), std::string::npos) << err;
}

TEST(PlanIo, JsonRoundTripKeepsKindsIdsAndLayers) {
  FloorPlan p;
  p.source = "mem";
  p.elements.push_back(Element::segment({0, 0}, {1, 2}, p.layer_index("walls")));
  p.elements.push_back(Element::circle({3, 3}, 0.25, p.layer_index("cols")));
  p.elements.push_back(Element::arc({1, 1}, 2.0, 0.5, 2.0, p.layer_index("walls")));
  std::stringstream ss;
  write_plan_json(p, ss);
  auto q = read_plan_json(ss, "mem.json");
  ASSERT_EQ(q.elements.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(q.elements[i].kind, p.elements[i].kind);
    EXPECT_EQ(q.layers[q.elements[i].layer], p.layers[p.elements[i].layer]);
    for (Eigen::Vector2d x : {Eigen::Vector2d(0.3, 0.7), Eigen::Vector2d(-2, 5)})
      EXPECT_NEAR(distance(q.elements[i], x), distance(p.elements[i], x), 1e-9);
  }
}

TEST(PlanIo, JsonUnitsAndLayerGlobs) {
  std::istringstream in(R"({"units":"mm","elements":[{"type":"segment","a":[0,0],"b":[1000,0],"layer":"A-WALL"},
    {"type":"circle","c":[0,0],"r":300,"layer":"S-COLS"}]})");
  PlanLoadOptions o;
  o.layer_globs = {"*wall*"};
  auto plan = read_plan_json(in, "u.json", o);
  ASSERT_EQ(plan.elements.size(), 1u);
  EXPECT_NEAR(plan.elements[0].b.x(), 1.0, 1e-12);
}

// One meaning of a layer list everywhere: "A,B" as one entry (--layers 'A,B', plan.layers: "A,B") selects
// the same elements as the two entries "A" and "B" (the bench used to pass "A,B" as one glob).
TEST(PlanIo, CommaSeparatedLayerListIsSplit) {
  EXPECT_EQ(split_layer_globs({"*wall*,S-COLS", "", "x,,y"}),
            (std::vector<std::string>{"*wall*", "S-COLS", "x", "y"}));
  const auto p = std::filesystem::temp_directory_path() / "fploc-layers-test.json";
  std::ofstream(p) << R"({"elements":[{"type":"segment","a":[0,0],"b":[1,0],"layer":"A-WALL"},
    {"type":"circle","c":[0,0],"r":0.3,"layer":"S-COLS"},{"type":"segment","a":[0,1],"b":[1,1],"layer":"F"}]})";
  const auto one = load_floor_plan(p.string(), {"*wall*,S-COLS"});
  const auto two = load_floor_plan(p.string(), {"*wall*", "S-COLS"});
  std::filesystem::remove(p);
  EXPECT_EQ(one.elements.size(), 2u);
  EXPECT_EQ(two.elements.size(), 2u);
}

TEST(PlanIo, EmptyLayerSelectionIsAnError) {
  std::istringstream in(R"({"elements":[{"type":"segment","a":[0,0],"b":[1,0],"layer":"walls"}]})");
  PlanLoadOptions o;
  o.layer_globs = {"nothing*"};
  const std::string err = error_of([&] { read_plan_json(in, "e.json", o); });
  EXPECT_NE(err.find("e.json: no elements on layers matching 'nothing*'"), std::string::npos) << err;
  EXPECT_NE(err.find("walls"), std::string::npos) << err;
}

TEST(PlanIo, JsonBadElementNamesIndex) {
  std::istringstream in(R"({"elements":[{"type":"segment","a":[0,0],"b":[1,0]},{"type":"circle","c":[0,0]}]})");
  const std::string err = error_of([&] { read_plan_json(in, "b.json", {}); });
  EXPECT_NE(err.find("b.json: elements[1]"), std::string::npos) << err;
}

// "unit": "cm" (for "units") loaded the plan in metres without a word; a typo in an element was ignored too.
TEST(PlanIo, JsonUnknownKeyIsAnError) {
  std::istringstream top(R"({"unit":"cm","elements":[{"type":"segment","a":[0,0],"b":[1,0]}]})");
  EXPECT_EQ(error_of([&] { read_plan_json(top, "u.json", {}); }),
            "u.json: unknown key \"unit\" (known keys: units, elements)");
  std::istringstream el(R"({"elements":[{"type":"segment","a":[0,0],"b":[1,0]},{"a":[0,0],"b":[1,0],"colour":"red"}]})");
  EXPECT_EQ(error_of([&] { read_plan_json(el, "e.json", {}); }),
            "e.json: elements[1]: segment: unknown key \"colour\" (known keys: type, a, b, layer)");
  std::istringstream arc(R"({"elements":[{"type":"arc","c":[0,0],"r":1,"start_deg":0,"end":90}]})");
  EXPECT_EQ(error_of([&] { read_plan_json(arc, "a.json", {}); }),
            "a.json: elements[0]: arc: unknown key \"end\" (known keys: type, c, r, start_deg, end_deg, layer)");
  std::istringstream ok(R"({"units":"cm","elements":[{"type":"circle","c":[0,0],"r":30,"layer":"cols"}]})");
  EXPECT_NEAR(read_plan_json(ok, "ok.json", {}).elements[0].r, 0.3, 1e-12);
}

TEST(PlanIo, GlobMatchesRealLayerNames) {
  EXPECT_TRUE(glob_match("*$A-WALL", "E1-RI-1F$0$A-WALL"));
  EXPECT_TRUE(glob_match("e-cols-f4*", "E-COLS-F4$0$0S-COLS-I"));
  EXPECT_FALSE(glob_match("*WALL", "A-WALL-PATT"));
}

TEST(PlanIo, CorridorCsvInCentimetres) {
  if (!have_shared()) GTEST_SKIP() << "no ../shared/data";
  auto plan = load_floor_plan(shared("floorplans/annf-demo-corridor-lines.csv"), {}, "cm");
  EXPECT_EQ(plan.elements.size(), 416u);
  const auto b = plan.bounds();
  EXPECT_GT(b.size().x(), 10.0);
  EXPECT_LT(b.size().x(), 500.0);
}

TEST(PlanIo, UnknownExtensionAndMissingFile) {
  EXPECT_NE(error_of([] { load_floor_plan("x.txt"); }).find("x.txt"), std::string::npos);
  EXPECT_NE(error_of([] { load_floor_plan("/nonexistent/p.csv"); }).find("/nonexistent/p.csv: cannot open"),
            std::string::npos);
}

// Saving to an extension it cannot write (e.g. `fploc occupancy map.yaml --out building.dxf`): one error naming
// the file, and the file that was there is left as it was (it used to be emptied before the extension was checked).
TEST(PlanIo, SaveWithUnsupportedExtensionLeavesTheFileAlone) {
  const std::string dir = ::testing::TempDir();
  FloorPlan plan;
  Element e;
  e.a = {0, 0};
  e.b = {1, 0};
  plan.elements.push_back(e);
  for (const std::string name : {"building.dxf", "notes.txt", "noext"}) {
    const std::string path = dir + "/" + name;
    { std::ofstream(path) << "the user's own file\n"; }
    const std::string err = error_of([&] { save_floor_plan(plan, path); });
    EXPECT_NE(err.find(path + ": unsupported extension"), std::string::npos) << err;
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    EXPECT_EQ(s.str(), "the user's own file\n") << name;
  }
  const std::string fresh = dir + "/fresh.svg";
  std::filesystem::remove(fresh);
  EXPECT_NE(error_of([&] { save_floor_plan(plan, fresh); }), "");
  EXPECT_FALSE(std::filesystem::exists(fresh)) << "an empty file left behind";
}

// A directory or an empty file where a plan is expected: one error about the path, from every reader
// (it used to be "note: no EOF marker" then "no supported entities" for a DXF, a JSON parse error, ...).
TEST(PlanIo, DirectoryOrEmptyFileIsNamedAsSuch) {
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) / "plan_io_dir_test";
  std::filesystem::remove_all(dir);
  for (const std::string ext : {".dxf", ".json", ".csv", ".fpmap", ".yaml", ".ifc", ".pbtxt"}) {
    const std::string d = (dir / ("plan" + ext)).string();
    std::filesystem::create_directories(d);
    EXPECT_EQ(error_of([&] { load_floor_plan(d); }), d + ": is a directory");
    const std::string e = (dir / ("empty" + ext)).string();
    { std::ofstream(e, std::ios::binary); }
    EXPECT_EQ(error_of([&] { load_floor_plan(e); }), e + ": empty file");
  }
  EXPECT_EQ(error_of([&] { read_input_file(dir.string()); }), dir.string() + ": is a directory");
  std::filesystem::remove_all(dir);
}
