// The designer's HTTP API (tvf/serve/http_server.h) through httplib::Client on an
// ephemeral port: JSON in and out, clear 4xx errors for malformed requests, the limits.
#include "tvf/serve/http_server.h"

#include "support/test_paths.h"
#include "test_scene.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <httplib.h>

#include <condition_variable>
#include <mutex>
#include <atomic>
#include <chrono>
#include <fstream>
#include <future>
#include <thread>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

namespace tvf::serve {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

struct Fixture {
  test::TempDir dir;
  std::unique_ptr<Session> session;
  std::unique_ptr<HttpServer> server;
  std::unique_ptr<httplib::Client> client;

  explicit Fixture(fs::path web_root = {}, std::size_t max_body = 64u << 20,
                   const std::function<void(SessionOptions&, ServerOptions&)>& tune = {}) {
    SessionOptions so;
    so.dir = dir.path();
    so.initial_scene = test::kServeScene;
    ServerOptions ho;
    ho.port = 0;
    ho.web_root = std::move(web_root);
    ho.max_body = max_body;
    if (tune) tune(so, ho);
    session = std::make_unique<Session>(so);
    server = std::make_unique<HttpServer>(*session, ho);
    server->start();
    client = std::make_unique<httplib::Client>("127.0.0.1", server->port());
    client->set_read_timeout(120, 0);
  }
};

// The JSON body of a response, checking its status.
json body(const httplib::Result& r, int status) {
  EXPECT_TRUE(r) << "no response";
  if (!r) return {};
  EXPECT_EQ(r->status, status) << r->body;
  EXPECT_EQ(r->get_header_value("Content-Type"), "application/json; charset=utf-8") << r->body;
  return json::parse(r->body, nullptr, false);
}

TEST(ServeHttp, SceneFrameAnalysisAndEditsOverHttp) {
  Fixture f;
  EXPECT_GT(f.server->port(), 0);
  json scene = body(f.client->Get("/api/scene"), 200);
  EXPECT_EQ(scene["scene"]["time"]["frames"], 21);
  ASSERT_TRUE(f.session->wait_idle(60));
  json frame = body(f.client->Get("/api/frame/20"), 200);
  EXPECT_EQ(frame["frame"], 20);
  EXPECT_EQ(frame["vectors"].size(), 33u * 33u * 3u);
  EXPECT_EQ(body(f.client->Get("/api/status"), 200)["state"], "ready");
  // Sent as it is, even to a browser that accepts Brotli (which took 0.5 s a frame).
  auto plain = f.client->Get("/api/frame/3", httplib::Headers{{"Accept-Encoding", "br, gzip"}});
  ASSERT_TRUE(plain);
  EXPECT_EQ(plain->get_header_value("Content-Encoding"), "");
  // The analysis first (GET waits for it): a frame read before it lists its singularities with
  // path -1, after it with their paths, so the two reads below would differ in the header.
  EXPECT_FALSE(body(f.client->Get("/api/analysis"), 200)["paths"].empty());
  // The binary frame (docs/serve_api.md, "Binary frames"): the session's bytes, as they are.
  auto binary = f.client->Get("/api/frame/3?format=f32", httplib::Headers{{"Accept-Encoding", "br, gzip"}});
  ASSERT_TRUE(binary);
  EXPECT_EQ(binary->status, 200);
  EXPECT_EQ(binary->get_header_value("Content-Type"), "application/octet-stream");
  EXPECT_EQ(binary->get_header_value("Content-Encoding"), "");
  EXPECT_EQ(binary->body, f.session->frame_f32(3));
  EXPECT_EQ(binary->body.size() % 4, 0u);
  EXPECT_LT(binary->body.size(), 33u * 33u * 3u * 4u + 1000u);
  EXPECT_EQ(body(f.client->Get("/api/frame/3?format=json"), 200)["frame"], 3);
  EXPECT_NE(body(f.client->Get("/api/frame/3?format=png"), 400)["error"].get<std::string>().find("format"), std::string::npos);
  EXPECT_EQ(body(f.client->Get("/api/preview?format=f32"), 404)["error"].get<std::string>().substr(0, 8), "preview:");

  scene["scene"]["falloff"] = 15;
  json put = body(f.client->Put("/api/scene", scene["scene"].dump(), "application/json"), 200);
  EXPECT_EQ(put["revision"].get<long long>(), scene["revision"].get<long long>() + 1);
  json edit = body(f.client->Post("/api/edit", R"({"op": "smooth", "strength": 0.3})", "application/json"), 200);
  EXPECT_NE(edit["summary"].get<std::string>(), "");
  EXPECT_EQ(body(f.client->Get("/api/scene"), 200)["scene"]["edits"].size(), 1u);
  EXPECT_EQ(body(f.client->Post("/api/undo", "", "application/json"), 200)["scene"]["edits"].size(), 0u);
  EXPECT_EQ(body(f.client->Post("/api/redo", "", "application/json"), 200)["scene"]["edits"].size(), 1u);
  // The Deform streamline drag's key: on a grid the difference of the two points.
  json tr = body(f.client->Post("/api/seed_translation", R"({"seed": [0.1, 0.2], "to": [-0.3, 0.5]})", "application/json"), 200);
  ASSERT_EQ(tr["translate"].size(), 2u) << tr;
  EXPECT_NEAR(tr["translate"][0].get<double>(), -0.4, 1e-12);
  EXPECT_NEAR(tr["translate"][1].get<double>(), 0.3, 1e-12);
  EXPECT_EQ(f.client->Post("/api/seed_translation", R"({"seed": [0.1, 0.2, 0], "to": [0, 0]})", "application/json")->status,
            400);
  // The Bifurcation drag's chart coordinates: on a grid the difference too.
  json cc = body(f.client->Post("/api/chart_coordinates", R"({"at": [0.1, 0.2], "to": [-0.3, 0.5]})", "application/json"), 200);
  ASSERT_EQ(cc["coords"].size(), 2u) << cc;
  EXPECT_NEAR(cc["coords"][0].get<double>(), -0.4, 1e-12);
  EXPECT_NEAR(cc["coords"][1].get<double>(), 0.3, 1e-12);
  EXPECT_EQ(f.client->Post("/api/chart_coordinates", R"({"seed": [0.1, 0.2], "to": [0, 0]})", "application/json")->status,
            400);

  json exported = body(f.client->Post("/api/export", R"({"dir": "x", "format": "npy"})", "application/json"), 200);
  ASSERT_FALSE(exported["files"].empty());
  auto file = f.client->Get("/api/files/x/times.npy");
  ASSERT_TRUE(file);
  EXPECT_EQ(file->status, 200);
  EXPECT_EQ(file->body.substr(1, 5), "NUMPY");
}

TEST(ServeHttp, MalformedRequestsGetAClearJsonError) {
  Fixture f({}, 4096);
  ASSERT_TRUE(f.session->wait_idle(60));
  auto error_of = [](const httplib::Result& r, int status) {
    return body(r, status).value("error", std::string());
  };
  EXPECT_NE(error_of(f.client->Put("/api/scene", "{\"tvf\": 1,", "application/json"), 400).find("not valid JSON"),
            std::string::npos);
  EXPECT_NE(error_of(f.client->Put("/api/scene", R"({"tvf": 1, "colour": 2})", "application/json"), 400)
                .find("colour"),
            std::string::npos);
  EXPECT_NE(error_of(f.client->Put("/api/scene", "[1, 2]", "application/json"), 400).find("scene object"),
            std::string::npos);
  EXPECT_NE(error_of(f.client->Post("/api/edit", "{\"op\": 1}", "text/plain"), 415).find("application/json"),
            std::string::npos);
  EXPECT_NE(error_of(f.client->Get("/api/nothing"), 404).find("no such"), std::string::npos);
  EXPECT_NE(error_of(f.client->Get("/api/frame/1000000"), 400).find("frame"), std::string::npos);
  EXPECT_NE(error_of(f.client->Post("/api/undo", "", "application/json"), 409).find("nothing to undo"),
            std::string::npos);
  EXPECT_NE(error_of(f.client->Put("/api/scene", std::string(10000, ' '), "application/json"), 413)
                .find("request body too large"),
            std::string::npos);
  // A number beyond double: one sentence naming the key, not the JSON library's text.
  const std::string huge = error_of(
      f.client->Put("/api/scene", R"({"tvf": 1, "time": {"frames": 1e400, "range": [0, 1]}})", "application/json"), 400);
  EXPECT_NE(huge.find("time.frames"), std::string::npos) << huge;
  EXPECT_EQ(huge.find("json.exception"), std::string::npos) << huge;
  const std::string deep = error_of(f.client->Post("/api/edit", R"({"op": "smooth", "strength": [1, [2, 1e999]]})",
                                                   "application/json"),
                                    400);
  EXPECT_NE(deep.find("strength[1][1]"), std::string::npos) << deep;
  // Nesting deeper than 1,000 levels is refused while parsing.
  const std::string nested = error_of(
      f.client->Post("/api/edit", "{\"strength\": " + std::string(1500, '[') + std::string(1500, ']') + "}",
                     "application/json"),
      400);
  EXPECT_NE(nested.find("more than 1000 deep"), std::string::npos) << nested;
  EXPECT_NE(error_of(f.client->Get("/api/files/..%2f..%2fetc%2fpasswd"), 403).find("leaves the working folder"),
            std::string::npos);
  EXPECT_NE(error_of(f.client->Get("/api/files/missing.npy"), 404).find("no such file"), std::string::npos);
  EXPECT_NE(error_of(f.client->Post("/api/upload?name=../x.obj", "v 0 0 0", "application/octet-stream"), 400)
                .find("plain file name"),
            std::string::npos);
  // A page of another site reaching this port through DNS rebinding names its own host.
  httplib::Headers evil{{"Host", "evil.example:80"}};
  EXPECT_EQ(f.client->Get("/api/scene", evil)->status, 403);
  // The server is still up and the scene as it was.
  EXPECT_EQ(body(f.client->Get("/api/scene"), 200)["revision"], 1);
}

// Issue 18: errors carry their place as fields beside the sentence (docs/serve_api.md):
// the file, the JSON path, and the line and column of the value in the request body.
TEST(ServeHttp, ErrorsNameTheirPlaceAsFields) {
  Fixture f;
  ASSERT_TRUE(f.session->wait_idle(60));
  const json bad = body(f.client->Put("/api/scene", "{\"tvf\": 1, \"domain\": {\"grid\": {}},\n \"time\": {\"frames\": -3, \"range\": [0, 1]}}",
                                      "application/json"),
                        400);
  EXPECT_EQ(bad.value("error", std::string()).rfind("scene.json: time.frames: ", 0), 0u) << bad;
  EXPECT_EQ(bad["file"], "scene.json");
  EXPECT_EQ(bad["json_path"], "time.frames");
  EXPECT_EQ(bad["line"], 2);
  EXPECT_EQ(bad["column"], 21);
  // A syntax error has its line and column and no JSON path.
  const json syntax = body(f.client->Put("/api/scene", "{\"tvf\": 1,\n\n  ]", "application/json"), 400);
  EXPECT_EQ(syntax["line"], 3) << syntax;
  EXPECT_EQ(syntax["column"], 3) << syntax;
  EXPECT_FALSE(syntax.contains("json_path")) << syntax;
  // An error without a place has the sentence alone.
  const json none = body(f.client->Post("/api/undo", "", "application/json"), 409);
  EXPECT_FALSE(none.contains("file") || none.contains("json_path") || none.contains("line")) << none;
}

// Issue 17: a request nested 100,000 deep crashed the server (the message printed the value
// recursively); host names compare case-insensitively; seed_translation answered null.
TEST(ServeHttp, HostileBodiesAreRefusedAndTheServerStaysUp) {
  Fixture f;
  ASSERT_TRUE(f.session->wait_idle(60));
  auto error_of = [](const httplib::Result& r, int status) {
    return body(r, status).value("error", std::string());
  };
  const std::string deep = std::string(100'000, '[') + std::string(100'000, ']');
  EXPECT_EQ(error_of(f.client->Put("/api/scene", "{\"tvf\": 1, \"description\": " + deep + "}", "application/json"),
                     400),
            "request body: not valid JSON at line 1, column 1026: arrays and objects nest more than 1000 deep, more "
            "than tvf reads");
  EXPECT_NE(error_of(f.client->Post("/api/edit", "{\"op\": \"smooth\", \"strength\": " + deep + "}", "application/json"),
                     400)
                .find("nest more than 1000 deep"),
            std::string::npos);
  // Within the limit, the value is quoted short.
  const std::string message = error_of(
      f.client->Post("/api/edit", "{\"op\": \"smooth\", \"strength\": " + std::string(900, '[') + std::string(900, ']') + "}",
                     "application/json"),
      400);
  EXPECT_NE(message.find("strength: must be a number, got [[[["), std::string::npos) << message.substr(0, 300);
  EXPECT_LT(message.size(), 400u);
  EXPECT_EQ(error_of(f.client->Post("/api/seed_translation", R"({"seed": [-1e308, 0], "to": [1e308, 0]})",
                                    "application/json"),
                     400),
            "seed_translation: \"seed\" has a coordinate of magnitude over 1e15");
  httplib::Headers upper{{"Host", "LOCALHOST:" + std::to_string(f.server->port())}};
  EXPECT_EQ(f.client->Get("/api/scene", upper)->status, 200);
  EXPECT_EQ(body(f.client->Get("/api/scene"), 200)["revision"], 1);
}

TEST(ServeHttp, ServesTheFrontEndOrSaysItIsMissing) {
  {
    Fixture f;
    auto r = f.client->Get("/");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200);
    EXPECT_NE(r->body.find("front end was not built"), std::string::npos);
  }
  test::TempDir web;
  test::write_text(web / "index.html", "<!doctype html><title>designer</title>");
  Fixture f(web.path());
  auto r = f.client->Get("/");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
  EXPECT_NE(r->body.find("<title>designer</title>"), std::string::npos);
}

// A raw connection to the server (to send what httplib::Client would not: chunked bodies
// that never end, headers one byte at a time). Reads time out after `timeout` seconds.
struct RawClient {
  int fd = -1;
  RawClient(int port, double timeout) {
    fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    timeval tv{static_cast<time_t>(timeout), static_cast<suseconds_t>((timeout - static_cast<time_t>(timeout)) * 1e6)};
    ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    timeval ts{2, 0};
    ::setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &ts, sizeof ts);
  }
  ~RawClient() { ::close(fd); }
  bool send(const std::string& s) { return ::send(fd, s.data(), s.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(s.size()); }
  // What the server sent until it closed the connection or the read timed out; `closed`
  // says which.
  std::string receive(bool* closed = nullptr) {
    std::string out;
    char buf[4096];
    for (;;) {
      const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
      if (n <= 0) {
        if (closed) *closed = n == 0 || errno == ECONNRESET;
        return out;
      }
      out.append(buf, static_cast<size_t>(n));
    }
  }
};

TEST(ServeHttp, ChangesNameTheirRevisionAndAStaleOneIsRefused) {
  Fixture f;
  auto got = f.client->Get("/api/scene");
  ASSERT_TRUE(got);
  const json seen = json::parse(got->body);
  const std::string tag = got->get_header_value("ETag");
  EXPECT_EQ(tag, "\"" + std::to_string(seen["revision"].get<long long>()) + "\"");
  json a = seen["scene"], b = seen["scene"];
  a["falloff"] = 11;
  b["falloff"] = 9;
  auto put = f.client->Put("/api/scene", httplib::Headers{{"If-Match", tag}}, a.dump(), "application/json");
  json after = body(put, 200);
  EXPECT_EQ(put->get_header_value("ETag"), "\"" + std::to_string(after["revision"].get<long long>()) + "\"");
  // The second tab, still on the first revision: refused, and the first tab's change kept.
  const json refused = body(f.client->Put("/api/scene", httplib::Headers{{"If-Match", tag}}, b.dump(), "application/json"), 412);
  EXPECT_NE(refused["error"].get<std::string>().find("another tab"), std::string::npos) << refused;
  EXPECT_EQ(body(f.client->Get("/api/scene"), 200)["scene"]["falloff"], 11);
  EXPECT_EQ(body(f.client->Post("/api/edit", httplib::Headers{{"If-Match", tag}}, R"({"op": "smooth", "strength": 0.3})",
                                "application/json"),
                 412)["error"].get<std::string>().substr(0, 5),
            "edit:");
  EXPECT_EQ(f.client->Post("/api/undo", httplib::Headers{{"If-Match", tag}}, "", "application/json")->status, 412);
  EXPECT_EQ(f.client->Post("/api/undo", httplib::Headers{{"If-Match", "yesterday"}}, "", "application/json")->status, 400);
  // With the current tag the undo goes through.
  EXPECT_EQ(body(f.client->Post("/api/undo", httplib::Headers{{"If-Match", put->get_header_value("ETag")}}, "",
                                "application/json"),
                 200)["scene"]["falloff"],
            20);
}

TEST(ServeHttp, AChunkedBodyIsReadOnlyUpToTheLimit) {
  Fixture f({}, 4096);
  RawClient c(f.server->port(), 4);
  ASSERT_TRUE(c.send("PUT /api/scene HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
                     "Transfer-Encoding: chunked\r\n\r\n"));
  // 8 KiB in chunks, and the body never ends: the answer must come at the limit.
  const std::string chunk = "400\r\n" + std::string(1024, ' ') + "\r\n";
  for (int k = 0; k < 8; ++k) c.send(chunk);
  bool closed = false;
  const std::string answer = c.receive(&closed);
  EXPECT_EQ(answer.substr(0, 12), "HTTP/1.1 413") << answer.substr(0, 200);
  EXPECT_NE(answer.find("request body too large"), std::string::npos) << answer.substr(0, 300);
  EXPECT_TRUE(closed) << "the connection stays open with the rest of the body unread";
  // Other methods and paths too.
  RawClient d(f.server->port(), 4);
  d.send("PATCH /anything HTTP/1.1\r\nHost: 127.0.0.1\r\nTransfer-Encoding: chunked\r\n\r\n");
  for (int k = 0; k < 8; ++k) d.send(chunk);
  EXPECT_EQ(d.receive().substr(0, 12), "HTTP/1.1 413");
  EXPECT_EQ(body(f.client->Get("/api/scene"), 200)["revision"], 1);
}

TEST(ServeHttp, ACompressedBodyIsLimitedOnItsDecodedSize) {
  Fixture f({}, 4096);
  httplib::Client gz("127.0.0.1", f.server->port());
  gz.set_compress(true);  // Content-Encoding: gzip; 100 kB of spaces are ~150 bytes
  const json r = body(gz.Put("/api/scene", std::string(100000, ' '), "application/json"), 413);
  EXPECT_NE(r["error"].get<std::string>().find("after decompression"), std::string::npos) << r;
  // Under the limit, a compressed body is fine.
  json scene = body(f.client->Get("/api/scene"), 200)["scene"];
  scene["falloff"] = 14;
  EXPECT_EQ(body(gz.Put("/api/scene", scene.dump(), "application/json"), 200)["scene"]["falloff"], 14);
}

TEST(ServeHttp, SlowClientsAreCutOffAndStatusAnswersMeanwhile) {
  Fixture f({}, 64u << 20, [](SessionOptions&, ServerOptions& o) {
    o.request_timeout = 1;
    o.threads = 4;
  });
  ASSERT_TRUE(f.session->wait_idle(60));
  // Twice as many clients as workers, each dripping its headers a byte at a time.
  std::atomic<bool> stop{false};
  std::vector<std::future<bool>> drips;
  for (int k = 0; k < 8; ++k)
    drips.push_back(std::async(std::launch::async, [&] {
      RawClient c(f.server->port(), 0.2);
      c.send("GET /api/status HTTP/1.1\r\n");
      for (int i = 0; i < 100 && !stop; ++i) {
        if (!c.send("X")) return true;  // cut off
        bool closed = false;
        c.receive(&closed);
        if (closed) return true;
      }
      return false;  // still connected after 20 s
    }));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  httplib::Client status("127.0.0.1", f.server->port());
  status.set_read_timeout(8, 0);
  status.set_connection_timeout(8, 0);
  EXPECT_EQ(body(status.Get("/api/status"), 200)["state"], "ready");
  for (auto& d : drips) EXPECT_TRUE(d.get());
  stop = true;
}

// The largest resident set this process has had since the last reset (Linux: writing 5 to
// /proc/self/clear_refs resets VmHWM to the current resident set), in bytes.
long long peak_resident() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stoll(line.substr(6)) * 1024;
  return -1;
}
void reset_peak_resident() { std::ofstream("/proc/self/clear_refs") << "5"; }

