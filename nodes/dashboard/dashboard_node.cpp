// fploc-dashboard: HTTP + Server-Sent Events view of a running graph (see docs/notes/dashboard.md).
// LCM handlers run on the node thread and only update latest-value slots in the Model's push hub; the
// HTTP server (http_server.h: one event-loop thread, Boost.Beast) answers requests and runs ONE broadcaster
// that sends each due update to every open event stream (capped; beyond the cap: 503).
#include <fploc/features_t.hpp>
#include <fploc/plan_diff_t.hpp>
#include <fploc/frame_pose_t.hpp>
#include <fploc/ground_truth_t.hpp>
#include <fploc/node_command_t.hpp>
#include <fploc/node_status_t.hpp>
#include <fploc/pose_t.hpp>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>
#include <mutex>

#include "fploc/core/text_out.h"
#include "fploc/runtime/bus.h"
#include "fploc/runtime/graph.h"
#include "fploc/runtime/node.h"
#include "fploc/runtime/robot.h"
#include "model.h"
#include "plan_diff_json.h"
#include "options/tools.pb.h"
#include "floors_json.h"
#include "plan_json.h"
#include "web_path.h"
#include "http_server.h"

#ifndef FPLOC_WEB_ROOT
#define FPLOC_WEB_ROOT ""
#endif

namespace fploc::dashboard {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {
double steady_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

const char* mime_type(const std::string& ext) {
  if (ext == ".html") return "text/html; charset=utf-8";
  if (ext == ".js" || ext == ".mjs") return "text/javascript; charset=utf-8";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".json") return "application/json";
  if (ext == ".svg") return "image/svg+xml";
  if (ext == ".png") return "image/png";
  if (ext == ".ico") return "image/x-icon";
  if (ext == ".txt" || ext == ".md") return "text/plain; charset=utf-8";
  return "application/octet-stream";
}

bool constant_time_equal(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char d = 0;
  for (size_t i = 0; i < a.size(); ++i) d |= (unsigned char)(a[i] ^ b[i]);
  return d == 0;
}
}  // namespace

class DashboardNode : public fploc::rt::Node {
 public:
  static fploc::rt::NodeSpec spec() {
    return {"dashboard", "dashboard", "web dashboard: floor plan, poses, features and node health over HTTP/SSE",
            {fploc::rt::input<fploc::pose_t>("pose", "FPLOC_POSE"),
             fploc::rt::input<fploc::frame_pose_t>("frame_pose", "FPLOC_FRAME_POSE"),
             fploc::rt::input<fploc::features_t>("features", "FPLOC_FEATURES"),
             fploc::rt::input<fploc::ground_truth_t>("ground_truth", "FPLOC_GROUND_TRUTH"),
             fploc::rt::input<fploc::node_status_t>("telemetry", fploc::rt::kTelemetryChannel),
             // Not connected unless the graph maps it (to FPLOC_PLAN_DIFF, where fploc-plan-diff publishes).
             fploc::rt::input<fploc::plan_diff_t>("plan_diff", "")}};
  }

  ~DashboardNode() override { stop_server(); }

