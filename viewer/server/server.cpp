// `pdyn serve`: Boost.Beast HTTP + WebSocket on one io_context thread, and a
// simulation thread. Every network object lives on the io thread; the
// simulation thread only posts finished frames and status lines to it, so
// no socket is touched from two threads.
#include "server.hpp"

#include <fmt/format.h>

// clang-format off
#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange unincluded
// clang-format on
#include <atomic>
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <csignal>
#include <deque>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <ostream>
#include <sstream>
#include <thread>

#include "pdyn/host/threads.hpp"
#include "pdyn/parallel.hpp"

namespace pdyn::viewer {

namespace {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
namespace fs = std::filesystem;
using tcp = net::ip::tcp;
using Clock = std::chrono::steady_clock;
using Bytes = std::shared_ptr<const std::string>;

// A client that has not read this many text messages (status lines come 4
// times a second) is not reading at all: it is dropped rather than buffered.
constexpr std::size_t kMaxQueuedTexts = 256;
// Larger WebSocket messages are refused by Beast itself, which closes the
// connection with code 1009 ("message too big"); up to this size the client
// gets an error message and stays connected.
constexpr std::size_t kMaxReadBytes = 1 << 20;

class WsSession;

// What the network side shares: the session, the open WebSockets, and the
// shutdown flag. Used on the io thread only.
struct Hub {
  Hub(net::io_context& c, Session& s, const ServerOptions& o) : ioc(c), session(s), options(o) {}
  net::io_context& ioc;
  Session& session;
  const ServerOptions& options;
  std::map<int, std::weak_ptr<WsSession>> clients;
  std::atomic<int> client_count{0};
  int next_id = 1;
  bool stopping = false;

  void accept_websocket(tcp::socket socket, const http::request<http::string_body>& req);
  void remove(int id);
  void broadcast_text(const Bytes& text);
  void broadcast_frame(const Bytes& frame);
  void close_all();
};

Bytes bytes(std::string s) { return std::make_shared<const std::string>(std::move(s)); }

// ---------------------------------------------------------------------------
// WebSocket: commands in, frames and JSON out.

class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(tcp::socket socket, Hub& hub, int id) : ws_(std::move(socket)), hub_(hub), id_(id) {}

  void start(const http::request<http::string_body>& req) {
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.read_message_max(kMaxReadBytes);
    ws_.async_accept(req, [self = shared_from_this()](beast::error_code ec) {
      if (ec) return self->gone();
      self->open_ = true;
      self->send_text(bytes(self->hub_.session.scene_json()));
      self->send_text(bytes(self->hub_.session.status_json()));
      self->send_frame(bytes(encode_frame(self->hub_.session.frame())));
      self->read();
    });
  }

  void send_text(const Bytes& text) {
    if (!open_) return;
    if (texts_.size() >= kMaxQueuedTexts) return close();
    texts_.push_back(text);
    pump();
  }

  // Only the newest frame waits: one that arrives while the previous is
  // still being written replaces the one waiting, so a slow client sees
  // fewer frames instead of older ones.
  void send_frame(const Bytes& frame) {
    if (!open_) return;
    frame_ = frame;
    pump();
  }

  void close() {
    if (!open_) return;
    open_ = false;
    ws_.async_close(websocket::close_code::going_away,
                    [self = shared_from_this()](beast::error_code) { self->gone(); });
  }

 private:
  void read() {
    ws_.async_read(buffer_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) return self->gone();
      self->on_message();
      self->read();
    });
  }

  void on_message() {
    const bool text = ws_.got_text();
    const std::string message = beast::buffers_to_string(buffer_.data());
    buffer_.consume(buffer_.size());
    if (!text) {
      return send_text(bytes(error_message(
          "", fmt::format("a binary message of {} bytes is not a command (expected a JSON text "
                          "message with an 'op')",
                          message.size()))));
    }
    Session& session = hub_.session;
    std::string op;
    try {
      const Command c = parse_command(message);
      op = c.op_name;
      const std::uint32_t topology = session.topology();
      const auto id = session.apply(c, id_);
      if (c.op == Command::Op::Move) return;  // 60 a second: no reply
      send_text(bytes(ack_message(op, id)));
      if (session.topology() != topology) hub_.broadcast_text(bytes(session.scene_json()));
      hub_.broadcast_text(bytes(session.status_json()));
    } catch (const std::exception& e) {
      send_text(bytes(error_message(op, e.what())));
    }
  }

  void pump() {
    if (writing_ || !open_) return;
    if (!texts_.empty()) {
      current_ = texts_.front();
      texts_.pop_front();
      ws_.text(true);
    } else if (frame_) {
      current_ = std::move(frame_);
      frame_.reset();
      ws_.binary(true);
    } else {
      return;
    }
    writing_ = true;
    ws_.async_write(net::buffer(*current_),
                    [self = shared_from_this()](beast::error_code ec, std::size_t) {
                      self->writing_ = false;
                      self->current_.reset();
                      if (ec) return self->gone();
                      self->pump();
                    });
  }

  // The client closed, vanished or failed: its mouse spring goes with it.
  void gone() {
    open_ = false;
    if (removed_) return;
    removed_ = true;
    hub_.remove(id_);
  }

  websocket::stream<beast::tcp_stream> ws_;
  beast::flat_buffer buffer_;
  Hub& hub_;
  int id_;
  std::deque<Bytes> texts_;
  Bytes frame_, current_;
  bool writing_ = false, open_ = false, removed_ = false;
};