// Issue 17: a request header line had no limit in bytes (cpp-httplib 0.11 reads a line
// whole before checking it): a 10 MB header line was read into memory. Now the request line
// and headers together are limited (max_head): 431 or closed at once, the server up, its
// memory not growing by the line.
TEST(ServeHttp, AHugeHeaderLineIsRefusedQuicklyWithBoundedMemory) {
  Fixture f;
  ASSERT_TRUE(f.session->wait_idle(60));
  reset_peak_resident();
  const long long before = peak_resident();
  RawClient c(f.server->port(), 5);
  constexpr long long kLine = 64LL << 20;
  const auto start = std::chrono::steady_clock::now();
  // Sent from another thread, 64 KiB at a time (no such string in this process either). The
  // line is 64 MiB, not 10 MB: loopback's socket buffers (tcp_wmem + tcp_rmem, up to ~10 MB)
  // can take 10 MB before a loaded server's worker reads its first bytes and closes.
  auto sender = std::async(std::launch::async, [&] {
    if (!c.send("GET /api/status HTTP/1.1\r\nHost: localhost\r\nX-Big: ")) return 0LL;
    const std::string chunk(64u << 10, 'a');
    long long sent = 0;
    for (; sent < kLine && c.send(chunk); sent += static_cast<long long>(chunk.size())) {
    }
    if (sent >= kLine) c.send("\r\n\r\n");
    return sent;
  });
  bool closed = false;
  const std::string answer = c.receive(&closed);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const long long sent = sender.get();
  EXPECT_TRUE(answer.rfind("HTTP/1.1 431", 0) == 0 || (answer.empty() && closed)) << answer.substr(0, 200);
  EXPECT_LT(seconds, 3.0) << "answered or closed after " << seconds << " s";
  EXPECT_LT(sent, kLine) << "the server took the whole 64 MiB line";
  const long long after = peak_resident();
  if (before > 0 && after > 0) {
    // The peak is the whole process's, so it also holds what the workers' first use costs.
    // Reading the line whole grows it by at least what the server received (a 10 MB line grew
    // it by 17 MB). Without sanitizers the refusal's buffers stay under 8 MiB; AddressSanitizer's
    // allocator (quarantine, per-thread caches, fake stacks) added 4.5 MiB in one run and
    // 10.2 MiB in a loaded CI run (stop 32), so there the bound is 24 MiB — still far below the
    // 64 MiB line, which `sent` above shows the server never took whole.
#if defined(__SANITIZE_ADDRESS__)
    constexpr long long kBound = 24LL << 20;
#else
    constexpr long long kBound = 8LL << 20;
#endif
    EXPECT_LT(after - before, kBound) << "peak resident set grew by " << after - before;
  }
  // Still up, and ordinary headers still pass.
  EXPECT_EQ(body(f.client->Get("/api/status"), 200)["state"], "ready");
  // Under the limit in all passes (cpp-httplib itself refuses one line over 8 KiB with
  // 400, once read); over it is refused with 431.
  for (const int lines : {6, 5 * 8}) {
    RawClient d(f.server->port(), 5);
    std::string head = "GET /api/status HTTP/1.1\r\nHost: localhost\r\n";
    for (int k = 0; k < lines; ++k) head += fmt::format("X-Big-{}: {}\r\n", k, std::string(1000, 'b'));
    d.send(head + "\r\n");
    const std::string got = d.receive();
    EXPECT_EQ(got.substr(0, 12), head.size() < (32u << 10) ? "HTTP/1.1 200" : "HTTP/1.1 431") << head.size();
  }
}

