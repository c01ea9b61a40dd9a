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

// A file a node writes in a folder that does not exist: the node fails at set-up, so --check says it.
TEST(CheckFiles, OutputFolderMustExist) {
  Dir d;
  auto e = check(d, "node { name: \"log\" executable: \"x\" pose_logger { file: \"/nonexistent-fploc/dir/p.tum\""
                    " uncertainty_file: \"" + (d.p / "p.unc").string() + "\" } }\n"
                    "node { name: \"s\" executable: \"y\" sim { metadata_out: \"no-dir/m.json\" } }\n"
                    "node { name: \"d\" executable: \"z\" plan_diff { out_json: \"/nonexistent-fploc/d.json\" } }\n");
  ASSERT_EQ(e.size(), 3u) << (e.empty() ? "" : e[0].str());
  EXPECT_NE(e[2].message.find("plan_diff.out_json"), std::string::npos) << e[2].str();
  EXPECT_NE(e[0].message.find("node 'log': pose_logger.file '/nonexistent-fploc/dir/p.tum' cannot be written: its "
                              "folder '/nonexistent-fploc/dir' does not exist"), std::string::npos) << e[0].str();
  EXPECT_NE(e[1].message.find("sim.metadata_out"), std::string::npos) << e[1].str();
  EXPECT_NE(e[1].message.find((d.p / "no-dir").string()), std::string::npos) << e[1].str();
}

// A node on another host writes into that host's folders: not checked here.
TEST(CheckFiles, ARemoteNodesOutputFoldersAreNotCheckedHere) {
  Dir d;
  auto e = check(d, "host { name: \"robot\" address: \"10.0.0.2\" }\n"
                    "node { name: \"log\" executable: \"x\" host: \"robot\" pose_logger { file: \"/data-on-robot/p.tum\" } }\n"
                    "node { name: \"here\" executable: \"y\" pose_logger { file: \"/nonexistent-fploc/p.tum\" } }\n");
  ASSERT_EQ(e.size(), 1u) << (e.empty() ? "" : e[0].str());
  EXPECT_NE(e[0].message.find("node 'here'"), std::string::npos) << e[0].str();
}

// Names the node checks at start (matcher::lookup_names, the map builder's own list) and a plan it needs.
TEST(CheckFiles, UnknownLookupAndMissingPlanAreOptionErrors) {
  Dir d;
  LoadedGraph g;
  std::vector<GraphError> errors;
  ASSERT_TRUE(load_graph(d.write("g.pbtxt", "node { name: \"m\" executable: \"x\"\n"
                                              "  matcher { plan { file: \"p.json\" }\n    lookup: \"anf-exact\" } }\n"
                                              "node { name: \"o\" executable: \"y\" optimizer { lookup: \"kdtree\" } }\n"
                                              "node { name: \"r\" executable: \"z\" relocalizer { plan { file: \"p.json\" } lookup: \"brute-force\" } }\n"),
                         g, errors));
  fploc::launch::check_option_values(g, errors);
  ASSERT_EQ(errors.size(), 2u) << (errors.empty() ? "" : errors[0].str());
  EXPECT_EQ(errors[0].line, 3);
  EXPECT_NE(errors[0].message.find("node 'm': matcher.lookup: unknown look-up 'anf-exact' (use \"annf-exact\", "),
            std::string::npos) << errors[0].str();
  EXPECT_NE(errors[0].message.find("\"kdtree\""), std::string::npos) << errors[0].str();
  EXPECT_NE(errors[1].message.find("node 'o': optimizer.plan.file: no floor plan given"), std::string::npos)
      << errors[1].str();
}
