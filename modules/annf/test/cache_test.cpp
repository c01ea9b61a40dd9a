// The on-disk ANNF cache: a hit gives the same field, a changed plan file or option is a miss, a
// damaged entry is rebuilt, and two processes starting at once build the field once.
#include "fploc/annf/cache.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <vector>

#include "fploc/floorplan/io.h"

using namespace fploc;
using namespace fploc::annf;
namespace fs = std::filesystem;

namespace {

// The test's folders, removed when the test program ends (the forked children leave with _exit, so only the parent
// removes them).
struct Folders {
  std::vector<std::string> made;
  ~Folders() {
    std::error_code ec;
    for (const auto& d : made) fs::remove_all(d, ec);
  }
} folders;

std::string fresh_dir(const std::string& name) {
  const std::string d = testing::TempDir() + "/annf_cache_" + name + "_" + std::to_string(::getpid());
  fs::remove_all(d);
  fs::create_directories(d);
  folders.made.push_back(d);
  return d;
}

// A random "building" of n segments in a 60 x 40 m box (written as CSV so the plan comes from a file).
std::string write_plan(const std::string& path, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(0, 60), y(0, 40), d(-3, 3);
  std::ofstream f(path);
  f.precision(17);
  for (int i = 0; i < n; ++i) {
    const double ax = x(rng), ay = y(rng);
    f << ax << "," << ay << "," << ax + d(rng) << "," << ay + d(rng) << (i % 3 ? ",walls" : ",columns") << "\n";
  }
  return path;
}

size_t count_files(const std::string& dir, const std::string& ext) {
  size_t n = 0;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ext) ++n;
  return n;
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

}  // namespace

TEST(AnnfCache, HitGivesTheSameField) {
  const std::string dir = fresh_dir("hit");
  const FloorPlan plan = load_floor_plan(write_plan(dir + "/p.csv", 300, 1));
  AnnfOptions o;
  o.mode = AnnfMode::kExact;
  std::string note;
  const auto built = cached_annf(plan, o, &note, dir + "/cache");
  EXPECT_TRUE(contains(note, "cached as")) << note;
  EXPECT_EQ(count_files(dir + "/cache", ".fpmap"), 1u);
  const auto hit = cached_annf(plan, o, &note, dir + "/cache");
  EXPECT_TRUE(contains(note, "ANNF cache hit")) << note;
  ASSERT_NE(built.get(), hit.get());
  EXPECT_EQ(hit->stats().leaves, built->stats().leaves);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> x(-3, 63), y(-3, 43);
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector2d p(x(rng), y(rng));
    double d1, d2;
    ASSERT_EQ(built->nearest(p, &d1), hit->nearest(p, &d2));
    ASSERT_EQ(d1, d2);
  }
  // Paper mode is another entry.
  o.mode = AnnfMode::kPaper;
  cached_annf(plan, o, &note, dir + "/cache");
  EXPECT_TRUE(contains(note, "cached as")) << note;
  EXPECT_EQ(count_files(dir + "/cache", ".fpmap"), 2u);
}