  void setup(fploc::rt::Context& ctx) override {
    ctx_ = &ctx;
    const auto& o = ctx.options<fploc::DashboardOptions>();
    // In composed replay there is no wall clock and no socket: the dashboard does nothing there.
    if (ctx.composed()) return;
    bind_ = o.bind().empty() ? "127.0.0.1" : o.bind();
    port_ = o.port() > 0 ? o.port() : 8080;
    max_hz_ = o.max_push_hz() > 0 ? std::min(o.max_push_hz(), 20.0) : 20.0;
    token_ = o.control_token();
    if (o.max_streams() > 0) max_streams_ = size_t(o.max_streams());
    ModelConfig mc;
    if (o.silent_after_s() > 0) mc.silent_after_s = o.silent_after_s();
    model_ = std::make_unique<Model>(mc);

    std::string root = o.web_root().empty() ? std::string() : ctx.resolve_path(o.web_root());
    if (root.empty() && getenv("FPLOC_WEB_ROOT")) root = getenv("FPLOC_WEB_ROOT");
    if (root.empty()) root = FPLOC_WEB_ROOT;
    std::error_code ec;
    web_root_ = fs::canonical(root, ec);
    if (ec || !fs::is_directory(web_root_)) ctx.error("dashboard.web_root: '" + root + "' is not a folder; no page will be served");

    load_plan(o);
    if (!o.graph().empty()) {
      const std::string gpath = ctx.resolve_path(o.graph());
      fploc::rt::LoadedGraph g;
      std::vector<fploc::rt::GraphError> errors;
      if (fploc::rt::load_graph(gpath, g, errors)) {
        for (const auto& n : g.graph.node())
          if (!n.disabled()) model_->expect_node(n.name(), n.executable(), steady_s());
      } else {
        ctx.error("dashboard.graph: " + (errors.empty() ? gpath : errors.front().str()));
      }
    }
    model_->set_info("bind", fploc::json_text(json(bind_)));
    model_->set_info("port", std::to_string(port_));
    model_->set_info("max_push_hz", fploc::json_text(json(max_hz_)));
    model_->set_info("control", token_.empty() ? "false" : "true");
    model_->set_info("silent_after_s", fploc::json_text(json(mc.silent_after_s)));

    ctx.subscribe<fploc::pose_t>("pose", [this](const fploc::pose_t& m) { model_->on_pose(m, steady_s(), wall_us()); });
    ctx.subscribe<fploc::frame_pose_t>(
        "frame_pose", [this](const fploc::frame_pose_t& m) { model_->on_frame_pose(m, steady_s(), wall_us()); });
    ctx.subscribe<fploc::features_t>("features",
                                     [this](const fploc::features_t& m) { model_->on_features(m, steady_s(), wall_us()); });
    ctx.subscribe<fploc::ground_truth_t>(
        "ground_truth", [this](const fploc::ground_truth_t& m) { model_->on_ground_truth(m, steady_s(), wall_us()); });
    ctx.subscribe<fploc::node_status_t>("telemetry",
                                        [this](const fploc::node_status_t& m) { model_->on_status(m, steady_s()); });
    // Other robots on the same plan: their poses and telemetry on "R/<the same channel>".
    std::vector<std::string> others(o.robots().begin(), o.robots().end());
    model_->set_robots(ctx.robot(), others);
    auto base = [&](const std::string& port) {
      const std::string& ch = ctx.channel(port);
      return ctx.robot().empty() ? ch : ch.substr(ctx.robot().size() + 1);
    };
    for (const auto& r : others) {
      if (r == ctx.robot() || !fploc::rt::valid_robot_name(r) || r.empty()) continue;
      auto h = std::make_unique<FleetHandler>(FleetHandler{this, r});
      ctx.bus().lcm().subscribe(fploc::rt::robot_channel(r, base("pose")), &FleetHandler::pose, h.get());
      ctx.bus().lcm().subscribe(fploc::rt::robot_channel(r, base("telemetry")), &FleetHandler::status, h.get());
      fleet_.push_back(std::move(h));
    }
    if (!ctx.channel("plan_diff").empty())
      ctx.subscribe<fploc::plan_diff_t>("plan_diff", [this](const fploc::plan_diff_t& m) { model_->on_plan_diff(plan_diff_json(m)); });
    ctx.every(0.5, [this] {
      model_->tick(steady_s(), wall_us());
      if (!listening_) try_listen();
      forward_commands();
    });
    try_listen();
  }

  void shutdown() override { stop_server(); }

 private:
  void load_plan(const fploc::DashboardOptions& o) {
    if (o.plan().file().empty()) {
      model_->set_plan_json("null");
      return;
    }
    const std::string path = ctx_->resolve_path(o.plan().file());
    try {
      std::vector<std::string> layers(o.plan().layers().begin(), o.plan().layers().end());
      // Every floor of a building (the page shows the pose's floor or the one the viewer picks).
      floors_ = load_floor_plans(path, layers, o.plan().units(), o.plan().floor());
      model_->set_plan_json(floors_.plan_json.at(floors_.initial));
      std::cerr << "[" << ctx_->name() << "] plan " << path << ": " << floors_.plan_json.size() << " floor(s), showing '"
                << floors_.initial << "'\n";
    } catch (const std::exception& e) {
      ctx_->error(std::string("dashboard.plan.file: ") + e.what());
      model_->set_plan_json("null");
    }
  }

  HttpReply json_reply(std::string body) {
    HttpReply r;
    r.content_type = "application/json";
    r.body = std::move(body);
    r.headers.push_back({"Cache-Control", "no-store"});
    return r;
  }
  static HttpReply text(int status, std::string body) {
    HttpReply r;
    r.status = status;
    r.body = std::move(body);
    return r;
  }

