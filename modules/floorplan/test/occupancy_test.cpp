#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>

#include "fploc/floorplan/io.h"
#include "fploc/floorplan/free_space.h"
#include "fploc/floorplan/occupancy.h"

using namespace fploc;

namespace {
std::string err_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

std::filesystem::path tmpdir() {
  auto d = std::filesystem::temp_directory_path() / ("fploc_occ_" + std::to_string(::getpid()));
  std::filesystem::create_directories(d);
  return d;
}

void write(const std::filesystem::path& p, const std::string& s) {
  std::ofstream f(p, std::ios::binary);
  f << s;
}

// A plan rasterised like `fploc map export-pgm` does it: a cell is occupied (0) when an element passes
// within half a cell diagonal of its centre, else free (254). Returns the PGM bytes.
std::string rasterise(const FloorPlan& plan, double res, double ox, double oy, int w, int h) {
  std::string img(size_t(w) * h, char(254));
  for (int row = 0; row < h; ++row)
    for (int i = 0; i < w; ++i) {
      const int j = h - 1 - row;
      const Eigen::Vector2d c(ox + (i + 0.5) * res, oy + (j + 0.5) * res);
      double d;
      nearest_element_brute_force(plan, c, &d);
      if (d <= res * std::sqrt(0.5)) img[size_t(row) * w + i] = 0;
    }
  return "P5\n# test\n" + std::to_string(w) + " " + std::to_string(h) + "\n255\n" + img;
}

double max_dist(const FloorPlan& from, const FloorPlan& to, double step) {
  double m = 0;
  for (const auto& e : from.elements) {
    const double len = (e.b - e.a).norm();
    const int n = std::max(1, int(std::ceil(len / step)));
    for (int k = 0; k <= n; ++k) {
      double d;
      nearest_element_brute_force(to, e.a + (e.b - e.a) * (double(k) / n), &d);
      m = std::max(m, d);
    }
  }
  return m;
}
}  // namespace

TEST(Occupancy, YamlFieldsAndErrors) {
  const MapYaml y = parse_map_yaml(
      "image: m.pgm\nresolution: 0.05\norigin: [-1.5, 2.0, 0.3]\nnegate: 1\noccupied_thresh: 0.7\nfree_thresh: 0.2\nmode: scale\n", "t.yaml");
  EXPECT_EQ(y.image, "m.pgm");
  EXPECT_DOUBLE_EQ(y.resolution, 0.05);
  EXPECT_DOUBLE_EQ(y.origin_x, -1.5);
  EXPECT_DOUBLE_EQ(y.origin_yaw, 0.3);
  EXPECT_TRUE(y.negate);
  EXPECT_EQ(y.mode, OccupancyMode::kScale);
  EXPECT_NE(err_of([] { parse_map_yaml("image: m.pgm\norigin: [0, 0, 0]\n", "t.yaml"); }).find("t.yaml: resolution: missing"), std::string::npos);
  EXPECT_NE(err_of([] { parse_map_yaml("image: m.pgm\nresolution: abc\norigin: [0,0,0]\n", "t.yaml"); }).find("t.yaml: resolution (line 2): expected a number"),
            std::string::npos);
  EXPECT_NE(err_of([] { parse_map_yaml("image: m.pgm\nresolution: 0.1\norigin: [0,0]\n", "t.yaml"); }).find("t.yaml: origin (line 3): expected [x, y, yaw]"),
            std::string::npos);
  EXPECT_NE(err_of([] { parse_map_yaml("image: m.pgm\nresolution: 0.1\norigin: [0,0,0]\nmode: fancy\n", "t.yaml"); }).find("t.yaml: mode"),
            std::string::npos);
  EXPECT_NE(err_of([] { parse_map_yaml("image: [m.pgm\nresolution: 0.1\n", "t.yaml"); }).find("t.yaml: line"), std::string::npos);
  EXPECT_NE(err_of([] { parse_map_yaml("image: m.pgm\nresolution: 0.1\norigin: [0,0,0]\nfree_thresh: 0.9\n", "t.yaml"); }).find("free_thresh"),
            std::string::npos);
}

