// `fploc launch --check` checks the files named in options: plans/maps, metadata, pcaps, graphs.
#include "check_files.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;
using namespace fploc::rt;

namespace {
struct Dir {
  fs::path p = fs::temp_directory_path() / ("fploc-check-" + std::to_string(::getpid()));
  Dir() { fs::create_directories(p); }
  ~Dir() { fs::remove_all(p); }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(p / name) << text;
    return (p / name).string();
  }
};

std::vector<GraphError> check(const Dir& d, const std::string& text) {
  LoadedGraph g;
  std::vector<GraphError> errors;
  EXPECT_TRUE(load_graph(d.write("g.pbtxt", text), g, errors)) << (errors.empty() ? "" : errors[0].str());
  fploc::launch::check_option_files(g, errors);
  return errors;
}
}  // namespace

TEST(CheckFiles, MissingPlanNamesNodeFieldLineAndPath) {
  Dir d;
  auto e = check(d, "name: \"t\"\nnode {\n  name: \"m\" executable: \"fploc-matcher\"\n"
                    "  matcher { plan { file: \"no-such-plan.json\" } }\n}\n");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].line, 4);
  EXPECT_NE(e[0].message.find("node 'm'"), std::string::npos) << e[0].str();
  EXPECT_NE(e[0].message.find("matcher.plan.file"), std::string::npos) << e[0].str();
  EXPECT_NE(e[0].message.find((d.p / "no-such-plan.json").string()), std::string::npos) << e[0].str();
  EXPECT_NE(e[0].message.find("does not exist"), std::string::npos) << e[0].str();
}

TEST(CheckFiles, UnparsablePlanAndMetadata) {
  Dir d;
  d.write("bad.json", "{ this is not json");
  d.write("meta.json", "{\"lidar_mode\": \"1024x10\"}");
  auto e = check(d, "node { name: \"m\" executable: \"x\" optimizer { plan { file: \"bad.json\" } } }\n"
                    "node { name: \"o\" executable: \"y\" os1_driver { metadata: \"meta.json\" pcap: \"meta.json\" } }\n");
  ASSERT_EQ(e.size(), 3u);
  EXPECT_NE(e[0].message.find("does not load"), std::string::npos) << e[0].str();
  EXPECT_NE(e[1].message.find("os1_driver.metadata"), std::string::npos) << e[1].str();
  EXPECT_NE(e[1].message.find("does not parse"), std::string::npos) << e[1].str();
  EXPECT_NE(e[2].message.find("not a pcap"), std::string::npos) << e[2].str();
}

TEST(CheckFiles, RealPlanAndRuntimeWrittenMetadataPass) {
  Dir d;
  const std::string plan = std::string(FPLOC_SOURCE_DIR) + "/data/plans/room.json";
  auto e = check(d, "node { name: \"s\" executable: \"x\" sim { plan { file: \"" + plan +
                        "\" } metadata_out: \"written-later.json\" } }\n"
                        "node { name: \"o\" executable: \"y\" os1_driver { metadata: \"written-later.json\" } }\n"
                        "node { name: \"off\" executable: \"z\" disabled: true matcher { plan { file: \"gone.json\" } } }\n");
  EXPECT_TRUE(e.empty()) << e[0].str();
}