  HttpReply handle(const HttpRequest& req) {
    if (req.method == "POST") {
      if (req.path == "/api/command") return on_command(req);
      return text(405, "read-only dashboard\n");
    }
    if (req.method != "GET" && req.method != "HEAD") return text(405, "read-only dashboard\n");
    if (req.path == "/api/plan") {
      if (auto f = req.query.find("floor"); f != req.query.end() && !f->second.empty()) {
        auto it = floors_.plan_json.find(f->second);
        if (it == floors_.plan_json.end()) return text(404, "no floor '" + f->second + "' in the plan\n");
        return json_reply(it->second);
      }
      return json_reply(model_->plan_json());
    }
    if (req.path == "/api/floors")
      return json_reply(floors_.floors_json.empty() ? std::string("{\"floors\":[],\"initial\":null}") : floors_.floors_json);
    if (req.path == "/api/state") return json_reply(model_->state_json());
    if (req.path == "/api/info") return json_reply(model_->info_json());
    if (req.path == "/api/history") {
      int64_t since = INT64_MIN;
      if (auto it = req.query.find("since"); it != req.query.end()) {
        try {
          size_t used = 0;
          since = std::stoll(it->second, &used);
          if (used != it->second.size()) throw std::invalid_argument("trailing");
        } catch (const std::exception&) {
          return text(400, "since: expected an integer utime\n");
        }
      }
      if (auto r = req.query.find("robot"); r != req.query.end() && !r->second.empty()) {
        if (!model_->has_robot(r->second)) return text(404, "no robot '" + r->second + "' on this dashboard\n");
        return json_reply(model_->fleet_history_json(r->second, since));
      }
      return json_reply(model_->history_json(since));
    }
    const std::string file = web_root_.empty() ? std::string() : resolve_web_path(web_root_, req.path);
    if (file.empty()) return text(404, "not found\n");
    std::ifstream in(file, std::ios::binary);
    HttpReply r;
    r.body.assign((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    r.content_type = mime_type(fs::path(file).extension().string());
    r.headers.push_back({"Cache-Control", "no-cache"});
    return r;
  }

  // Control is off unless the options give a token; then POST /api/command with header
  // X-Fploc-Token and body {"node": ..., "action": "restart"|"stop"|"start"} is forwarded to the
  // launcher on FPLOC_CONTROL (which checks the token again).
  HttpReply on_command(const HttpRequest& req) {
    if (token_.empty()) return text(403, "control is disabled (dashboard.control_token is empty)\n");
    if (!constant_time_equal(req.header("x-fploc-token"), token_)) return text(403, "bad token\n");
    fploc::node_command_t c;
    try {
      auto j = json::parse(req.body);
      c.node = j.at("node").get<std::string>();
      c.action = j.at("action").get<std::string>();
      if (c.action != "restart" && c.action != "stop" && c.action != "start") throw std::runtime_error("bad action");
    } catch (const std::exception& e) {
      return text(400, std::string("expected {\"node\":..., \"action\":\"restart|stop|start\"}: ") + e.what() + "\n");
    }
    c.utime = wall_us();
    c.executable = "";
    c.num_set = 0;
    c.token = token_;
    std::lock_guard<std::mutex> lk(cmd_mu_);
    if (commands_.size() >= 16) return text(429, "too many commands queued\n");
    commands_.push_back(c);
    return json_reply("{\"queued\":true}");
  }

  void forward_commands() {
    std::vector<fploc::node_command_t> cmds;
    {
      std::lock_guard<std::mutex> lk(cmd_mu_);
      cmds.swap(commands_);
    }
    for (const auto& c : cmds) ctx_->bus().lcm().publish(ctx_->ns(fploc::rt::kControlChannel), &c);
  }

  void try_listen() {
    if (listening_ || stopping_) return;
    if (!server_) {
      HttpServerConfig hc;
      hc.bind = bind_;
      hc.port = port_;
      hc.max_push_hz = max_hz_;
      hc.max_streams = max_streams_;
      hc.common_headers = {{"X-Content-Type-Options", "nosniff"},
                           {"Referrer-Policy", "no-referrer"},
                           {"Content-Security-Policy",
                            "default-src 'self'; img-src 'self' data:; style-src 'self'; connect-src 'self'"}};
      server_ = std::make_unique<HttpServer>(hc, model_->hub(), [this](const HttpRequest& r) { return handle(r); });
      server_->on_streams_changed([this](size_t n) { model_->set_clients(n); });
    }
    std::string err;
    if (!server_->listen(err)) {
      // Its telemetry says so while it lasts (state "failing", last_error), not only one line on stderr.
      ctx_->set_failing("dashboard: cannot listen on " + bind_ + ":" + std::to_string(port_) + " (" + err +
                        "); not serving, retrying every 0.5 s");
      return;
    }
    ctx_->set_failing("");
    listening_ = true;
    server_->start();
    std::cerr << "[" << ctx_->name() << "] dashboard on http://" << bind_ << ":" << port_ << "/ (web root "
              << web_root_.string() << "; at most " << max_streams_ << " event streams)" << std::endl;
  }

  void stop_server() {
    if (stopping_) return;
    stopping_ = true;
    if (server_) server_->stop();
  }

  struct FleetHandler {
    DashboardNode* self;
    std::string robot;
    void pose(const lcm::ReceiveBuffer*, const std::string&, const fploc::pose_t* m) {
      self->model_->on_fleet_pose(robot, *m, steady_s(), wall_us());
    }
    void status(const lcm::ReceiveBuffer*, const std::string&, const fploc::node_status_t* m) {
      self->model_->on_fleet_status(robot, *m, steady_s());
    }
  };
  std::vector<std::unique_ptr<FleetHandler>> fleet_;
  fploc::rt::Context* ctx_ = nullptr;
  std::unique_ptr<Model> model_;
  std::unique_ptr<HttpServer> server_;
  size_t max_streams_ = 256;
  std::string bind_, token_;
  int port_ = 8080;
  double max_hz_ = 20;
  FloorPlans floors_;  // set in setup, read by the HTTP thread
  fs::path web_root_;
  bool listening_ = false, stopping_ = false;
  std::mutex cmd_mu_;
  std::vector<fploc::node_command_t> commands_;
};

FPLOC_REGISTER_NODE(DashboardNode)

}  // namespace fploc::dashboard