TEST(ServeHttp, StopIsPromptWhileRequestsWaitForAField) {
  Fixture f({}, 64u << 20, [](SessionOptions& s, ServerOptions&) {
    s.parallel = false;
    s.field_wait_seconds = 600;
  });
  ASSERT_TRUE(f.session->wait_idle(60));
  json big = body(f.client->Get("/api/scene"), 200)["scene"];
  big["domain"]["grid"]["size"] = {129, 129};
  big["time"]["frames"] = 400;
  body(f.client->Put("/api/scene", big.dump(), "application/json"), 200);
  // An export waiting for the big field, and an idle keep-alive connection.
  auto waiting = std::async(std::launch::async, [&] {
    httplib::Client c("127.0.0.1", f.server->port());
    c.set_read_timeout(600, 0);
    auto r = c.Post("/api/export", R"({"dir": "x"})", "application/json");
    return r ? r->status : -1;
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  auto stopped = std::async(std::launch::async, [&] { f.server->stop(); });
  ASSERT_EQ(stopped.wait_for(std::chrono::seconds(30)), std::future_status::ready) << "stop() hangs";
  ASSERT_EQ(waiting.wait_for(std::chrono::seconds(5)), std::future_status::ready);
  const int st = waiting.get();
  EXPECT_EQ(st, 503);  // answered, not cut
}

// The `event: status` payloads of a server-sent event stream, in the order they arrive.
struct EventLog {
  std::mutex mutex;
  std::condition_variable arrived;
  std::string text;
  std::vector<json> events;
  bool ended = false;
  void add(const char* data, size_t n) {
    std::lock_guard lock(mutex);
    text.append(data, n);
    for (size_t end; (end = text.find("\n\n")) != std::string::npos; text.erase(0, end + 2)) {
      const std::string block = text.substr(0, end);
      if (block.rfind("event: status\ndata: ", 0) == 0) events.push_back(json::parse(block.substr(20)));
    }
    arrived.notify_all();
  }
  // Waits until an event satisfies `want`; returns it (null after `seconds`).
  json wait_for(const std::function<bool(const json&)>& want, double seconds) {
    std::unique_lock lock(mutex);
    json found;
    arrived.wait_for(lock, std::chrono::duration<double>(seconds), [&] {
      for (const json& e : events)
        if (want(e)) return found = e, true;
      return ended;
    });
    return found;
  }
};

TEST(ServeHttp, EventStreamPushesTheNewRevisionAndItsReadiness) {
  Fixture f;
  ASSERT_TRUE(f.session->wait_idle(60));
  EventLog log;
  std::atomic<bool> quit{false};
  int stream_status = 0;
  std::string type;
  std::thread reader([&] {
    httplib::Client c("127.0.0.1", f.server->port());
    auto r = c.Get(
        "/api/events",
        [&](const httplib::Response& res) {
          stream_status = res.status;
          type = res.get_header_value("Content-Type");
          return true;
        },
        [&](const char* data, size_t n) {
          log.add(data, n);
          return !quit.load();
        });
    std::lock_guard lock(log.mutex);
    log.ended = true;
    log.arrived.notify_all();
  });
  // First the status as it is: revision 1, ready, its field.
  const json first = log.wait_for([](const json&) { return true; }, 20);
  ASSERT_TRUE(first.is_object());
  EXPECT_EQ(stream_status, 200);
  EXPECT_EQ(type, "text/event-stream");
  EXPECT_EQ(first["revision"], 1);
  EXPECT_EQ(first["state"], "ready");
  EXPECT_EQ(first["result_revision"], 1);

  json scene = body(f.client->Get("/api/scene"), 200);
  scene["scene"]["falloff"] = 15;
  auto put = f.client->Put("/api/scene", httplib::Headers{{"If-Match", "\"1\""}}, scene["scene"].dump(),
                           "application/json");
  ASSERT_TRUE(put);
  ASSERT_EQ(put->status, 200) << put->body;
  // Pushed without asking: the new revision, then its field ready.
  const json changed = log.wait_for([](const json& e) { return e["revision"] == 2; }, 20);
  ASSERT_TRUE(changed.is_object());
  const json ready = log.wait_for(
      [](const json& e) { return e["revision"] == 2 && e["state"] == "ready" && e["result_revision"] == 2; }, 60);
  ASSERT_TRUE(ready.is_object()) << "no ready event for revision 2";
  // The field is published before its analysis, so the status moves on after `ready`: the
  // analysis's end is pushed too.
  const json analysed = log.wait_for(
      [](const json& e) { return e["analysis_revision"] == 2 && e["analysis"] == "ready"; }, 60);
  ASSERT_TRUE(analysed.is_object()) << "no event for revision 2's analysis";
  // Nothing is left to change: the status as read now is one the stream pushed.
  const json now = body(f.client->Get("/api/status"), 200);
  EXPECT_EQ(now["analysis_revision"], 2);
  EXPECT_EQ(log.wait_for([&](const json& e) { return e == now; }, 20), now);
  quit = true;
  // The reader stops at the next event or heartbeat; a scene change makes one now.
  (void)f.client->Post("/api/undo", "{}", "application/json");
  reader.join();
}

TEST(ServeHttp, EventStreamsAreLimitedAndStopEndsThemPromptly) {
  Fixture f({}, 64u << 20, [](SessionOptions&, ServerOptions& o) { o.max_streams = 2; });
  std::vector<std::thread> readers;
  std::atomic<int> opened{0};
  for (int k = 0; k < 2; ++k)
    readers.emplace_back([&] {
      httplib::Client c("127.0.0.1", f.server->port());
      c.set_read_timeout(60, 0);
      // Each stream counted once, at its first bytes: a stream that gets two events before
      // the other has connected (seen under ASan) must not count as two.
      bool counted = false;
      (void)c.Get("/api/events", [&](const char*, size_t) {
        if (!counted) opened.fetch_add(1);
        counted = true;
        return true;
      });
    });
  for (int k = 0; k < 200 && opened.load() < 2; ++k) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ASSERT_GE(opened.load(), 2);
  // A third stream is refused with a sentence; plain requests are still answered.
  const json refused = body(f.client->Get("/api/events"), 503);
  EXPECT_NE(refused["error"].get<std::string>().find("the limit is 2"), std::string::npos) << refused;
  EXPECT_EQ(body(f.client->Get("/api/status"), 200)["revision"], 1);
  const auto start = std::chrono::steady_clock::now();
  f.server->stop();
  for (auto& t : readers) t.join();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(seconds, 5.0);  // not the 300 s a stream may last
}

}  // namespace
}  // namespace tvf::serve
