// Tests for ctsurg/sim/live/live_server.h: the token, the Host and the Origin checks, hostile socket
// messages, a second browser, and a real browser (headless Chromium, tests/support/chromium/
// chromium_live.mjs) dragging a grab and a cut across the scenario tests' bar and saving the session,
// which then replays to the same trajectory.
#include "chromium_checks.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/trajectory_file.h"
#include "ctsurg/sim/live/live_protocol.h"
#include "ctsurg/sim/live/live_server.h"
#include "ctsurg/sim/scenario/scenario.h"
#include "ctsurg/sim/scenario/scenario_run.h"
#include "live_test_scenarios.h"
#include "scenario_test_files.h"
#include "test_support.h"

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <fstream>
#include <random>
#include <thread>

namespace fs = std::filesystem;
namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using nlohmann::json;
using namespace ctsurg;
using namespace ctsurg::sim;
using ctsurg::test::TempDir;
using ctsurg::sim::test::expect_same_trajectory;
using ctsurg::sim::test::live_bar_text;

namespace {

// A session on the bar and its server, running on a thread of its own until destroyed.
struct Running {
  TempDir dir;
  std::unique_ptr<LiveSession> session;
  std::unique_ptr<LiveServer> server;
  std::thread thread;

  explicit Running(LiveServerOptions options = {}) {
    ctsurg::sim::test::write_block_files(dir.path(), 16, 4, 4, 2.0);
    const std::string text = live_bar_text("", "0.02");
    session = std::make_unique<LiveSession>(parse_scenario(text, dir.path() / "bar.yaml", dir.path()), text);
    if (options.save_scenario.empty()) {
      options.save_scenario = dir.path() / "saved.yaml";
      options.save_trajectory = dir.path() / "saved.h5";
    }
    server = std::make_unique<LiveServer>(*session, options);
    thread = std::thread([this] { server->run(); });
  }
  ~Running() { stop(); }
  void stop() {
    if (!thread.joinable()) return;
    server->stop();
    thread.join();
  }
  std::string host() const { return "127.0.0.1:" + std::to_string(server->port()); }
};

struct Reply {
  int status = 0;
  std::string body;
  http::fields headers;
};

Reply http_get(const Running& r, const std::string& target, const std::string& host = "",
               http::verb method = http::verb::get) {
  asio::io_context io;
  beast::tcp_stream stream(io);
  stream.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), r.server->port()));
  http::request<http::string_body> request(method, target, 11);
  request.set(http::field::host, host.empty() ? r.host() : host);
  http::write(stream, request);
  beast::flat_buffer buffer;
  http::response<http::string_body> response;
  http::read(stream, buffer, response);
  Reply out{static_cast<int>(response.result_int()), response.body(), {}};
  for (const auto& field : response) out.headers.set(field.name_string(), field.value());
  return out;
}

// A WebSocket client of the server (the page's side of the protocol).
struct Client {
  asio::io_context io;
  websocket::stream<beast::tcp_stream> ws{io};

  // Throws beast::system_error when the server refuses the handshake.
  Client(const Running& r, const std::string& path, const std::string& origin) : Client(r.server->port(), path, origin) {}
  Client(uint16_t port, const std::string& path, const std::string& origin) {
    beast::get_lowest_layer(ws).connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), port));
    ws.set_option(websocket::stream_base::decorator([origin](websocket::request_type& q) { q.set(http::field::origin, origin); }));
    ws.handshake("127.0.0.1:" + std::to_string(port), path);
  }
  static std::string page_origin(const Running& r) { return "http://" + r.host(); }

  void send(const std::string& text) {
    ws.text(true);
    ws.write(asio::buffer(text));
  }
  // The next text message, skipping binary frames and status messages; empty when the socket closed.
  json next_text(const std::string& skip_type = "status") {
    for (;;) {
      beast::flat_buffer buffer;
      beast::error_code ec;
      ws.read(buffer, ec);
      if (ec) return json();
      if (!ws.got_text()) continue;
      json m = json::parse(beast::buffers_to_string(buffer.data()));
      if (m["type"] != skip_type) return m;
    }
  }
  // Reads until a binary frame; returns its bytes (empty when the socket closed).
  std::vector<uint8_t> next_frame() {
    for (;;) {
      beast::flat_buffer buffer;
      beast::error_code ec;
      ws.read(buffer, ec);
      if (ec) return {};
      if (ws.got_binary()) {
        const std::string bytes = beast::buffers_to_string(buffer.data());
        return {bytes.begin(), bytes.end()};
      }
    }
  }
};

}  // namespace

