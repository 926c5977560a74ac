// The designer's HTTP API (tvf/serve/http_server.h) through httplib::Client on an
// ephemeral port: JSON in and out, clear 4xx errors for malformed requests, the limits.
#include "tvf/serve/http_server.h"

#include "support/test_paths.h"
#include "test_scene.h"

#include <gtest/gtest.h>
#include <httplib.h>

namespace tvf::serve {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

struct Fixture {
  test::TempDir dir;
  std::unique_ptr<Session> session;
  std::unique_ptr<HttpServer> server;
  std::unique_ptr<httplib::Client> client;

  explicit Fixture(fs::path web_root = {}, std::size_t max_body = 64u << 20) {
    SessionOptions so;
    so.dir = dir.path();
    so.initial_scene = test::kServeScene;
    session = std::make_unique<Session>(so);
    ServerOptions ho;
    ho.port = 0;
    ho.web_root = std::move(web_root);
    ho.max_body = max_body;
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
  EXPECT_FALSE(body(f.client->Get("/api/analysis"), 200)["paths"].empty());

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
  EXPECT_EQ(error_of(f.client->Put("/api/scene", std::string(10000, ' '), "application/json"), 413),
            "request body too large");
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

}  // namespace
}  // namespace tvf::serve
