#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "fploc/runtime/graph.h"
#include "fploc/runtime/bus.h"
#include "fploc/runtime/node.h"
#include "fploc/runtime/cli_messages.h"

using namespace fploc::rt;

TEST(Graph, ParsesNodesWithLines) {
  const std::string text = R"pb(name: "t"
lcm_url: "memq://"
node {
  name: "seg"
  executable: "fploc-segmenter"
  input { port: "scan" channel: "OS1_SCAN" }
  segmenter { seed_rings: 3 }
}
node {
  name: "log"
  executable: "fploc-pose-logger"
  pose_logger { file: "out.tum" }
}
)pb";
  LoadedGraph g;
  std::vector<GraphError> errors;
  ASSERT_TRUE(parse_graph_text(text, "t.pbtxt", g, errors)) << (errors.empty() ? "" : errors[0].str());
  ASSERT_EQ(g.graph.node_size(), 2);
  EXPECT_EQ(g.node_line(0), 3);
  EXPECT_EQ(g.node_line(1), 9);
  EXPECT_EQ(g.node_line(0, "executable"), 5);
  EXPECT_EQ(g.node_line(0, "input", 0), 6);
  EXPECT_EQ(node_options_field(g.graph.node(0)), "segmenter");
  auto o = node_options(g.graph.node(0));
  ASSERT_TRUE(o);
  EXPECT_NE(o->DebugString().find("seed_rings: 3"), std::string::npos);
}

TEST(Graph, EveryUnknownFieldIsReportedWithItsLine) {
  const std::string text = R"pb(name: "t"
node {
  name: "seg"
  executable: "fploc-segmenter"
  segmenter { seed_ringz: 3 }
}
node {
  name: "log"
  exekutable: "x"
}
)pb";
  LoadedGraph g;
  std::vector<GraphError> errors;
  EXPECT_FALSE(parse_graph_text(text, "t.pbtxt", g, errors));
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_EQ(errors[0].line, 5);
  EXPECT_NE(errors[0].message.find("seed_ringz"), std::string::npos);
  EXPECT_EQ(errors[1].line, 9);
  EXPECT_EQ(errors[0].str().rfind("t.pbtxt:5: ", 0), 0u);
}

// A misspelt field is the only error: the rest of the graph is still read as a launch would read it (its
// ${NAME:-default} values expanded), so `fploc launch --check` does not add false errors about "${...}" folders.
TEST(Graph, AMisspeltFieldLeavesTheRestExpanded) {
  ::unsetenv("FPLOC_GRAPH_TEST_DIR");
  const std::string text =
      "node {\n  name: \"opt\"\n  optimizer { window: 10 windw: 3 }\n}\n"
      "node {\n  name: \"log\"\n  pose_logger { file: \"${FPLOC_GRAPH_TEST_DIR:-/tmp}/p.tum\" }\n}\n";
  LoadedGraph g;
  std::vector<GraphError> errors;
  EXPECT_FALSE(parse_graph_text(text, "t.pbtxt", g, errors));
  ASSERT_EQ(errors.size(), 1u) << errors.back().str();
  EXPECT_NE(errors[0].message.find("windw"), std::string::npos) << errors[0].str();
  EXPECT_EQ(g.graph.node(1).pose_logger().file(), "/tmp/p.tum");
}

TEST(Graph, WrongValueTypeIsAnError) {
  LoadedGraph g;
  std::vector<GraphError> errors;
  EXPECT_FALSE(parse_graph_text("node {\n name: \"a\"\n segmenter { seed_rings: \"many\" }\n}\n", "x.pbtxt", g, errors));
  ASSERT_FALSE(errors.empty());
  EXPECT_EQ(errors[0].line, 3);
}

TEST(Overrides, SetsNestedAndRejectsUnknown) {
  auto o = default_options("matcher");
  ASSERT_TRUE(o);
  std::string err;
  EXPECT_TRUE(apply_overrides(*o, {"lookup=kdtree", "initial_pose.x=1.5", "max_iterations=7"}, err)) << err;
  const auto s = o->ShortDebugString();
  EXPECT_NE(s.find("lookup: \"kdtree\""), std::string::npos) << s;
  EXPECT_NE(s.find("x: 1.5"), std::string::npos) << s;
  EXPECT_FALSE(apply_overrides(*o, {"lokup=kdtree"}, err));
  EXPECT_NE(err.find("lokup"), std::string::npos);
  EXPECT_FALSE(apply_overrides(*o, {"max_iterations=lots"}, err));
}

