// fploc-dashboard: HTTP + Server-Sent Events view of a running graph (see docs/notes/dashboard.md).
// LCM handlers run on the node thread and only update latest-value slots in the Model; the HTTP server
// (cpp-httplib) runs on its own thread pool, one thread per SSE client, each pushing the newest values
// at most max_push_hz times per second. A slow browser only delays its own thread.
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

#include "fploc/runtime/bus.h"
#include "fploc/runtime/graph.h"
#include "fploc/runtime/node.h"
#include "model.h"
#include "plan_diff_json.h"
#include "options/tools.pb.h"
#include "plan_json.h"
#include "web_path.h"
// Last: httplib pulls in <resolv.h>, whose `_res` macro breaks Eigen headers included after it.
#include <httplib.h>

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
    model_->set_info("bind", json(bind_).dump());
    model_->set_info("port", std::to_string(port_));
    model_->set_info("max_push_hz", json(max_hz_).dump());
    model_->set_info("control", token_.empty() ? "false" : "true");
    model_->set_info("silent_after_s", json(mc.silent_after_s).dump());

    ctx.subscribe<fploc::pose_t>("pose", [this](const fploc::pose_t& m) { model_->on_pose(m, steady_s(), wall_us()); });
    ctx.subscribe<fploc::frame_pose_t>(
        "frame_pose", [this](const fploc::frame_pose_t& m) { model_->on_frame_pose(m, steady_s(), wall_us()); });
    ctx.subscribe<fploc::features_t>("features",
                                     [this](const fploc::features_t& m) { model_->on_features(m, steady_s(), wall_us()); });
    ctx.subscribe<fploc::ground_truth_t>(
        "ground_truth", [this](const fploc::ground_truth_t& m) { model_->on_ground_truth(m, steady_s(), wall_us()); });
    ctx.subscribe<fploc::node_status_t>("telemetry",
                                        [this](const fploc::node_status_t& m) { model_->on_status(m, steady_s()); });
    if (!ctx.channel("plan_diff").empty())
      ctx.subscribe<fploc::plan_diff_t>("plan_diff", [this](const fploc::plan_diff_t& m) { model_->on_plan_diff(plan_diff_json(m)); });
    ctx.every(0.5, [this] {
      model_->tick(steady_s(), wall_us());
      if (!listening_) try_listen();
      forward_commands();
    });
    setup_routes();
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
      FloorPlan plan = load_plan_file(path, layers, o.plan().units());
      model_->set_plan_json(plan_to_json(plan));
      std::cerr << "[" << ctx_->name() << "] plan " << path << ": " << plan.elements.size() << " elements\n";
    } catch (const std::exception& e) {
      ctx_->error(std::string("dashboard.plan.file: ") + e.what());
      model_->set_plan_json("null");
    }
  }

  void setup_routes() {
    auto& s = server_;
    s.new_task_queue = [] { return new httplib::ThreadPool(16); };
    s.set_tcp_nodelay(true);  // small SSE events must not wait for delayed ACKs (Nagle)
    s.set_keep_alive_max_count(100);
    s.set_read_timeout(5, 0);
    s.set_write_timeout(5, 0);
    s.set_payload_max_length(64 * 1024);
    s.set_post_routing_handler([](const httplib::Request&, httplib::Response& res) {
      res.set_header("X-Content-Type-Options", "nosniff");
      res.set_header("Referrer-Policy", "no-referrer");
      res.set_header("Content-Security-Policy",
                     "default-src 'self'; img-src 'self' data:; style-src 'self'; connect-src 'self'");
    });
    auto json_reply = [](httplib::Response& res, const std::string& body) {
      res.set_header("Cache-Control", "no-store");
      res.set_content(body, "application/json");
    };
    s.Get("/api/plan", [this, json_reply](const httplib::Request&, httplib::Response& res) { json_reply(res, model_->plan_json()); });
    s.Get("/api/state", [this, json_reply](const httplib::Request&, httplib::Response& res) { json_reply(res, model_->state_json()); });
    s.Get("/api/history", [this, json_reply](const httplib::Request& req, httplib::Response& res) {
      int64_t since = INT64_MIN;
      if (req.has_param("since")) {
        try {
          since = std::stoll(req.get_param_value("since"));
        } catch (const std::exception&) {
          res.status = 400;
          res.set_content("since: expected an integer utime\n", "text/plain");
          return;
        }
      }
      json_reply(res, model_->history_json(since));
    });
    s.Get("/api/info", [this, json_reply](const httplib::Request&, httplib::Response& res) { json_reply(res, model_->info_json()); });
    s.Get("/api/events", [this](const httplib::Request&, httplib::Response& res) {
      res.set_header("Cache-Control", "no-store");
      res.set_header("X-Accel-Buffering", "no");
      auto cursor = std::make_shared<ClientCursor>();
      model_->client_count(+1);
      res.set_chunked_content_provider(
          "text/event-stream",
          [this, cursor](size_t, httplib::DataSink& sink) {
            std::string out;
            if (!model_->next_push(*cursor, max_hz_, 10.0, out)) {
              sink.done();
              return false;
            }
            if (out.empty()) out = ": keep-alive\n\n";
            return sink.write(out.data(), out.size());
          },
          [this](bool) { model_->client_count(-1); });
    });
    s.Post("/api/command", [this](const httplib::Request& req, httplib::Response& res) { on_command(req, res); });
    s.Post(R"(/.*)", [](const httplib::Request&, httplib::Response& res) {
      res.status = 405;
      res.set_content("read-only dashboard\n", "text/plain");
    });
    s.Get(R"(/.*)", [this](const httplib::Request& req, httplib::Response& res) {
      const std::string file = web_root_.empty() ? std::string() : resolve_web_path(web_root_, req.path);
      if (file.empty()) {
        res.status = 404;
        res.set_content("not found\n", "text/plain");
        return;
      }
      std::ifstream in(file, std::ios::binary);
      std::string body((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      res.set_header("Cache-Control", "no-cache");
      res.set_content(std::move(body), mime_type(fs::path(file).extension().string()));
    });
  }

  // Control is off unless the options give a token; then POST /api/command with header
  // X-Fploc-Token and body {"node": ..., "action": "restart"|"stop"|"start"} is forwarded to the
  // launcher on FPLOC_CONTROL (which checks the token again).
  void on_command(const httplib::Request& req, httplib::Response& res) {
    if (token_.empty()) {
      res.status = 403;
      res.set_content("control is disabled (dashboard.control_token is empty)\n", "text/plain");
      return;
    }
    if (!constant_time_equal(req.get_header_value("X-Fploc-Token"), token_)) {
      res.status = 403;
      res.set_content("bad token\n", "text/plain");
      return;
    }
    fploc::node_command_t c;
    try {
      auto j = json::parse(req.body);
      c.node = j.at("node").get<std::string>();
      c.action = j.at("action").get<std::string>();
      if (c.action != "restart" && c.action != "stop" && c.action != "start") throw std::runtime_error("bad action");
    } catch (const std::exception& e) {
      res.status = 400;
      res.set_content(std::string("expected {\"node\":..., \"action\":\"restart|stop|start\"}: ") + e.what() + "\n",
                      "text/plain");
      return;
    }
    c.utime = wall_us();
    c.executable = "";
    c.num_set = 0;
    c.token = token_;
    std::lock_guard<std::mutex> lk(cmd_mu_);
    if (commands_.size() >= 16) {
      res.status = 429;
      return;
    }
    commands_.push_back(c);
    res.set_content("{\"queued\":true}", "application/json");
  }

  void forward_commands() {
    std::vector<fploc::node_command_t> cmds;
    {
      std::lock_guard<std::mutex> lk(cmd_mu_);
      cmds.swap(commands_);
    }
    for (const auto& c : cmds) ctx_->bus().lcm().publish(fploc::rt::kControlChannel, &c);
  }

  void try_listen() {
    if (listening_ || stopping_) return;
    if (!server_.bind_to_port(bind_.c_str(), port_)) {
      if (!bind_error_reported_) ctx_->error("dashboard: cannot listen on " + bind_ + ":" + std::to_string(port_) +
                                             " (address in use or not local); retrying every 0.5 s");
      bind_error_reported_ = true;
      return;
    }
    listening_ = true;
    std::cerr << "[" << ctx_->name() << "] dashboard on http://" << bind_ << ":" << port_ << "/ (web root "
              << web_root_.string() << ")" << std::endl;
    thread_ = std::thread([this] { server_.listen_after_bind(); });
  }

  void stop_server() {
    if (stopping_) return;
    stopping_ = true;
    if (model_) model_->stop();
    if (listening_) {
      // stop() is a no-op before listen_after_bind() has started: wait for it (at most 1 s).
      for (int i = 0; i < 100 && !server_.is_running(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
      server_.stop();
    }
    if (thread_.joinable()) thread_.join();
  }

  fploc::rt::Context* ctx_ = nullptr;
  std::unique_ptr<Model> model_;
  httplib::Server server_;
  std::thread thread_;
  std::string bind_, token_;
  int port_ = 8080;
  double max_hz_ = 20;
  fs::path web_root_;
  bool listening_ = false, stopping_ = false, bind_error_reported_ = false;
  std::mutex cmd_mu_;
  std::vector<fploc::node_command_t> commands_;
};

FPLOC_REGISTER_NODE(DashboardNode)

}  // namespace fploc::dashboard