TEST(Occupancy, UnknownYamlKeyIsAWarningNamingLineAndKey) {
  const MapYaml y = parse_map_yaml("image: m.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nocupied_thresh: 0.9\nfoo: 1\n", "t.yaml");
  EXPECT_DOUBLE_EQ(y.occupied_thresh, 0.65);  // ignored, as map_server does
  ASSERT_EQ(y.warnings.size(), 2u);
  EXPECT_EQ(y.warnings[0], "t.yaml: line 5: unknown key 'foo' (ignored, as map_server does)");
  EXPECT_EQ(y.warnings[1], "t.yaml: line 4: unknown key 'ocupied_thresh' (ignored, as map_server does; did you mean 'occupied_thresh'?)");
  EXPECT_TRUE(parse_map_yaml("image: m.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nmode: raw\n", "t.yaml").warnings.empty());
}

TEST(Occupancy, PgmErrors) {
  EXPECT_NE(err_of([] { read_pgm("P6\n1 1\n255\n\0\0\0", "a.pgm"); }).find("a.pgm: byte 0: magic"), std::string::npos);
  EXPECT_NE(err_of([] { read_pgm("P5\n10 10\n255\nabc", "a.pgm"); }).find("a.pgm: byte 13: pixels: truncated pixel data (expected 100 bytes, got 3)"),
            std::string::npos);
  EXPECT_NE(err_of([] { read_pgm("P5\n10 x\n255\n", "a.pgm"); }).find("height"), std::string::npos);
  EXPECT_NE(err_of([] { read_pgm("P5\n10", "a.pgm"); }).find("height: missing"), std::string::npos);
  const GrayImage g = read_pgm("P2\n# c\n2 1\n65535\n0 65535\n", "b.pgm");
  ASSERT_EQ(g.value.size(), 2u);
  EXPECT_EQ(g.value[0], 0);
  EXPECT_EQ(g.value[1], 255);
}

// `fploc occupancy DIR` said "image: missing", a YAML whose image is a directory "magic ... got ''".
TEST(Occupancy, DirectoryOrEmptyFileIsNamedAsSuch) {
  const auto d = tmpdir() / "dirs";
  std::filesystem::create_directories(d / "img.pgm");
  EXPECT_EQ(err_of([&] { read_occupancy_map(d.string()); }), d.string() + ": is a directory");
  write(d / "m.yaml", "image: img.pgm\nresolution: 0.1\norigin: [0, 0, 0]\n");
  EXPECT_EQ(err_of([&] { read_occupancy_map((d / "m.yaml").string()); }),
            (d / "m.yaml").string() + ": image: " + (d / "img.pgm").string() + ": is a directory");
  write(d / "e.pgm", "");
  write(d / "e.yaml", "image: e.pgm\nresolution: 0.1\norigin: [0, 0, 0]\n");
  EXPECT_EQ(err_of([&] { read_occupancy_map((d / "e.yaml").string()); }),
            (d / "e.yaml").string() + ": image: " + (d / "e.pgm").string() + ": empty file");
  write(d / "z.yaml", "");
  EXPECT_EQ(err_of([&] { read_occupancy_map((d / "z.yaml").string()); }), (d / "z.yaml").string() + ": empty file");
  std::filesystem::remove_all(d);
}