TEST(AnnfCache, ChangedFileOrOptionsMiss) {
  const std::string dir = fresh_dir("miss");
  const std::string csv = write_plan(dir + "/p.csv", 200, 2);
  AnnfOptions o;
  o.mode = AnnfMode::kExact;
  std::string note;
  cached_annf(load_floor_plan(csv), o, &note, dir + "/cache");
  EXPECT_TRUE(contains(note, "cached as")) << note;
  // The same content: a hit, also when read through another path.
  fs::copy_file(csv, dir + "/copy.csv");
  cached_annf(load_floor_plan(dir + "/copy.csv"), o, &note, dir + "/cache");
  EXPECT_TRUE(contains(note, "cache hit")) << note;
  // One coordinate of the file changed by 1 mm: a miss.
  std::string text;
  {
    std::ifstream f(csv);
    std::stringstream ss;
    ss << f.rdbuf();
    text = ss.str();
  }
  const size_t comma = text.find(',');
  std::ofstream(csv) << "0.001" << text.substr(comma);
  const FloorPlan changed = load_floor_plan(csv);
  cached_annf(changed, o, &note, dir + "/cache");
  EXPECT_TRUE(contains(note, "cached as")) << note;
  // A layer renamed: a miss. An option changed: a miss. Back to the first options: a hit.
  FloorPlan renamed = changed;
  renamed.layers[0] = "other";
  cached_annf(renamed, o, &note, dir + "/cache");
  EXPECT_TRUE(contains(note, "cached as")) << note;
  o.max_depth = 6;
  cached_annf(changed, o, &note, dir + "/cache");
  EXPECT_TRUE(contains(note, "cached as")) << note;
  o.max_depth = 7;
  cached_annf(changed, o, &note, dir + "/cache");
  EXPECT_TRUE(contains(note, "cache hit")) << note;
  EXPECT_NE(annf_cache_key(changed, o), annf_cache_key(renamed, o));
  // A damaged entry is rebuilt and replaced.
  const std::string entry = dir + "/cache/" + annf_cache_key(changed, o) + ".fpmap";
  fs::resize_file(entry, fs::file_size(entry) / 2);
  cached_annf(changed, o, &note, dir + "/cache");
  EXPECT_TRUE(contains(note, "cached as")) << note;
  cached_annf(changed, o, &note, dir + "/cache");
  EXPECT_TRUE(contains(note, "cache hit")) << note;
  // An unusable folder: built in memory, with the reason.
  std::ofstream(dir + "/file") << "x";
  const auto a = cached_annf(changed, o, &note, dir + "/file/sub");
  EXPECT_TRUE(a != nullptr);
  EXPECT_TRUE(contains(note, "not cached")) << note;
}

TEST(AnnfCache, TwoProcessesAtOnceBuildOnce) {
  const std::string dir = fresh_dir("race");
  const FloorPlan plan = load_floor_plan(write_plan(dir + "/p.csv", 1500, 3));
  AnnfOptions o;
  o.mode = AnnfMode::kExact;
  o.max_depth = 8;
  int go[2];
  ASSERT_EQ(::pipe(go), 0);
  pid_t kids[2];
  for (int k = 0; k < 2; ++k) {
    kids[k] = ::fork();
    ASSERT_GE(kids[k], 0);
    if (kids[k] == 0) {
      ::close(go[1]);
      char c;
      if (::read(go[0], &c, 1) != 1) ::_exit(3);  // start together
      std::string note;
      int rc = 0;
      try {
        const auto a = cached_annf(plan, o, &note, dir + "/cache");
        rc = a->stats().leaves > 0 ? 0 : 4;
      } catch (...) {
        rc = 5;
      }
      std::ofstream(dir + "/note" + std::to_string(k)) << note;
      ::_exit(rc);
    }
  }
  ::close(go[0]);
  ASSERT_EQ(::write(go[1], "xx", 2), 2);
  ::close(go[1]);
  for (pid_t p : kids) {
    int st = 0;
    ASSERT_EQ(::waitpid(p, &st, 0), p);
    EXPECT_TRUE(WIFEXITED(st) && WEXITSTATUS(st) == 0) << st;
  }
  int built = 0, hits = 0;
  for (int k = 0; k < 2; ++k) {
    std::ifstream f(dir + "/note" + std::to_string(k));
    std::string note((std::istreambuf_iterator<char>(f)), {});
    built += contains(note, "cached as");
    hits += contains(note, "cache hit");
    std::cerr << "process " << k << ": " << note << "\n";
  }
  EXPECT_EQ(built, 1);
  EXPECT_EQ(hits, 1);
  EXPECT_EQ(count_files(dir + "/cache", ".fpmap"), 1u);
  for (const auto& e : fs::directory_iterator(dir + "/cache"))
    EXPECT_FALSE(contains(e.path().filename().string(), ".tmp.")) << e.path();  // no leftovers
  std::string note;
  cached_annf(plan, o, &note, dir + "/cache");
  EXPECT_TRUE(contains(note, "cache hit")) << note;
}
