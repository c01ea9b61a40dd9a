#include <gtest/gtest.h>

#include "fploc/runtime/validate.h"

using namespace fploc::rt;

namespace {
// Fake executables: fploc-src publishes pose_t on P, fploc-log consumes pose_t (options pose_logger),
// fploc-seg consumes scan_t on OS1_SCAN (options segmenter); anything else is missing.
ValidateHooks fake() {
  ValidateHooks h;
  h.resolve = [](const std::string& e) {
    return (e == "fploc-src" || e == "fploc-log" || e == "fploc-seg" || e == "lcm-logplayer") ? "/bin/" + e : "";
  };
  h.describe = [](const std::string& p) {
    DescribeResult r;
    if (p == "/bin/lcm-logplayer") return r;
    r.describable = true;
    if (p == "/bin/fploc-src") r.spec = {"src", "", "", {{"out", "fploc.pose_t", "P", true}}};
    if (p == "/bin/fploc-log") r.spec = {"log", "pose_logger", "", {{"pose", "fploc.pose_t", "FPLOC_POSE", false}}};
    if (p == "/bin/fploc-seg") r.spec = {"seg", "segmenter", "", {{"scan", "fploc.scan_t", "OS1_SCAN", false}}};
    return r;
  };
  return h;
}
std::vector<GraphError> check(const std::string& text) {
  LoadedGraph g;
  std::vector<GraphError> errors;
  if (parse_graph_text(text, "g.pbtxt", g, errors)) validate_graph(g, fake(), errors);
  return errors;
}
std::string all(const std::vector<GraphError>& e) {
  std::string s;
  for (const auto& x : e) s += x.str() + "\n";
  return s;
}
}  // namespace

TEST(Validate, GoodGraphPasses) {
  const auto e = check(R"(node { name: "s" executable: "fploc-src" }
node { name: "l" executable: "fploc-log" input { port: "pose" channel: "P" } pose_logger { file: "x" } }
)");
  EXPECT_TRUE(e.empty()) << all(e);
}

TEST(Validate, EveryProblemWithItsLine) {
  const auto e = check(R"(node { name: "s" executable: "fploc-src" }
node { name: "l" executable: "fploc-log"
  input { port: "pose" channel: "OS1_SCAN" }
}
node { name: "seg" executable: "fploc-seg" }
node { name: "s" executable: "fploc-src" }
node { name: "l2" executable: "fploc-log"
  segmenter { seed_rings: 2 }
  input { port: "poze" channel: "P" }
}
node { name: "l3" executable: "fploc-log" }
)");
  const std::string s = all(e);
  ASSERT_EQ(e.size(), 7u) << s;  // + l2's unmapped "pose" on its default FPLOC_POSE
  // l's input on OS1_SCAN: no producer (seg also consumes OS1_SCAN: no producer either).
  EXPECT_NE(s.find("g.pbtxt:3: node 'l' input 'pose' on channel 'OS1_SCAN' has no producer"), std::string::npos) << s;
  EXPECT_NE(s.find("g.pbtxt:5: node 'seg' input 'scan' on channel 'OS1_SCAN' has no producer"), std::string::npos) << s;
  EXPECT_NE(s.find("g.pbtxt:6: duplicate node name 's' (first defined at line 1)"), std::string::npos) << s;
  EXPECT_NE(s.find("g.pbtxt:8: node 'l2': options field 'segmenter' does not match"), std::string::npos) << s;
  EXPECT_NE(s.find("g.pbtxt:9: node 'l2': fploc-log has no input port 'poze'"), std::string::npos) << s;
  // l3 is not mapped: its default channel FPLOC_POSE has no producer, reported at the node's line.
  EXPECT_NE(s.find("g.pbtxt:11: node 'l3' input 'pose' on channel 'FPLOC_POSE' has no producer"), std::string::npos) << s;
  // ... and says how to leave an input unconnected (a display-only input, e.g. the dashboard's).
  EXPECT_NE(s.find("FPLOC_POSE' has no producer (no node of the graph publishes it); if it is to stay unconnected: "
                   "input { port: \"pose\" channel: \"\" }"), std::string::npos) << s;
  for (size_t i = 1; i < e.size(); ++i) EXPECT_LE(e[i - 1].line, e[i].line);  // sorted by line
}