TEST(LiveServer, ServesThePageOnlyUnderItsTokenAndToItsOwnHost) {
  Running r;
  const std::string base = "/" + r.server->token() + "/";
  EXPECT_EQ(r.server->token().size(), 32u);
  EXPECT_EQ(r.server->url(), "http://" + r.host() + base);
  const Reply page = http_get(r, base);
  ASSERT_EQ(page.status, 200);
  EXPECT_NE(page.body.find("live_page.js"), std::string::npos);
  EXPECT_EQ(page.headers[http::field::content_type], "text/html; charset=utf-8");
  EXPECT_NE(std::string(page.headers["Content-Security-Policy"]).find("default-src 'self'"), std::string::npos);
  EXPECT_EQ(http_get(r, base + "three.module.js").status, 200);
  EXPECT_EQ(http_get(r, base + "live_page.js?x=1").status, 200);
  // No token, another token, the token without its slash, a file not served: nothing about the session.
  for (const std::string& target : {std::string("/"), std::string("/favicon.ico"), "/" + std::string(32, 'a') + "/",
                                    "/" + r.server->token(), base + "uvs.bin", base + "../" + r.server->token() + "/",
                                    base + "etc/passwd"}) {
    const Reply refused = http_get(r, target);
    EXPECT_EQ(refused.status, 404) << target;
    EXPECT_EQ(refused.body.find(r.server->token()), std::string::npos) << target;
  }
  // Another host name (a DNS-rebinding page) and other methods are refused.
  EXPECT_EQ(http_get(r, base, "attacker.example:" + std::to_string(r.server->port())).status, 421);
  EXPECT_EQ(http_get(r, base, "localhost:" + std::to_string(r.server->port())).status, 200);
  EXPECT_EQ(http_get(r, base, "", http::verb::post).status, 405);
  EXPECT_EQ(r.server->stats().refused_requests, 9u);  // 7 not found, 421, 405
}

TEST(LiveServer, RefusesSocketsWithoutTheTokenOrFromAnotherOrigin) {
  Running r;
  const std::string base = "/" + r.server->token() + "/";
  EXPECT_THROW(Client(r, "/ws", Client::page_origin(r)), beast::system_error);
  EXPECT_THROW(Client(r, "/" + std::string(32, '0') + "/ws", Client::page_origin(r)), beast::system_error);
  EXPECT_THROW(Client(r, base + "ws", "http://attacker.example"), beast::system_error);
  EXPECT_THROW(Client(r, base + "ws", ""), beast::system_error);
  Client c(r, base + "ws", Client::page_origin(r));
  const json hello = c.next_text();
  EXPECT_EQ(hello["type"], "hello");
  EXPECT_EQ(hello["scenario"], "live bar");
  EXPECT_GT(hello["vertex_count"].get<int>(), 100);
  EXPECT_EQ(hello["save_to"]["scenario"], (r.dir.path() / "saved.yaml").string());
  // The first frame carries the triangles.
  const LiveFrame f = decode_live_frame(c.next_frame());
  EXPECT_TRUE(f.flags & LiveFrame::triangles_follow);
  EXPECT_EQ(f.positions.size(), 3 * hello["vertex_count"].get<size_t>());
}

TEST(LiveServer, HostileSocketMessagesAreAnsweredAndTheServerGoesOn) {
  Running r;
  const std::string ws = "/" + r.server->token() + "/ws";
  {
    Client c(r, ws, Client::page_origin(r));
    ASSERT_EQ(c.next_text()["type"], "hello");
    const auto error_for = [&](const std::string& text) {
      c.send(text);
      const json reply = c.next_text();
      EXPECT_EQ(reply["type"], "error") << text << " -> " << reply.dump();
      return reply.value("message", std::string());
    };
    EXPECT_NE(error_for("not json").find("not JSON"), std::string::npos);
    EXPECT_NE(error_for(std::string(5000, ' ')).find("at most 4096"), std::string::npos);
    EXPECT_NE(error_for(R"({"type": "move", "id": 0, "position_mm": [1, 2, 3]})").find("not a tool this page holds"), std::string::npos);
    EXPECT_NE(error_for(R"({"type": "begin", "tool": "grab", "radius_mm": 3, "position_mm": [1e6, 0, 0]})").find("position_mm[0]"),
              std::string::npos);
    EXPECT_NE(error_for(R"({"type": "launch"})").find("type"), std::string::npos);
    c.ws.binary(true);
    c.ws.write(asio::buffer(std::string("\x01\x02\x03")));
    EXPECT_EQ(c.next_text()["type"], "error");
    // Random and mutated messages: each one answered (an error, or began for a valid begin).
    std::mt19937 random(7);
    const std::string valid = R"({"type": "begin", "tool": "probe", "radius_mm": 2, "position_mm": [40, -15, 35], "seq": 9})";
    for (int k = 0; k < 150; ++k) {
      std::string text = valid;
      for (int e = 0; e < 1 + static_cast<int>(random() % 4); ++e) {
        text[random() % text.size()] = static_cast<char>(32 + random() % 95);  // printable: valid UTF-8
      }
      c.send(text);
      const json reply = c.next_text();
      ASSERT_TRUE(reply.is_object()) << "no answer to " << text;
      EXPECT_TRUE(reply["type"] == "error" || reply["type"] == "began") << text;
      if (reply["type"] == "began") c.send(json{{"type", "end"}, {"id", reply["id"]}}.dump());
    }
    // A message over the socket's limit closes that socket (1009)...
    c.send(std::string(LiveServer::kMaxSocketMessageBytes + 1, 'x'));
    EXPECT_TRUE(c.next_text().is_null());
  }
  // ... and the server goes on: a new page gets its hello and frames.
  Client again(r, ws, Client::page_origin(r));
  EXPECT_EQ(again.next_text()["type"], "hello");
  EXPECT_FALSE(again.next_frame().empty());
  EXPECT_GE(r.server->stats().refused_messages, 7u);
}