void Hub::accept_websocket(tcp::socket socket, const http::request<http::string_body>& req) {
  if (stopping) return;
  const int id = next_id++;
  auto ws = std::make_shared<WsSession>(std::move(socket), *this, id);
  clients[id] = ws;
  client_count = static_cast<int>(clients.size());
  ws->start(req);
}

void Hub::remove(int id) {
  if (clients.erase(id) == 0) return;
  client_count = static_cast<int>(clients.size());
  session.forget_client(id);
  if (!stopping) broadcast_text(bytes(session.status_json()));
}

void Hub::broadcast_text(const Bytes& text) {
  for (auto& [id, weak] : clients) {
    if (auto c = weak.lock()) c->send_text(text);
  }
}

void Hub::broadcast_frame(const Bytes& frame) {
  for (auto& [id, weak] : clients) {
    if (auto c = weak.lock()) c->send_frame(frame);
  }
}

void Hub::close_all() {
  for (auto& [id, weak] : clients) {
    if (auto c = weak.lock()) c->close();
  }
}

// ---------------------------------------------------------------------------
// HTTP: the page's files and /api/state.

const char* content_type(const fs::path& file) {
  const std::string ext = file.extension().string();
  if (ext == ".html") return "text/html; charset=utf-8";
  if (ext == ".js" || ext == ".mjs") return "text/javascript; charset=utf-8";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".json" || ext == ".map") return "application/json";
  if (ext == ".png") return "image/png";
  if (ext == ".svg") return "image/svg+xml";
  if (ext == ".ico") return "image/x-icon";
  return "application/octet-stream";
}

// The file under `root` that `path` names, or nothing: only plain relative
// names below the root are served (no "..", no backslashes, no NUL).
std::optional<fs::path> static_file(const fs::path& root, std::string path) {
  if (path == "/") path = "/index.html";
  if (path.empty() || path[0] != '/' || path.find('\\') != std::string::npos ||
      path.find('\0') != std::string::npos || path.find('%') != std::string::npos) {
    return std::nullopt;
  }
  const fs::path rel = fs::path(path.substr(1)).lexically_normal();
  for (const auto& part : rel) {
    if (part == ".." || part == ".") return std::nullopt;
  }
  const fs::path file = root / rel;
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) return std::nullopt;
  return file;
}

