#include "http_server.h"

#include <utility>  // before Boost 1.74 Asio, which uses std::exchange without it under C++20
#include <atomic>
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <chrono>
#include <cmath>
#include <deque>
#include <mutex>
#include <optional>
#include <set>
#include <thread>

namespace fploc::dashboard {

namespace net = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
using tcp = net::ip::tcp;

namespace {
double steady_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
int hexval(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}
}  // namespace

std::string percent_decode(const std::string& s, bool plus_is_space) {
  std::string out;
  out.reserve(s.size());
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '%' && i + 2 < s.size() && hexval(s[i + 1]) >= 0 &&
        hexval(s[i + 2]) >= 0) {
      out += char(hexval(s[i + 1]) * 16 + hexval(s[i + 2]));
      i += 2;
    } else if (plus_is_space && s[i] == '+') {
      out += ' ';
    } else {
      out += s[i];
    }
  }
  return out;
}

struct HttpServer::Impl : std::enable_shared_from_this<HttpServer::Impl> {
  struct Stream;
  struct Session;

  HttpServerConfig cfg;
  PushHub& hub;
  Handler handler;
  std::atomic<size_t> n_conns{0}, n_streams{0};
  std::atomic<bool> wake_pending{false}, stopped{false};
  std::function<void(size_t)> streams_cb;
  double last_send_s = 0;
  int bound_port = 0;

  net::io_context ioc{1};
  tcp::acceptor acceptor{ioc};
  net::steady_timer timer{ioc};
  std::set<std::shared_ptr<Stream>> streams;  // loop thread only
  std::thread thread;

  Impl(HttpServerConfig c, PushHub& h, Handler f) : cfg(std::move(c)), hub(h), handler(std::move(f)) {}

  // ---- one event stream: a queue of shared buffers, one write in flight, a read that only notices EOF.
  struct Stream : std::enable_shared_from_this<Stream> {
    Impl* srv;
    tcp::socket sock;
    std::deque<std::shared_ptr<const std::string>> q;
    size_t queued = 0;
    bool writing = false, closed = false;
    char rd[512];
    Stream(Impl* s, tcp::socket so) : srv(s), sock(std::move(so)) {}
    ~Stream() { --srv->n_conns; }
    void push(const std::shared_ptr<const std::string>& b) {
      if (closed) return;
      q.push_back(b);
      queued += b->size();
      if (queued > srv->cfg.max_queued_bytes) return close();
      if (!writing) write_next();
    }
    void write_next() {
      writing = true;
      net::async_write(sock, net::buffer(*q.front()), [self = shared_from_this()](beast::error_code ec, size_t) {
        self->writing = false;
        if (ec || self->closed) return self->close();
        self->queued -= self->q.front()->size();
        self->q.pop_front();
        if (!self->q.empty()) self->write_next();
      });
    }
    void read_loop() {
      sock.async_read_some(net::buffer(rd), [self = shared_from_this()](beast::error_code ec, size_t) {
        if (ec) return self->close();
        self->read_loop();
      });
    }
    void close() {
      if (closed) return;
      closed = true;
      beast::error_code ec;
      sock.shutdown(tcp::socket::shutdown_both, ec);
      sock.close(ec);
      srv->remove_stream(shared_from_this());
    }
  };