TEST(LiveServer, ASecondBrowserTakesTheSessionOverAndTheFirstOnesGrabIsLetGo) {
  Running r;
  const std::string ws = "/" + r.server->token() + "/ws";
  Client first(r, ws, Client::page_origin(r));
  ASSERT_EQ(first.next_text()["type"], "hello");
  first.send(R"({"type": "begin", "tool": "grab", "radius_mm": 2.5, "position_mm": [42, -15, 35], "seq": 1})");
  const json began = first.next_text();
  ASSERT_EQ(began["type"], "began");
  EXPECT_EQ(began["seq"], 1);
  first.send(R"({"type": "move", "id": 0, "position_mm": [42, -15, 40], "seq": 2})");
  // The frame that follows says the move was handed to the session.
  for (;;) {
    const LiveFrame f = decode_live_frame(first.next_frame());
    if (f.seq == 2) break;
  }
  Client second(r, ws, Client::page_origin(r));
  const json closed = first.next_text();
  EXPECT_EQ(closed["type"], "closed");
  EXPECT_NE(closed["message"].get<std::string>().find("another browser"), std::string::npos);
  EXPECT_TRUE(first.next_text().is_null());  // then the socket closes
  EXPECT_EQ(second.next_text()["type"], "hello");
  // The second page cannot move the first one's tool; it is no longer held.
  second.send(R"({"type": "move", "id": 0, "position_mm": [42, -15, 38]})");
  EXPECT_EQ(second.next_text()["type"], "error");
  r.stop();
  EXPECT_FALSE(r.session->tool_active(0));
  EXPECT_EQ(r.server->stats().sockets_taken_over, 1u);
  EXPECT_TRUE(r.server->unsaved());
}

TEST(LiveServer, ChromiumDragsAGrabAndACutAndTheSavedSessionReplays) {
  CTSURG_REQUIRE_CHROMIUM();
  Running r;
  const fs::path before = r.dir.path() / "before.png", after = r.dir.path() / "after.png";
  const auto quote = [](const std::string& s) { return "'" + s + "'"; };
  // The bar seen from the front (y = -19 mm is its front face): the grab near its free end, the cut
  // across its middle.
  const std::string command =
      "node " + quote((ctsurg::test::source_dir() / "tests/support/chromium/chromium_live.mjs").string()) +
      " --size 640x480 --timeout-ms 60000 --grab 40,-19,35 --cut 26,-19,37 " + quote(r.server->url()) + " " +
      quote(before.string()) + " " + quote(after.string());
  const ctsurg::test::CommandResult run = ctsurg::test::run_shell(command);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const size_t at = run.output.find("live: ");
  ASSERT_NE(at, std::string::npos) << run.output;
  const json page = json::parse(run.output.substr(at + 6, run.output.find('\n', at) - at - 6));
  // Nothing but the server was asked for, and the page threw nothing.
  std::istringstream lines(run.output);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("request: ", 0) == 0) {
      EXPECT_EQ(line.rfind("request: " + r.server->url(), 0), 0u) << line;
    }
    EXPECT_NE(line.rfind("exception: ", 0), 0u) << line;
  }
  EXPECT_TRUE(page["errors"].empty()) << page.dump();
  EXPECT_TRUE(page["guards"].empty()) << page.dump();
  EXPECT_NE(page["topologyAfter"], page["topologyBefore"]);  // the cut opened the bar
  EXPECT_GT(page["latencies"].size(), 0u);
  EXPECT_FALSE(page["saved"].is_null());
  // The pictures before and after differ (the bar moved and opened).
  const auto pixels = [](const fs::path& p) { return ctsurg::test::read_bytes(p); };
  EXPECT_NE(pixels(before), pixels(after));

  r.stop();
  const LiveServerStats stats = r.server->stats();
  EXPECT_GT(stats.frames_sent, 10u);
  EXPECT_EQ(stats.saves, 1u);
  EXPECT_FALSE(stats.input_to_picture_ms.empty());
  // The session: a grab and a cut recorded, the topology changed; the saved scenario replays to the
  // saved trajectory bit for bit.
  EXPECT_GT(r.session->topology_version(), 1u);
  const fs::path yaml = r.dir.path() / "saved.yaml";
  const std::string text = ctsurg::test::read_bytes(yaml);
  EXPECT_NE(text.find("grab:"), std::string::npos);
  EXPECT_NE(text.find("cut:"), std::string::npos);
  expect_same_trajectory(read_trajectory_file(r.dir.path() / "saved.h5"), run_scenario(read_scenario_file(yaml)));
}