// NaN and infinity parse as numbers in text format; in an option they are a typo or a broken generator, never a
// setting (a NaN initial pose started the matcher nowhere). One error each, naming the node, the option and its line.
TEST(Graph, NonFiniteOptionIsAnErrorWithItsLine) {
  const std::string text = R"pb(name: "t"
shutdown_timeout_s: 2
node {
  name: "m"
  executable: "fploc-matcher"
  matcher { plan { file: "p.json" }
            initial_pose { x: nan y: 1 yaw: 0 } }
}
node {
  name: "o"
  executable: "fploc-optimizer"
  optimizer { alpha: -inf beta: 0.9 }
}
)pb";
  LoadedGraph g;
  std::vector<GraphError> errors;
  EXPECT_FALSE(parse_graph_text(text, "t.pbtxt", g, errors));
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_EQ(errors[0].str(), "t.pbtxt:7: node 'm': matcher.initial_pose.x is nan (not a finite number)");
  EXPECT_EQ(errors[1].str(), "t.pbtxt:12: node 'o': optimizer.alpha is -inf (not a finite number)");
}

TEST(Overrides, NonFiniteValueIsRejected) {
  auto o = default_options("matcher");
  ASSERT_TRUE(o);
  std::string err;
  EXPECT_FALSE(apply_overrides(*o, {"initial_pose.x=nan"}, err));
  EXPECT_EQ(err, "override 'initial_pose.x=nan': initial_pose.x is nan (not a finite number)");
  EXPECT_FALSE(apply_overrides(*o, {"max_correspondence_m=inf"}, err));
  EXPECT_NE(err.find("max_correspondence_m is inf"), std::string::npos) << err;
  EXPECT_TRUE(apply_overrides(*o, {"initial_pose.x=1e300"}, err)) << err;
}

// ${NAME:-default} in a string option is the environment's value (graphs/demo.pbtxt: ${FPLOC_DEMO_DIR:-/tmp}, so
// two users' demos do not write the same files); an unset NAME without a default is one error with its line.
TEST(Graph, EnvironmentInStringOptions) {
  const std::string text = R"pb(name: "t"
node {
  name: "log"
  executable: "fploc-pose-logger"
  pose_logger { file: "${FPLOC_GRAPH_TEST_DIR:-/tmp}/poses.tum" }
}
)pb";
  ::unsetenv("FPLOC_GRAPH_TEST_DIR");
  LoadedGraph g;
  std::vector<GraphError> errors;
  ASSERT_TRUE(parse_graph_text(text, "t.pbtxt", g, errors)) << (errors.empty() ? "" : errors[0].str());
  EXPECT_EQ(g.graph.node(0).pose_logger().file(), "/tmp/poses.tum");
  ::setenv("FPLOC_GRAPH_TEST_DIR", "/home/u/run1", 1);
  LoadedGraph g2;
  ASSERT_TRUE(parse_graph_text(text, "t.pbtxt", g2, errors));
  EXPECT_EQ(g2.graph.node(0).pose_logger().file(), "/home/u/run1/poses.tum");
  ::unsetenv("FPLOC_GRAPH_TEST_DIR");
  LoadedGraph g3;
  EXPECT_FALSE(parse_graph_text("node {\n  name: \"log\"\n  pose_logger { file: \"${FPLOC_GRAPH_TEST_DIR}/p.tum\" }\n}\n",
                                "u.pbtxt", g3, errors));
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_EQ(errors[0].str(), "u.pbtxt:3: node 'log': pose_logger.file: environment variable FPLOC_GRAPH_TEST_DIR is not set "
                             "(write ${FPLOC_GRAPH_TEST_DIR:-DEFAULT} for a default)");
}