class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket socket, Hub& hub) : stream_(std::move(socket)), hub_(hub) {}

  void read() {
    parser_.emplace();
    parser_->body_limit(64 * 1024);
    stream_.expires_after(std::chrono::seconds(30));
    http::async_read(
        stream_, buffer_, *parser_,
        [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
  }

 private:
  using Response = http::response<http::string_body>;

  void on_read(beast::error_code ec) {
    if (ec) {
      beast::error_code ignored;
      stream_.socket().shutdown(tcp::socket::shutdown_both, ignored);
      return;
    }
    http::request<http::string_body> req = parser_->release();
    const std::string target(req.target());
    const std::string path = target.substr(0, target.find('?'));
    if (websocket::is_upgrade(req) && path == "/ws") {
      stream_.expires_never();
      hub_.accept_websocket(stream_.release_socket(), req);
      return;
    }
    respond(handle(req, path));
  }

  Response make(const http::request<http::string_body>& req, http::status status, const char* type,
                std::string body) {
    Response res{status, req.version()};
    res.set(http::field::server, "pdyn serve");
    res.set(http::field::content_type, type);
    res.set(http::field::cache_control, "no-cache");
    res.keep_alive(req.keep_alive());
    const std::size_t size = body.size();
    if (req.method() != http::verb::head) res.body() = std::move(body);
    res.content_length(size);
    return res;
  }

  Response handle(const http::request<http::string_body>& req, const std::string& path) {
    if (req.method() != http::verb::get && req.method() != http::verb::head) {
      Response res = make(req, http::status::method_not_allowed, "text/plain; charset=utf-8",
                          "only GET and HEAD are served (the viewer is read-only over HTTP; "
                          "commands go through the WebSocket /ws)\n");
      res.set(http::field::allow, "GET, HEAD");
      return res;
    }
    if (path == "/api/state") {
      return make(req, http::status::ok, "application/json", hub_.session.state_json());
    }
    if (const auto file = static_file(hub_.options.root, path)) {
      std::ifstream in(*file, std::ios::binary);
      std::ostringstream ss;
      ss << in.rdbuf();
      return make(req, http::status::ok, content_type(*file), ss.str());
    }
    return make(req, http::status::not_found, "text/plain; charset=utf-8",
                fmt::format("not found: {} (the viewer serves /, its files, /api/state and /ws)\n",
                            path.size() > 200 ? path.substr(0, 200) + "..." : path));
  }

  void respond(Response res) {
    auto sp = std::make_shared<Response>(std::move(res));
    http::async_write(stream_, *sp,
                      [self = shared_from_this(), sp](beast::error_code ec, std::size_t) {
                        if (ec || sp->need_eof()) {
                          beast::error_code ignored;
                          self->stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
                          return;
                        }
                        self->read();
                      });
  }

  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  Hub& hub_;
};

void accept(tcp::acceptor& acceptor, Hub& hub) {
  acceptor.async_accept([&acceptor, &hub](beast::error_code ec, tcp::socket socket) {
    if (hub.stopping || !acceptor.is_open()) return;
    if (!ec) std::make_shared<HttpSession>(std::move(socket), hub)->read();
    accept(acceptor, hub);
  });
}

// Binds `acceptor` to --host and --port, or throws saying why not.
void listen_on(tcp::acceptor& acceptor, const ServerOptions& options) {
  boost::system::error_code ec;
  const auto address = net::ip::make_address(options.host, ec);
  if (ec) {
    throw Error(
        fmt::format("--host {}: not an IP address (expected e.g. 127.0.0.1, or 0.0.0.0 for "
                    "every interface)",
                    options.host));
  }
  const tcp::endpoint endpoint(address, options.port);
  acceptor.open(endpoint.protocol(), ec);
  if (!ec) acceptor.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) acceptor.bind(endpoint, ec);
  if (!ec) acceptor.listen(net::socket_base::max_listen_connections, ec);
  if (ec) {
    throw Error(
        fmt::format("cannot listen on {}:{}: {} (expected a free port, or --port 0 for any)",
                    options.host, options.port, ec.message()));
  }
}

// The simulation thread: steps to real time, then offers a frame when the
// state changed, at most options.frame_rate times a second, and a status
// line four times a second, until `stop`.
void simulate(Session& session, Hub& hub, net::io_context& ioc, const ServerOptions& options,
              const std::atomic<bool>& stop) {
  // OpenMP's thread count is a per-thread setting: set it where the
  // forces run.
  if (options.threads > 0) set_threads(options.threads);
  const auto period = std::chrono::duration<double>(1.0 / options.frame_rate);
  auto last = Clock::now(), last_status = last;
  std::uint64_t sent = ~std::uint64_t{0};
  while (!stop) {
    const auto now = Clock::now();
    session.advance(std::chrono::duration<double>(now - last).count(), 0.8 * period.count());
    last = now;
    if (hub.client_count > 0) {
      const std::uint64_t version = session.version();
      if (version != sent) {
        sent = version;
        auto frame = bytes(encode_frame(session.frame()));
        net::post(ioc, [&hub, frame] { hub.broadcast_frame(frame); });
      }
      if (now - last_status >= std::chrono::milliseconds(250)) {
        last_status = now;
        auto status = bytes(session.status_json());
        net::post(ioc, [&hub, status] { hub.broadcast_text(status); });
      }
    }
    std::this_thread::sleep_until(now + std::chrono::duration_cast<Clock::duration>(period));
  }
}

}  // namespace

void serve(Session& session, const ServerOptions& options, std::ostream& out,
           const std::string& scene_name) {
  net::io_context ioc{1};
  Hub hub(ioc, session, options);

  tcp::acceptor acceptor(ioc);
  listen_on(acceptor, options);
  const unsigned short port = acceptor.local_endpoint().port();

  // Ctrl-C: stop taking connections, close every WebSocket with "going
  // away", give the close frames a moment, then stop.
  net::signal_set signals(ioc, SIGINT, SIGTERM);
  net::steady_timer grace(ioc);
  std::atomic<bool> stop{false};
  signals.async_wait([&](const boost::system::error_code& e, int) {
    if (e) return;
    hub.stopping = true;
    stop = true;
    acceptor.close();
    hub.close_all();
    grace.expires_after(std::chrono::milliseconds(300));
    grace.async_wait([&](const boost::system::error_code&) { ioc.stop(); });
  });
  accept(acceptor, hub);

  std::thread simulation([&] { simulate(session, hub, ioc, options, stop); });

  out << fmt::format("pdyn serve: http://{}:{}/ ({})", options.host, port, scene_name) << std::endl;
  try {
    ioc.run();
  } catch (...) {
    stop = true;
    simulation.join();
    throw;
  }
  stop = true;
  simulation.join();
}

}  // namespace pdyn::viewer