// A header smaller than the data (height 51 for 515 rows) silently gave a cut map; an ASCII PGM cut in the
// pixels said "truncated PGM header".
TEST(Occupancy, PixelDataLongerOrShorterThanTheHeader) {
  EXPECT_EQ(err_of([] { read_pgm("P5\n4 1\n255\nabcdefghijkl", "a.pgm"); }),
            "a.pgm: byte 15: the pixel data is longer than the header's 4x1 says: 8 bytes after the image (2 more rows of 4)");
  EXPECT_EQ(err_of([] { read_pgm("P2\n2 2\n255\n0 1\n2 3\n4 5\n", "b.pgm"); }),
            "b.pgm: byte 18: the pixel data is longer than the header's 2x2 says: 5 bytes after the image");
  EXPECT_EQ(err_of([] { read_pgm("P2\n3 2\n255\n0 1 2\n3 # c\n", "c.pgm"); }),
            "c.pgm: byte 23: pixel data truncated: got 4 of 3x2 = 6 values");
  // Trailing whitespace after the pixels is fine.
  EXPECT_EQ(read_pgm("P5\n2 1\n255\nab\n", "d.pgm").value.size(), 2u);
  EXPECT_EQ(read_pgm("P2\n2 1\n255\n0 1\n\n", "e.pgm").value.size(), 2u);
}

TEST(Occupancy, ModesAndOrientation) {
  // 3 x 2 image: top row black/mid-grey/white, bottom row white/white/black.
  GrayImage img;
  img.width = 3;
  img.height = 2;
  img.value = {0, 128, 255, 255, 255, 0};
  MapYaml y;
  y.resolution = 0.1;
  y.origin_x = 1;
  y.origin_y = 2;
  OccupancyGrid t = occupancy_from_image(img, y, "x");
  // Row 0 of the grid is the image's bottom row.
  EXPECT_EQ(t.at(0, 0), 0);
  EXPECT_EQ(t.at(2, 0), 100);
  EXPECT_EQ(t.at(0, 1), 100);
  EXPECT_EQ(t.at(1, 1), -1);  // p = 0.498: between the thresholds
  EXPECT_TRUE(t.cell_centre(2, 1).isApprox(Eigen::Vector2d(1.25, 2.15)));
  y.mode = OccupancyMode::kScale;
  OccupancyGrid s = occupancy_from_image(img, y, "x");
  EXPECT_GT(s.at(1, 1), 0);
  EXPECT_LT(s.at(1, 1), 100);
  EXPECT_FALSE(s.occupied(1, 1));
  y.mode = OccupancyMode::kTrinary;
  y.negate = true;
  OccupancyGrid n = occupancy_from_image(img, y, "x");
  EXPECT_EQ(n.at(0, 0), 100);
  EXPECT_EQ(n.at(2, 0), 0);
  y.origin_yaw = M_PI / 2;
  OccupancyGrid r = occupancy_from_image(img, y, "x");
  EXPECT_TRUE(r.cell_centre(0, 0).isApprox(Eigen::Vector2d(0.95, 2.05)));
}

// A wall two cells thick (every cell of it is a boundary cell) becomes its two faces, not a serpentine through
// both columns (seen on data/plans/room.yaml: 587 of 639 segments were such 5 cm zigzags).
TEST(Occupancy, TwoCellWallGivesStraightFaces) {
  OccupancyGrid g;
  g.width = 20;
  g.height = 60;
  g.resolution = 0.05;
  g.data.assign(size_t(g.width) * g.height, 0);
  for (int j = 5; j < 55; ++j) g.data[size_t(j) * g.width + 9] = g.data[size_t(j) * g.width + 10] = 100;
  // A one-cell stub on top: the chain starts at its end and walks down the wall (the serpentine came from walking
  // towards -y or -x, where the +x / +y neighbours were tried first).
  g.data[size_t(55) * g.width + 9] = g.data[size_t(56) * g.width + 9] = 100;
  VectoriseStats st;
  const FloorPlan v = vectorise_occupancy(g, {}, &st);
  EXPECT_EQ(st.boundary_cells, 102u);
  EXPECT_LE(st.max_error_m, 0.5 * g.resolution + 1e-9);
  double longest = 0;
  for (const auto& e : v.elements) longest = std::max(longest, (e.b - e.a).norm());
  EXPECT_LE(v.elements.size(), 5u) << "the wall's two faces, its ends and the stub";
  EXPECT_GT(longest, 2.0) << "no segment runs along the wall";
}