  // ---- ordinary requests (keep-alive), handed over to a Stream for the events path.
  struct Session : std::enable_shared_from_this<Session> {
    Impl* srv;
    beast::tcp_stream stream;
    beast::flat_buffer buf;
    std::optional<http::request_parser<http::string_body>> parser;
    http::response<http::string_body> res;
    bool handed_over = false;
    Session(Impl* s, tcp::socket so) : srv(s), stream(std::move(so)) {}
    ~Session() {
      if (!handed_over) --srv->n_conns;
    }
    void read() {
      parser.emplace();
      parser->body_limit(srv->cfg.max_body_bytes);
      parser->header_limit(16 * 1024);
      stream.expires_after(std::chrono::milliseconds(int64_t(srv->cfg.read_timeout_s * 1000)));
      http::async_read(stream, buf, *parser,
                       [self = shared_from_this()](beast::error_code ec, size_t) { self->on_read(ec); });
    }
    void on_read(beast::error_code ec) {
      if (ec == http::error::body_limit) return reply(413, "request body too large\n", false);
      if (ec) return close();
      auto& req = parser->get();
      HttpRequest r;
      r.method = std::string(req.method_string());
      const std::string target(req.target());
      const size_t qm = target.find('?');
      r.path = percent_decode(target.substr(0, qm));
      if (qm != std::string::npos) {
        const std::string qs = target.substr(qm + 1);
        size_t a = 0;
        while (a <= qs.size()) {
          size_t b = qs.find('&', a);
          if (b == std::string::npos) b = qs.size();
          const std::string kv = qs.substr(a, b - a);
          const size_t eq = kv.find('=');
          if (!kv.empty())
            r.query[percent_decode(kv.substr(0, eq), true)] =
                eq == std::string::npos ? "" : percent_decode(kv.substr(eq + 1), true);
          a = b + 1;
        }
      }
      if (r.path.find('\0') != std::string::npos) return reply(400, "bad path\n", false);
      if (r.method == "GET" && r.path == srv->cfg.events_path) return open_stream(req.version());
      for (const auto& f : req) {
        std::string name(f.name_string());
        for (auto& c : name) c = char(std::tolower((unsigned char)c));
        r.headers[name] = std::string(f.value());
      }
      r.body = std::move(req.body());
      HttpReply out;
      try {
        out = srv->handler(r);
      } catch (const std::exception& e) {
        out.status = 500;
        out.body = std::string("internal error: ") + e.what() + "\n";
      }
      send(out, req.keep_alive(), req.version());
    }
    void open_stream(unsigned version) {
      if (srv->n_streams >= srv->cfg.max_streams) {
        HttpReply r;
        r.status = 503;
        r.body = "too many event streams: this dashboard serves at most " + std::to_string(srv->cfg.max_streams) +
                 " at once (dashboard.max_streams); try again later\n";
        r.headers.push_back({"Retry-After", "5"});
        return send(r, false, version);
      }
      std::string head = "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\n"
                         "X-Accel-Buffering: no\r\nConnection: close\r\n";
      for (const auto& [k, v] : srv->cfg.common_headers) head += k + ": " + v + "\r\n";
      head += "\r\nretry: 1000\n\n" + srv->hub.snapshot();
      handed_over = true;
      beast::error_code ec;
      stream.socket().set_option(tcp::no_delay(true), ec);
      auto s = std::make_shared<Stream>(srv, stream.release_socket());
      srv->add_stream(s);
      s->push(std::make_shared<const std::string>(std::move(head)));
      s->read_loop();
    }
    void reply(int status, const std::string& body, bool keep_alive) {
      HttpReply r;
      r.status = status;
      r.body = body;
      send(r, keep_alive, 11);
    }
    void send(const HttpReply& r, bool keep_alive, unsigned version) {
      res = {};
      res.version(version);
      res.result(http::int_to_status(unsigned(r.status)));
      res.set(http::field::content_type, r.content_type);
      for (const auto& [k, v] : srv->cfg.common_headers) res.set(k, v);
      for (const auto& [k, v] : r.headers) res.set(k, v);
      res.body() = r.body;
      res.keep_alive(keep_alive);
      res.prepare_payload();
      stream.expires_after(std::chrono::milliseconds(int64_t(srv->cfg.read_timeout_s * 1000)));
      http::async_write(stream, res, [self = shared_from_this(), keep_alive](beast::error_code ec, size_t) {
        if (ec || !keep_alive) return self->close();
        self->read();
      });
    }
    void close() {
      beast::error_code ec;
      stream.socket().shutdown(tcp::socket::shutdown_send, ec);
      stream.close();
    }
  };

  void add_stream(const std::shared_ptr<Stream>& s) {
    streams.insert(s);
    n_streams = streams.size();
    if (streams_cb) streams_cb(streams.size());
  }
  void remove_stream(const std::shared_ptr<Stream>& s) {
    if (!streams.erase(s)) return;
    n_streams = streams.size();
    if (streams_cb) streams_cb(streams.size());
  }