// A queue policy is for inputs (which messages a node takes); on an output it is one error at its line.
TEST(Validate, AQueuePolicyOnAnOutputIsAnError) {
  const auto e = check(R"(node { name: "s" executable: "fploc-src"
  output { port: "out" channel: "P" queue: LATEST }
}
node { name: "l" executable: "fploc-log" input { port: "pose" channel: "P" queue: LATEST } pose_logger { file: "x" } }
)");
  const std::string s = all(e);
  ASSERT_EQ(e.size(), 1u) << s;
  EXPECT_NE(s.find("g.pbtxt:2: node 's': output port 'out' has a queue policy (queue applies to inputs only)"),
            std::string::npos) << s;
}

TEST(Validate, TypeMismatchAndExternalProducers) {
  auto e = check(R"(node { name: "s" executable: "fploc-src" output { port: "out" channel: "OS1_SCAN" } }
node { name: "seg" executable: "fploc-seg" }
)");
  ASSERT_EQ(e.size(), 1u) << all(e);
  EXPECT_EQ(e[0].line, 2);
  EXPECT_NE(e[0].message.find("expects fploc.scan_t but node 's' output 'out' publishes fploc.pose_t"),
            std::string::npos)
      << e[0].message;
  // A disabled node (e.g. lcm-logplayer) declares the channels that come from outside the graph.
  e = check(R"(node { name: "log" executable: "lcm-logplayer" disabled: true output { port: "x" channel: "OS1_SCAN" } }
node { name: "seg" executable: "fploc-seg" }
)");
  EXPECT_TRUE(e.empty()) << all(e);
}

TEST(Validate, SpecJsonRoundTrip) {
  NodeSpec s{"pose_logger", "pose_logger", "d \"q\"", {{"pose", "fploc.pose_t", "FPLOC_POSE", false}}};
  const NodeSpec r = parse_spec_json(spec_json(s));
  EXPECT_EQ(r.type, s.type);
  EXPECT_EQ(r.options_field, "pose_logger");
  EXPECT_EQ(r.description, s.description);
  ASSERT_EQ(r.ports.size(), 1u);
  EXPECT_EQ(r.ports[0].lcm_type, "fploc.pose_t");
  EXPECT_FALSE(r.ports[0].output);
  EXPECT_THROW(parse_spec_json("not json"), std::runtime_error);
  EXPECT_THROW(parse_spec_json("{\"type\":\"x\"}"), std::runtime_error);
}

TEST(Validate, ResolvesFromBinDirThenPath) {
  EXPECT_EQ(resolve_executable("sh", "/nonexistent"), resolve_executable("sh", ""));
  EXPECT_FALSE(resolve_executable("sh", "").empty());
  EXPECT_EQ(resolve_executable("fploc-definitely-missing", "/usr/bin"), "");
  EXPECT_EQ(resolve_executable("sh", "/bin"), "/bin/sh");
}

TEST(Validate, EmptyChannelMeansNotConnected) {
  const auto e = check(R"(node { name: "l" executable: "fploc-log" input { port: "pose" channel: "" } }
)");
  EXPECT_TRUE(e.empty()) << all(e);
}

TEST(Validate, MissingExecutableDoesNotCascadeIntoNoProducer) {
  const auto e = check(R"(node { name: "s" executable: "fploc-missing" }
node { name: "l" executable: "fploc-log" }
)");
  ASSERT_EQ(e.size(), 1u) << all(e);
  EXPECT_NE(e[0].str().find("g.pbtxt:1: node 's': executable 'fploc-missing' not found"), std::string::npos) << all(e);
}