// The shipped demo graphs write their files under ${FPLOC_DEMO_DIR:-/tmp}: none hard-codes /tmp (graphs/
// demo-building.pbtxt did, so two users' building demos wrote the same files).
TEST(Graph, DemoGraphsWriteUnderFplocDemoDir) {
  ::setenv("FPLOC_DEMO_DIR", "/home/u/demo", 1);
  for (const char* name : {"demo.pbtxt", "demo-building.pbtxt", "multihost.pbtxt"}) {  // multihost: hard-coded /tmp too
    LoadedGraph g;
    std::vector<GraphError> errors;
    ASSERT_TRUE(load_graph(std::string(FPLOC_SOURCE_DIR) + "/graphs/" + name, g, errors))
        << name << ": " << (errors.empty() ? "" : errors[0].str());
    int files = 0;
    for (const auto& n : g.graph.node()) {
      const std::string text = n.DebugString();
      EXPECT_EQ(text.find("\"/tmp/"), std::string::npos) << name << ": node '" << n.name() << "' writes to /tmp:\n" << text;
      for (size_t at = text.find("\"/home/u/demo/"); at != std::string::npos; at = text.find("\"/home/u/demo/", at + 1)) ++files;
    }
    EXPECT_GE(files, 4) << name << ": metadata, poses and ground truth under $FPLOC_DEMO_DIR";
  }
  ::unsetenv("FPLOC_DEMO_DIR");
}

// A Pose2D yaw beyond +-2 pi in a node's options (degrees given where radians are read: `fploc node initial-pose`
// takes degrees, the options radians) is said once when the node's context is made, naming the option.
TEST(Context, WarnsOnceOfAYawInDegrees) {
  Bus bus("memq://");
  NodeSpec spec{"matcher", "matcher", "", {}};
  auto o = default_options("matcher");
  ASSERT_TRUE(o);
  std::string err;
  ASSERT_TRUE(apply_overrides(*o, {"initial_pose.yaw=90"}, err)) << err;
  testing::internal::CaptureStderr();
  { Context ctx(bus, spec, "m1", std::move(o), {}, "/", true); }
  std::string said = testing::internal::GetCapturedStderr();
  EXPECT_NE(said.find("[m1] warning: matcher.initial_pose.yaw 90 is outside [-2 pi, 2 pi]: yaw is in radians"), std::string::npos) << said;
  EXPECT_EQ(said.find("warning", said.find("warning") + 1), std::string::npos) << "said twice: " << said;
  auto ok = default_options("matcher");
  ASSERT_TRUE(apply_overrides(*ok, {"initial_pose.yaw=-1.44"}, err)) << err;
  testing::internal::CaptureStderr();
  { Context ctx(bus, spec, "m2", std::move(ok), {}, "/", true); }
  said = testing::internal::GetCapturedStderr();
  EXPECT_EQ(said.find("warning"), std::string::npos) << said;
}

// A node's status changes (Context::status_changed) are said on stderr for the first 200 only, the 200th saying that
// further ones are only in telemetry; the line is telemetry's detail (cleared for a status that needs no
// explanation); a change already said elsewhere on stderr is neither printed again nor counted.
TEST(Context, StatusChangesArePrintedTwoHundredTimesAndKeptInTheDetail) {
  Bus bus("memq://");
  NodeSpec spec{"grid2d", "", "", {}};
  Context ctx(bus, spec, "g1", nullptr, {}, "/", true);
  testing::internal::CaptureStderr();
  EXPECT_TRUE(ctx.status_changed("scan 0: POOR: too few returns"));
  std::string said = testing::internal::GetCapturedStderr();
  EXPECT_EQ(said, "[g1] scan 0: POOR: too few returns\n");
  EXPECT_EQ(ctx.stats().detail, "scan 0: POOR: too few returns");
  testing::internal::CaptureStderr();
  EXPECT_FALSE(ctx.status_changed("scan 1: LOST: said by error()", true, false));
  said = testing::internal::GetCapturedStderr();
  EXPECT_EQ(said, "");
  EXPECT_EQ(ctx.stats().detail, "scan 1: LOST: said by error()");
  EXPECT_TRUE(ctx.status_changed("scan 2: OK", false));
  EXPECT_EQ(ctx.stats().detail, "") << "an OK status clears the detail";
  testing::internal::CaptureStderr();
  for (int i = 3; i < 400; ++i) ctx.status_changed("scan " + std::to_string(i) + ": " + (i % 2 ? "POOR" : "OK"));
  said = testing::internal::GetCapturedStderr();
  // 2 printed before, so 198 more: scans 3..200, the last one marked.
  EXPECT_EQ(std::count(said.begin(), said.end(), '\n'), Context::kStatusChangesPrinted - 2) << said;
  EXPECT_NE(said.find("[g1] scan 200: OK (further changes: telemetry's detail)\n"), std::string::npos) << said;
  EXPECT_EQ(said.find("scan 201"), std::string::npos);
  EXPECT_EQ(said.find("further changes"), said.rfind("further changes")) << "marked once";
  EXPECT_EQ(ctx.stats().detail, "scan 399: POOR") << "the detail follows every change";
}

