// `pdyn serve` from outside, as a browser sees it: the real program on a
// free port, HTTP and WebSocket clients over loopback. Bad messages get an
// error and the connection stays; a client vanishing mid-stream does not
// stop the others; two clients see one simulation; frames stay under ~60
// a second; SIGINT stops the server with status 0.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>
#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange unincluded

#include "protocol.hpp"
#include "support/test_support.hpp"

extern char** environ;

namespace pdyn::viewer {
namespace {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
namespace fs = std::filesystem;
using tcp = net::ip::tcp;
using nlohmann::json;
using namespace std::chrono_literals;

// A 10 x 10 cloth, pinned at two corners: always moving, quick to step.
const char* kClothScene = R"(
simulation: { dt: 0.001, duration: 1, solver: { type: rk4 } }
particles:
  - grid: { origin: [0, 0, 1], u: [0.1, 0, 0], v: [0, 0, 0.1], nx: 10, ny: 10, mass: 0.01,
            pin: [[0, -1], [-1, -1]], springs: { structural: { ks: 100, kd: 0.01 } } }
forces:
  - { type: gravity }
)";

// The real `pdyn serve` as a child process on a free port.
class Server {
 public:
  Server() {
    const fs::path dir = test::temp_dir("serve");
    scene_ = test::write_file(dir / "cloth.yaml", kClothScene);
    test::write_file(dir / "page" / "index.html", "<!doctype html><title>pdyn</title>\n");
    int out[2];
    if (pipe(out) != 0) throw std::runtime_error("pipe");
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
    posix_spawn_file_actions_addclose(&actions, out[0]);
    const std::string page = (dir / "page").string();
    std::vector<std::string> args{PDYN_BIN,   "serve", scene_.string(), "--port",       "0",
                                  "--viewer", page,    "--plugin-path", PDYN_PLUGIN_DIR};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    if (posix_spawn(&pid_, PDYN_BIN, &actions, nullptr, argv.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&actions);
    close(out[1]);
    out_ = out[0];
    // The first line: "pdyn serve: http://127.0.0.1:PORT/ (SCENE)".
    std::string line;
    const auto deadline = std::chrono::steady_clock::now() + 30s;
    while (line.find('\n') == std::string::npos && std::chrono::steady_clock::now() < deadline) {
      pollfd p{out_, POLLIN, 0};
      if (poll(&p, 1, 100) <= 0) continue;
      char buf[256];
      const ssize_t n = read(out_, buf, sizeof buf);
      if (n <= 0) break;
      line.append(buf, static_cast<std::size_t>(n));
    }
    first_line_ = line.substr(0, line.find('\n'));
    const auto colon = first_line_.rfind(':');
    if (colon != std::string::npos) port_ = std::atoi(first_line_.c_str() + colon + 1);
  }
  ~Server() {
    if (pid_ > 0) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    close(out_);
  }
  int port() const { return port_; }
  const std::string& first_line() const { return first_line_; }
  const fs::path& scene() const { return scene_; }

  // SIGINT; the exit status, or -1 if it is still running after 10 s.
  int interrupt() {
    kill(pid_, SIGINT);
    for (int k = 0; k < 1000; ++k) {
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      std::this_thread::sleep_for(10ms);
    }
    return -1;
  }

 private:
  pid_t pid_ = -1;
  int out_ = -1;
  int port_ = 0;
  std::string first_line_;
  fs::path scene_;
};

std::pair<int, std::string> http_request(int port, http::verb verb, const std::string& target) {
  net::io_context ioc;
  tcp::socket socket(ioc);
  socket.connect({net::ip::make_address("127.0.0.1"), static_cast<unsigned short>(port)});
  http::request<http::string_body> req{verb, target, 11};
  req.set(http::field::host, "127.0.0.1");
  http::write(socket, req);
  beast::flat_buffer buffer;
  http::response<http::string_body> res;
  http::read(socket, buffer, res);
  return {static_cast<int>(res.result_int()), res.body()};
}

struct WsMessage {
  bool text = false;
  std::string data;
};

// A WebSocket client whose reads time out instead of hanging the test.
class Client {
 public:
  explicit Client(int port) : ws_(ioc_) {
    ws_.next_layer().connect(
        {net::ip::make_address("127.0.0.1"), static_cast<unsigned short>(port)});
    ws_.handshake("127.0.0.1", "/ws");
  }
  void send(const std::string& text, bool binary = false) {
    ws_.binary(binary);
    ws_.write(net::buffer(text));
  }
  std::optional<WsMessage> read(std::chrono::milliseconds timeout = 5000ms) {
    std::optional<WsMessage> got;
    bool failed = false;
    buffer_.consume(buffer_.size());
    ws_.async_read(buffer_, [&](beast::error_code ec, std::size_t) {
      if (ec) {
        failed = true;
        return;
      }
      got = WsMessage{ws_.got_text(), beast::buffers_to_string(buffer_.data())};
    });
    ioc_.restart();
    ioc_.run_for(timeout);
    if (!got && !failed) {
      beast::error_code ignored;
      ws_.next_layer().cancel(ignored);
      ioc_.restart();
      ioc_.run();
    }
    return got;
  }
  // The next text message of this type, skipping frames and other messages.
  json next(const std::string& type) {
    for (int k = 0; k < 2000; ++k) {
      const auto m = read();
      if (!m) break;
      if (m->text) {
        json j = json::parse(m->data);
        if (j["type"] == type) return j;
      }
    }
    ADD_FAILURE() << "no '" << type << "' message";
    return json{};
  }
  std::optional<Frame> next_frame() {
    for (int k = 0; k < 2000; ++k) {
      const auto m = read();
      if (!m) break;
      if (!m->text) return decode_frame(m->data);
    }
    return std::nullopt;
  }
  // Drops the TCP connection with no WebSocket close: a browser tab killed.
  void vanish() {
    beast::error_code ignored;
    ws_.next_layer().close(ignored);
  }

