// The dashboard's HTTP server: one thread, one event loop (Boost.Asio/Beast from Debian's
// libboost-dev) for every connection. Ordinary requests are answered by `handler` on that thread; the
// event-stream path is served by ONE broadcaster: whenever the push hub says something is due it formats
// the SSE text once and queues the same buffer on every open stream. Open streams are capped
// (`max_streams`): the next one gets an immediate `503` with a plain-text reason and Retry-After. A client
// that does not read (more than `max_queued_bytes` waiting) is dropped; it reconnects (EventSource) and
// starts again from the latest values. No LCM here.
#pragma once
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "push_hub.h"

namespace fploc::dashboard {

struct HttpRequest {
  std::string method;  // "GET", "POST", ...
  std::string path;    // percent-decoded, without the query
  std::map<std::string, std::string> query;    // decoded
  std::map<std::string, std::string> headers;  // lower-case names
  std::string body;
  std::string header(const std::string& lower_name) const {
    auto it = headers.find(lower_name);
    return it == headers.end() ? std::string() : it->second;
  }
};

struct HttpReply {
  int status = 200;
  std::string content_type = "text/plain; charset=utf-8";
  std::string body;
  std::vector<std::pair<std::string, std::string>> headers;
};

struct HttpServerConfig {
  std::string bind = "127.0.0.1";
  int port = 8080;
  std::string events_path = "/api/events";
  size_t max_streams = 256;          // open event streams; beyond: 503
  size_t max_connections = 1024;     // all connections; beyond: closed at once
  double max_push_hz = 20;           // per stream
  double keepalive_s = 10;           // ": keep-alive" comment when nothing else went out
  size_t max_queued_bytes = 8 << 20; // per stream; a client further behind is dropped
  size_t max_body_bytes = 64 * 1024;
  double read_timeout_s = 5;
  std::vector<std::pair<std::string, std::string>> common_headers;  // on every reply
};

class HttpServer {
 public:
  using Handler = std::function<HttpReply(const HttpRequest&)>;
  HttpServer(HttpServerConfig cfg, PushHub& hub, Handler handler);
  ~HttpServer();
  // Binds and listens (false + error when the address is taken or not local).
  bool listen(std::string& error);
  void start();  // runs the event loop on its own thread
  void stop();   // closes everything, joins the thread
  size_t streams() const;
  int port() const;  // the bound port (useful with port 0)
  // Called on the loop thread whenever the number of open streams changes.
  void on_streams_changed(std::function<void(size_t)> f);

 private:
  struct Impl;
  std::shared_ptr<Impl> impl_;
};

std::string percent_decode(const std::string& s, bool plus_is_space = false);

}  // namespace fploc::dashboard