// The tool: Ctrl-C after a save still saves what came after it and ends cleanly (the file writers'
// own SIGINT handler, installed by the first save, hands the signal to the server's).
TEST(CtsurgLive, CtrlCAfterASaveSavesTheRestAndExitsCleanly) {
  TempDir dir;
  ctsurg::sim::test::write_block_files(dir.path(), 16, 4, 4, 2.0);
  const fs::path scenario = dir.path() / "bar.yaml", saved = dir.path() / "rehearsal.yaml";
  std::ofstream(scenario) << live_bar_text("", "0.02");
  int out[2];
  ASSERT_EQ(pipe(out), 0);
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(out[1], STDOUT_FILENO);
    close(out[0]);
    const std::string tool = std::string(CTSURG_TOOL_DIR) + "/ctsurg-live";
    execl(tool.c_str(), tool.c_str(), scenario.c_str(), "--save", saved.c_str(), "-q", static_cast<char*>(nullptr));
    _exit(127);
  }
  close(out[1]);
  // A session that stopped sending pictures would leave the reads below waiting for ever: after 120 s
  // the tool is killed, its socket closes and the test fails below instead of at ctest's timeout.
  struct Watchdog {
    pid_t pid;
    std::atomic<bool> done{false};
    std::thread thread{[this] {
      for (int k = 0; k < 1200 && !done; ++k) std::this_thread::sleep_for(std::chrono::milliseconds(100));
      if (!done) kill(pid, SIGKILL);
    }};
    explicit Watchdog(pid_t p) : pid(p) {}
    ~Watchdog() { disarm(); }
    void disarm() {
      done = true;
      if (thread.joinable()) thread.join();
    }
  } watchdog(pid);
  // The URL is the line with http://.
  std::string printed, url;
  char buffer[256];
  while (url.empty()) {
    const ssize_t n = read(out[0], buffer, sizeof buffer);
    ASSERT_GT(n, 0) << "ctsurg-live printed no URL: " << printed;
    printed.append(buffer, static_cast<size_t>(n));
    const size_t at = printed.find("http://127.0.0.1:"), end = printed.find('\n', at == std::string::npos ? 0 : at);
    if (at != std::string::npos && end != std::string::npos) url = printed.substr(at, end - at);
  }
  close(out[0]);
  const size_t port_at = std::string("http://127.0.0.1:").size(), slash = url.find('/', port_at);
  const uint16_t port = static_cast<uint16_t>(std::stoi(url.substr(port_at, slash - port_at)));
  {
    Client c(port, url.substr(slash) + "ws", "http://127.0.0.1:" + std::to_string(port));
    ASSERT_EQ(c.next_text()["type"], "hello");
    const auto drag = [&](int id, double z) {
      c.send(R"({"type": "begin", "tool": "grab", "radius_mm": 2.5, "position_mm": [42, -15, 35]})");
      EXPECT_EQ(c.next_text()["type"], "began");
      c.send(json{{"type", "move"}, {"id", id}, {"position_mm", {42, -15, z}}}.dump());
      for (int k = 0; k < 10; ++k) c.next_frame();  // a few pictures with the tool held
      c.send(json{{"type", "end"}, {"id", id}}.dump());
      for (int k = 0; k < 10; ++k) c.next_frame();
    };
    drag(0, 38);
    c.send(R"({"type": "save"})");
    EXPECT_EQ(c.next_text()["type"], "saved");
    drag(1, 32);  // unsaved: a 3 mm move in one message (it travels over a picture tick)
  }
  watchdog.disarm();
  ASSERT_EQ(kill(pid, SIGINT), 0);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status)) << "ended by signal " << (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  EXPECT_EQ(WEXITSTATUS(status), 0);
  // The file Ctrl-C saved holds both grabs, and replays.
  const std::string text = ctsurg::test::read_bytes(saved);
  size_t grabs = 0;
  for (size_t at = text.find("grab:"); at != std::string::npos; at = text.find("grab:", at + 1)) ++grabs;
  EXPECT_EQ(grabs, 2u) << text;
  expect_same_trajectory(read_trajectory_file(dir.path() / "rehearsal.h5"), run_scenario(read_scenario_file(saved)));
}