// Rasterise a plan with straight, diagonal and short walls, vectorise, and compare both ways: every wall
// point is within one cell of the vectorised plan and vice versa; the chain error is within tolerance.
TEST(Occupancy, RoundTripWithinOneCell) {
  FloorPlan p;
  p.elements.push_back(Element::segment({0, 0}, {6, 0}));
  p.elements.push_back(Element::segment({6, 0}, {6, 4}));
  p.elements.push_back(Element::segment({6, 4}, {0, 4}));
  p.elements.push_back(Element::segment({0, 4}, {0, 0}));
  p.elements.push_back(Element::segment({1, 1}, {4.3, 3.1}));   // diagonal
  p.elements.push_back(Element::segment({5.0, 1.0}, {5.0, 1.4}));  // short
  const double res = 0.05, ox = -0.5, oy = -0.5;
  const int w = 140, h = 100;
  const auto dir = tmpdir();
  write(dir / "rt.pgm", rasterise(p, res, ox, oy, w, h));
  write(dir / "rt.yaml", "image: rt.pgm\nresolution: 0.05\norigin: [-0.5, -0.5, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.25\n");
  VectoriseStats st;
  const FloorPlan v = load_occupancy_plan((dir / "rt.yaml").string(), &st);
  EXPECT_GT(st.boundary_cells, 0u);
  EXPECT_LE(st.max_error_m, 0.5 * res + 1e-9);
  EXPECT_LT(st.segments, st.boundary_cells / 4);  // it is a simplification
  EXPECT_LE(max_dist(p, v, res / 2), res);
  EXPECT_LE(max_dist(v, p, res / 2), res);
  // The extension dispatch gives the same plan.
  const FloorPlan d = load_floor_plan((dir / "rt.yaml").string());
  EXPECT_EQ(d.elements.size(), v.elements.size());
  // Errors name the file and the field.
  write(dir / "bad.yaml", "image: missing.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n");
  EXPECT_NE(err_of([&] { load_floor_plan((dir / "bad.yaml").string()); }).find("bad.yaml: image: file"), std::string::npos);
  write(dir / "trunc.pgm", "P5\n10 10\n255\n");
  write(dir / "trunc.yaml", "image: trunc.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n");
  EXPECT_NE(err_of([&] { load_floor_plan((dir / "trunc.yaml").string()); }).find("trunc.pgm: byte 13: pixels: truncated"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(Occupancy, ShipInteriorMap) {
  const std::string path = std::string(FPLOC_SHARED_DIR) + "/data/recordings/ship-interior/ship_interior_corner_10mm.yaml";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data absent: " << path;
  const OccupancyGrid g = read_occupancy_map(path);
  EXPECT_EQ(g.width, 180);
  EXPECT_EQ(g.height, 515);
  VectoriseStats st;
  const FloorPlan v = vectorise_occupancy(g, {}, &st);
  EXPECT_GT(st.occupied_cells, 100u);
  EXPECT_GT(v.elements.size(), 2u);
  EXPECT_LE(st.max_error_m, 0.5 * g.resolution + 1e-9);
}

// Random edits of a valid YAML and PGM: a value or one clear error naming the source, never a crash
// (a short in-test fuzz; libyaml does the YAML syntax).
TEST(Occupancy, MutatedInputsNeverCrash) {
  std::mt19937 rng(11);
  const std::string yaml = "image: m.pgm\nresolution: 0.05\norigin: [-1.5, 2.0, 0.3]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.2\nmode: trinary\n";
  std::string pgm = "P5\n# c\n4 3\n255\n";
  for (int k = 0; k < 12; ++k) pgm += char(k * 20);
  const std::string alphabet = "0123456789 .-+:[],#\n\tPabc\xff";
  int ok = 0, err = 0;
  for (int it = 0; it < 20000; ++it) {
    std::string s = it % 2 ? yaml : pgm;
    for (int e = 1 + int(rng() % 4); e > 0; --e) {
      const size_t p = rng() % (s.size() + 1);
      switch (rng() % 3) {
        case 0: s.insert(p, 1, alphabet[rng() % alphabet.size()]); break;
        case 1: if (p < s.size()) s.erase(p, 1); break;
        default: if (p < s.size()) s[p] = alphabet[rng() % alphabet.size()]; break;
      }
    }
    try {
      if (it % 2) parse_map_yaml(s, "f.yaml");
      else read_pgm(s, "f.pgm");
      ++ok;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(it % 2 ? "f.yaml" : "f.pgm"), std::string::npos) << e.what();
      ++err;
    }
  }
  EXPECT_GT(ok, 0);
  EXPECT_GT(err, 0);
}

// The free space of a grid: a wall column, free cells on one side, unknown on the other. A point is free only in a
// known free cell farther than the clearance from the wall's cell centres; unknown cells, occupied cells and points
// off the map are not (the map has no opinion there); a rotated origin is honoured.
TEST(FreeSpace, KnownFreeBeyondTheClearanceOnly) {
  OccupancyGrid g;
  g.width = 40;
  g.height = 20;
  g.resolution = 0.05;
  g.origin_x = 1.0;
  g.origin_y = 2.0;
  g.data.assign(size_t(g.width) * g.height, 0);
  for (int j = 0; j < g.height; ++j) {
    g.data[size_t(j) * g.width + 20] = 100;                                    // wall: x = 1.0 + 20.5 * 0.05 = 2.025
    for (int i = 21; i < g.width; ++i) g.data[size_t(j) * g.width + i] = -1;  // unknown beyond it
  }
  const FreeSpace fs(g);
  EXPECT_EQ(fs.free_cells(), 20u * 20u);
  const double y = 2.5, wall_x = 2.025;
  EXPECT_TRUE(fs.free({wall_x - 0.5, y}, 0.1));
  EXPECT_TRUE(fs.free({wall_x - 0.2, y}, 0.1));
  EXPECT_FALSE(fs.free({wall_x - 0.2, y}, 0.3)) << "within the clearance";
  EXPECT_FALSE(fs.free({wall_x - 0.05, y}, 0.1)) << "next to the wall";
  EXPECT_FALSE(fs.free({wall_x, y}, 0.1)) << "on the wall";
  EXPECT_FALSE(fs.free({wall_x + 0.5, y}, 0.1)) << "unknown";
  EXPECT_FALSE(fs.known({wall_x + 0.5, y})) << "unknown";
  EXPECT_TRUE(fs.known({wall_x, y})) << "occupied: known";
  EXPECT_TRUE(fs.known({wall_x - 0.5, y})) << "free: known";
  EXPECT_FALSE(fs.known({0.5, y})) << "off the map";
  EXPECT_FALSE(fs.free({0.5, y}, 0.1)) << "off the map";
  EXPECT_FALSE(fs.free({wall_x - 0.5, 5.0}, 0.1)) << "off the map";
  EXPECT_FALSE(FreeSpace().free({0, 0}, 0.1)) << "no map";
  EXPECT_FALSE(fs.free({std::nan(""), y}, 0.1)) << "not a point";
  EXPECT_FALSE(fs.free({1e30, y}, 0.1)) << "far off the map";
  // The same map rotated by 90 degrees about its origin: map x runs along world y, map y along world -x.
  g.origin_yaw = M_PI / 2;
  const FreeSpace rot(g);
  EXPECT_TRUE(rot.free({1.0 - 0.5, 2.0 + (wall_x - 1.0) - 0.5}, 0.1));
  EXPECT_FALSE(rot.free({1.0 - 0.5, 2.0 + (wall_x - 1.0) + 0.5}, 0.1)) << "unknown side";
}