  void accept() {
    acceptor.async_accept([self = shared_from_this()](beast::error_code ec, tcp::socket sock) {
      if (self->stopped) return;
      if (!ec) {
        if (self->n_conns >= self->cfg.max_connections) {
          beast::error_code e2;
          sock.close(e2);
        } else {
          ++self->n_conns;
          beast::error_code e2;
          sock.set_option(tcp::no_delay(true), e2);
          std::make_shared<Session>(self.get(), std::move(sock))->read();
        }
      }
      self->accept();
    });
  }

  // The broadcaster: woken by the hub (any thread) and by its own timer (held-back streams, keep-alive).
  void wake() {
    if (wake_pending.exchange(true)) return;
    net::post(ioc, [self = shared_from_this()] {
      self->wake_pending = false;
      self->flush();
    });
  }
  void flush() {
    if (stopped) return;
    const double now = steady_s();
    double next_due = INFINITY;
    std::string text = hub.take_due(now, cfg.max_push_hz, next_due);
    if (text.empty() && now - last_send_s >= cfg.keepalive_s) text = ": keep-alive\n\n";
    if (!text.empty()) {
      last_send_s = now;
      if (!streams.empty()) {
        auto b = std::make_shared<const std::string>(std::move(text));
        // push() may close (and erase) a stream: iterate over a copy.
        auto copy = streams;
        for (auto& s : copy) s->push(b);
      }
    }
    const double at = std::min(next_due, last_send_s + cfg.keepalive_s);
    timer.expires_after(std::chrono::microseconds(int64_t(std::max(0.0, at - now) * 1e6) + 1));
    timer.async_wait([self = shared_from_this()](beast::error_code ec) {
      if (!ec) self->flush();
    });
  }
};

HttpServer::HttpServer(HttpServerConfig cfg, PushHub& hub, Handler handler)
    : impl_(std::make_shared<Impl>(std::move(cfg), hub, std::move(handler))) {}

HttpServer::~HttpServer() { stop(); }

bool HttpServer::listen(std::string& error) {
  beast::error_code ec;
  const auto addr = net::ip::make_address(impl_->cfg.bind, ec);
  if (ec) {
    error = "bad bind address '" + impl_->cfg.bind + "': " + ec.message();
    return false;
  }
  tcp::endpoint ep(addr, (unsigned short)impl_->cfg.port);
  auto& a = impl_->acceptor;
  if (a.is_open()) a.close(ec);
  a.open(ep.protocol(), ec);
  if (!ec) a.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) a.bind(ep, ec);
  if (!ec) a.listen(net::socket_base::max_listen_connections, ec);
  if (ec) {
    error = ec.message();
    a.close(ec);
    return false;
  }
  impl_->bound_port = a.local_endpoint().port();
  return true;
}

void HttpServer::start() {
  auto impl = impl_;
  impl->hub.set_notify([w = std::weak_ptr<Impl>(impl)] {
    if (auto s = w.lock()) s->wake();
  });
  impl->accept();
  impl->flush();
  impl->thread = std::thread([impl] { impl->ioc.run(); });
}

void HttpServer::stop() {
  auto impl = impl_;
  if (!impl || impl->stopped.exchange(true)) return;
  impl->hub.set_notify(nullptr);
  net::post(impl->ioc, [impl] {
    beast::error_code ec;
    impl->acceptor.close(ec);
    impl->timer.cancel();
    auto copy = impl->streams;
    for (auto& s : copy) s->close();
    impl->ioc.stop();
  });
  if (impl->thread.joinable()) impl->thread.join();
  else impl->ioc.stop();
}

size_t HttpServer::streams() const { return impl_->n_streams; }
int HttpServer::port() const { return impl_->bound_port; }
void HttpServer::on_streams_changed(std::function<void(size_t)> f) { impl_->streams_cb = std::move(f); }

}  // namespace fploc::dashboard