// `fploc replay --set matcher.plan.file=my.dxf` run in the folder holding my.dxf: the path is the working directory's,
// as every other path on the command line; it was resolved against the graph's folder (graphs/my.dxf: cannot open).
// Only file options change; names (plan.floor, lookup) and absolute paths stay as given.
TEST(Overrides, CommandLinePathsAreRelativeToTheWorkingDirectory) {
  const std::string text = R"pb(name: "t"
lcm_url: "memq://"
node {
  name: "matcher"
  executable: "fploc-matcher"
  matcher { plan { file: "../data/plans/room.json" } }
}
node {
  name: "log"
  executable: "fploc-pose-logger"
  pose_logger { file: "out.tum" }
}
)pb";
  LoadedGraph g;
  std::vector<GraphError> errors;
  ASSERT_TRUE(parse_graph_text(text, "/somewhere/graphs/t.pbtxt", g, errors));
  std::string err;
  ASSERT_TRUE(apply_node_overrides(g.graph,
                                   {"matcher.plan.file=plans/my.dxf", "matcher.plan.floor=first", "matcher.lookup=kdtree",
                                    "log.file=/abs/est.tum"},
                                   {}, err))
      << err;
  const std::string cwd = std::filesystem::current_path().string();
  EXPECT_EQ(g.graph.node(0).matcher().plan().file(), (std::filesystem::path(cwd) / "plans/my.dxf").string());
  EXPECT_EQ(g.graph.node(0).matcher().plan().floor(), "first");
  EXPECT_EQ(g.graph.node(0).matcher().lookup(), "kdtree");
  EXPECT_EQ(g.graph.node(1).pose_logger().file(), "/abs/est.tum");
  EXPECT_EQ(command_line_path_override("n.metadata=../os1.json", "/w/run"), "n.metadata=/w/os1.json");
  EXPECT_EQ(command_line_path_override("n.plan.units=mm", "/w"), "n.plan.units=mm");
  EXPECT_EQ(command_line_path_override("n.plan.file=", "/w"), "n.plan.file=");
  // An error names the override as given.
  EXPECT_FALSE(apply_node_overrides(g.graph, {"nonode.plan.file=x.dxf"}, {}, err));
  EXPECT_NE(err.find("nonode.plan.file=x.dxf"), std::string::npos) << err;
}

// A typo'd option of a CLI11 main (fploc map render --layer Walls): CLI11 said "The following arguments were not
// expected: Walls --layer" without naming the command. Now one line naming the command and the option.
TEST(CliMessages, ATypoedOptionIsNamedWithItsCommand) {
  const auto error_of = [](std::vector<std::string> args) {
    CLI::App app{"t"};
    std::string plan, layers;
    auto* render = app.add_subcommand("render", "r");
    render->add_option("--plan", plan)->required();
    render->add_option("--layers", layers);
    std::reverse(args.begin(), args.end());
    try {
      app.parse(args);
    } catch (const CLI::ParseError& e) {
      return cli_error_text(app, e, "fploc map");
    }
    return std::string("parsed");
  };
  EXPECT_EQ(error_of({"render", "--plan", "p.dxf", "--layer", "Walls"}),
            "fploc map: unknown option '--layer' (fploc map --help lists the options)");
  EXPECT_EQ(error_of({"render", "--plan", "p.dxf", "extra1", "extra2"}),
            "fploc map: unexpected argument 'extra1' (fploc map --help lists the options)");
  EXPECT_EQ(error_of({"render", "--plan"}).rfind("fploc map: --plan: 1 required TEXT missing", 0), 0u);
}