 private:
  net::io_context ioc_;
  websocket::stream<tcp::socket> ws_;
  beast::flat_buffer buffer_;
};

TEST(Serve, HttpServesThePageTheStateAndRefusesTheRest) {
  Server server;
  ASSERT_GT(server.port(), 0) << server.first_line();
  EXPECT_EQ(server.first_line(), "pdyn serve: http://127.0.0.1:" + std::to_string(server.port()) +
                                     "/ (" + server.scene().string() + ")");
  const auto [page_status, page] = http_request(server.port(), http::verb::get, "/");
  EXPECT_EQ(page_status, 200);
  EXPECT_EQ(page, "<!doctype html><title>pdyn</title>\n");
  const auto [state_status, state] = http_request(server.port(), http::verb::get, "/api/state");
  EXPECT_EQ(state_status, 200);
  const json j = json::parse(state);
  EXPECT_EQ(j["count"], 100);
  EXPECT_EQ(j["particles"].size(), 100u);
  EXPECT_EQ(j["particles"][99]["fixed"], true);
  EXPECT_EQ(http_request(server.port(), http::verb::get, "/../cloth.yaml").first, 404);
  EXPECT_EQ(http_request(server.port(), http::verb::get, "/missing.js").first, 404);
  EXPECT_EQ(http_request(server.port(), http::verb::post, "/api/state").first, 405);
  EXPECT_EQ(server.interrupt(), 0);
}

TEST(Serve, BadMessagesGetAnErrorAndTheConnectionStays) {
  Server server;
  ASSERT_GT(server.port(), 0) << server.first_line();
  Client c(server.port());
  const json scene = c.next("scene");
  EXPECT_EQ(scene["count"], 100);
  EXPECT_EQ(scene["version"], kProtocolVersion);
  const auto first = c.next_frame();
  ASSERT_TRUE(first);
  EXPECT_EQ(first->speeds.size(), 100u);
  EXPECT_EQ(first->topology, scene["topology"].get<std::uint32_t>());

  const std::pair<std::string, std::string> bad[] = {
      {"not json", "message is not JSON"},
      {"[]", "message is a JSON array"},
      {R"({"op":"fly"})", "unknown op 'fly'"},
      {R"({"op":"nail","id":100})", "nail: field 'id' is 100, but there are 100 particles"},
      {R"({"op":"play","pad":")" + std::string(100000, 'x') + "\"}", "is too long"},
  };
  for (const auto& [text, reason] : bad) {
    c.send(text);
    const json e = c.next("error");
    EXPECT_NE(e["message"].get<std::string>().find(reason), std::string::npos) << e.dump();
  }
  c.send("\x01\x02", true);
  EXPECT_NE(c.next("error")["message"].get<std::string>().find("binary message"),
            std::string::npos);
  // Still connected, and still obeyed.
  c.send(R"({"op":"play"})");
  EXPECT_EQ(c.next("ack")["op"], "play");
  EXPECT_EQ(server.interrupt(), 0);
}

TEST(Serve, FramesStayUnderSixtyASecondAndAVanishedClientStopsNobody) {
  Server server;
  ASSERT_GT(server.port(), 0) << server.first_line();
  Client a(server.port()), b(server.port());
  a.send(R"({"op":"play"})");
  a.next("ack");
  // b stops reading; a counts what it gets in 2 s.
  int frames = 0;
  std::uint64_t first_step = 0, last_step = 0;
  const auto end = std::chrono::steady_clock::now() + 2s;
  while (std::chrono::steady_clock::now() < end) {
    const auto m = a.read(500ms);
    if (!m || m->text) continue;
    const Frame f = decode_frame(m->data);
    if (frames++ == 0) first_step = f.step;
    last_step = f.step;
  }
  EXPECT_LE(frames, 2 * 65);
  EXPECT_GE(frames, 10);  // a 100-particle cloth at real time: frames flow
  EXPECT_GT(last_step, first_step);
  b.vanish();
  std::this_thread::sleep_for(300ms);
  const auto before = a.next_frame();
  std::this_thread::sleep_for(300ms);
  const auto after = a.next_frame();
  ASSERT_TRUE(before && after);
  EXPECT_GT(after->step, before->step);
  EXPECT_EQ(http_request(server.port(), http::verb::get, "/api/state").first, 200);
  EXPECT_EQ(server.interrupt(), 0);
}

TEST(Serve, TwoClientsSeeOneSimulation) {
  Server server;
  ASSERT_GT(server.port(), 0) << server.first_line();
  Client a(server.port()), b(server.port());
  const json sa = a.next("scene"), sb = b.next("scene");
  EXPECT_EQ(sa["topology"], sb["topology"]);
  a.send(R"({"op":"nail","id":5})");
  const json na = a.next("scene"), nb = b.next("scene");
  EXPECT_EQ(na["topology"], sa["topology"].get<int>() + 1);
  EXPECT_EQ(nb["topology"], na["topology"]);
  EXPECT_EQ(nb["fixed"][5], 1);
  b.send(R"({"op":"step"})");
  EXPECT_EQ(b.next("ack")["op"], "step");
  json status = json::object();  // a periodic status from before the step may come first
  for (int k = 0; k < 20 && status.value("step", 0) != 1; ++k) status = a.next("status");
  EXPECT_EQ(status["step"], 1);
  const json state = json::parse(http_request(server.port(), http::verb::get, "/api/state").second);
  EXPECT_EQ(state["step"], 1);
  EXPECT_EQ(state["particles"][5]["fixed"], true);
  EXPECT_EQ(server.interrupt(), 0);
}

TEST(Serve, ABadSceneOrPortIsRefusedWithItsReason) {
  const fs::path dir = test::temp_dir("serve-bad");
  test::write_file(dir / "page" / "index.html", "x");
  const auto bad = test::write_file(dir / "bad.yaml", "simulation: { dt: -1, steps: 1 }\n");
  const auto r = test::pdyn({"serve", bad.string(), "--viewer", (dir / "page").string()});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find(bad.string() + ":1:"), std::string::npos) << r.err;
  const auto nopage = test::pdyn({"serve", bad.string(), "--viewer", (dir / "none").string()});
  EXPECT_EQ(nopage.status, 1);
  EXPECT_NE(nopage.err.find("the viewer's page was not found"), std::string::npos) << nopage.err;
  const auto port = test::pdyn({"serve", bad.string(), "--port", "70000"});
  EXPECT_EQ(port.status, 2);
  EXPECT_NE(port.err.find("--port 70000 is out of range"), std::string::npos) << port.err;
}

}  // namespace
}  // namespace pdyn::viewer
