// The designer's Lagrangian overlays over HTTP (session_lcs.cpp): GET /api/ftle and
// POST /api/streakline, /api/timeline give the library's FTLE and curves of the session's
// field (checked against compute_ftle_at and trace_streakline on the exported field), and
// refuse bad parameters with one sentence naming them.
#include "tvf/serve/http_server.h"

#include "tvf/field/field_io.h"
#include "tvf/integrate/ftle.h"
#include "tvf/integrate/streakline.h"
#include "tvf/mesh/tangent_bundle.h"

#include "support/test_paths.h"
#include "test_scene.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <httplib.h>

#include <cmath>

namespace tvf::serve {
namespace {

using nlohmann::json;

struct Served {
  test::TempDir dir;
  std::unique_ptr<Session> session;
  std::unique_ptr<HttpServer> server;
  std::unique_ptr<httplib::Client> client;
  Served() {
    SessionOptions so;
    so.dir = dir.path();
    so.initial_scene = test::kServeScene;  // 33² grid on [−1, 1]², 21 frames on [0, 1]
    ServerOptions ho;
    ho.port = 0;
    session = std::make_unique<Session>(so);
    server = std::make_unique<HttpServer>(*session, ho);
    server->start();
    client = std::make_unique<httplib::Client>("127.0.0.1", server->port());
    client->set_read_timeout(120, 0);
  }
  json get(const std::string& path, int status) const {
    auto r = client->Get(path);
    EXPECT_TRUE(r) << path;
    if (!r) return {};
    EXPECT_EQ(r->status, status) << path << ": " << r->body;
    return json::parse(r->body, nullptr, false);
  }
  json post(const std::string& path, const json& body, int status) const {
    auto r = client->Post(path, body.dump(), "application/json");
    EXPECT_TRUE(r) << path;
    if (!r) return {};
    EXPECT_EQ(r->status, status) << path << " " << body << ": " << r->body;
    return json::parse(r->body, nullptr, false);
  }
  // The session's field, as `tvf generate` would write it.
  FieldFile field() const {
    post("/api/export", {{"dir", "x"}, {"format", "npy"}}, 200);
    return load_field_file((dir.path() / "x" / "field.tvff").string());
  }
};

TEST(ServeLcs, FtleIsTheLibrarysOfTheSessionsField) {
  Served s;
  ASSERT_TRUE(s.session->wait_idle(60));
  // Before a field exists: 409 would be answered; here it exists.
  const FieldFile f = s.field();
  const TangentBundle bundle(f.mesh);
  for (const char* dir : {"forward", "backward"}) {
    const json a = s.get(fmt::format("/api/ftle?t=0.5&horizon=0.25&direction={}", dir), 200);
    EXPECT_EQ(a["direction"], dir);
    EXPECT_DOUBLE_EQ(a["span"].get<double>(), 0.25);
    EXPECT_FALSE(a["cut"].get<bool>());
    const FtleSlice want = compute_ftle_at(bundle, f.field, 0.5, 0.25, dir == std::string("forward") ? 1 : -1);
    ASSERT_EQ(a["values"].size(), want.values.size());
    int defined = 0;
    for (size_t v = 0; v < want.values.size(); ++v) {
      if (std::isnan(want.values[v])) {
        EXPECT_TRUE(a["values"][v].is_null()) << v;
        continue;
      }
      ++defined;
      ASSERT_TRUE(a["values"][v].is_number()) << v;
      EXPECT_NEAR(a["values"][v].get<double>(), want.values[v], 1e-5) << v;  // 5 decimals
    }
    EXPECT_GT(defined, 900);
    EXPECT_LE(a["range"][0].get<double>(), a["range"][1].get<double>());
    EXPECT_LE(a["min"].get<double>(), a["range"][0].get<double>());
    EXPECT_GE(a["max"].get<double>(), a["range"][1].get<double>());
  }
  // Past the range's end: cut, divided by the time integrated.
  const json cut = s.get("/api/ftle?t=0.9&horizon=0.25", 200);
  EXPECT_TRUE(cut["cut"].get<bool>());
  EXPECT_NEAR(cut["span"].get<double>(), 0.1, 1e-12);
  EXPECT_EQ(cut["direction"], "forward");
}

TEST(ServeLcs, FtleRefusesBadParametersNamingThem) {
  Served s;
  ASSERT_TRUE(s.session->wait_idle(60));
  auto error = [&](const std::string& query) { return s.get("/api/ftle?" + query, 400)["error"].get<std::string>(); };
  EXPECT_EQ(error("horizon=0.2"), "ftle: \"t\" must be a number");
  EXPECT_EQ(error("t=abc&horizon=0.2"), "ftle: \"t\" must be a number");
  EXPECT_EQ(error("t=2&horizon=0.2"), "ftle: \"t\" = 2 is outside the field's time range [0, 1]");
  EXPECT_EQ(error("t=0.5&horizon=-1"), "ftle: \"horizon\" = -1 must be positive and at most the field's time span 1");
  EXPECT_EQ(error("t=0.5&horizon=3"), "ftle: \"horizon\" = 3 must be positive and at most the field's time span 1");
  EXPECT_EQ(error("t=0.5&horizon=nan"), "ftle: \"horizon\" is not finite");
  EXPECT_EQ(error("t=0.5&horizon=0.2&direction=sideways"), "ftle: \"direction\" must be \"forward\" or \"backward\"");
}

TEST(ServeLcs, StreaklinesAndTimelinesAreTheLibrarys) {
  Served s;
  ASSERT_TRUE(s.session->wait_idle(60));
  const FieldFile f = s.field();
  const TangentBundle bundle(f.mesh);
  const json a = s.post("/api/streakline", {{"seed", {0.5, 0.5}}, {"from", 0.0}, {"to", 0.8}, {"spacing", 0.01}}, 200);
  StreaklineOptions o;
  o.t0 = 0;
  o.t1 = 0.8;
  o.release_spacing = 0.01;
  const Streakline want = trace_streakline(bundle, f.field, Vec3(0.5, 0.5, 0), o);
  EXPECT_EQ(a["released"].get<int>(), want.released);
  EXPECT_EQ(a["left"].get<int>(), want.left);
  EXPECT_EQ(a["resolution"].get<double>(), want.resolution);
  EXPECT_EQ(a["largest_gap"].get<double>(), want.largest_gap);
  EXPECT_EQ(a["unresolved"].get<int>(), want.unresolved);
  EXPECT_TRUE(a["unresolved_by"].is_null());
  ASSERT_EQ(a["points"].size(), want.points.size());
  ASSERT_GT(want.points.size(), 50u);
  for (size_t i = 0; i < want.points.size(); ++i) {
    ASSERT_EQ(a["points"][i].size(), 2u);
    EXPECT_NEAR(a["points"][i][0].get<double>(), want.points[i].position.x(), 1e-12);
    EXPECT_NEAR(a["points"][i][1].get<double>(), want.points[i].position.y(), 1e-12);
  }
  // The newest dye is at the seed.
  EXPECT_NEAR(a["points"].back()[0].get<double>(), 0.5, 1e-9);
  EXPECT_NEAR(a["points"].back()[1].get<double>(), 0.5, 1e-9);
  EXPECT_DOUBLE_EQ(a["t"].get<double>(), 0.8);
  // The time the trace took, read after it: 50 and more particles each traced over frames
  // take more than a microsecond (the clock was once read before the trace: 26 ns).
  EXPECT_GT(a["seconds"].get<double>(), 1e-6);

  const json line = s.post("/api/timeline", {{"line", {{-0.5, 0.5}, {0.5, 0.5}}}, {"from", 0.0}, {"to", 0.5}}, 200);
  EXPECT_GE(line["points"].size(), 100u);
  EXPECT_DOUBLE_EQ(line["t"].get<double>(), 0.5);
  EXPECT_EQ(line["unresolved"].get<int>(), 0);
  EXPECT_TRUE(line["unresolved_by"].is_null());
  EXPECT_LE(line["largest_gap"].get<double>(), line["resolution"].get<double>());
  EXPECT_GT(line["seconds"].get<double>(), 1e-6);

  auto error = [&](const char* path, const json& body, int status = 400) {
    return s.post(path, body, status)["error"].get<std::string>();
  };
  EXPECT_EQ(error("/api/streakline", {{"seed", {0.5, 0.5, 0}}, {"from", 0}, {"to", 1}}),
            "streakline: \"seed\" must be a position of 2 numbers on this grid");
  EXPECT_EQ(error("/api/streakline", {{"seed", {0.5, 0.5}}, {"from", 0.6}, {"to", 0.5}}),
            "streakline: \"from\" = 0.6 is after \"to\" = 0.5");
  EXPECT_EQ(error("/api/streakline", {{"seed", {0.5, 0.5}}, {"from", 0}, {"to", 1}, {"spacing", 1e-6}}),
            "streakline: (to − from)/spacing = 1000000 releases, more than 20000");
  EXPECT_EQ(error("/api/streakline", {{"seed", {0.5, 0.5}}, {"to", 1}}), "streakline: \"from\" must be a number");
  EXPECT_NE(error("/api/streakline", {{"seed", {5, 5}}, {"from", 0}, {"to", 1}}, 422).find("streakline: "),
            std::string::npos);
  EXPECT_EQ(error("/api/timeline", {{"line", {{0, 0}}}, {"from", 0}, {"to", 1}}),
            "timeline: \"line\" must be two positions [a, b]");
  EXPECT_EQ(error("/api/timeline", {{"line", {{0, 0}, {0.5, 0}}}, {"from", 0}, {"to", 1}, {"count", 1}}),
            "timeline: \"count\" must be a whole number of particles in [2, 2000]");
  EXPECT_NE(error("/api/timeline", {{"line", {{0.2, 0.2}, {0.2, 0.2}}}, {"from", 0}, {"to", 1}}, 422)
                .find("timeline: the timeline's ends (0.2, 0.2) and (0.2, 0.2) are one point of the domain"),
            std::string::npos);
}

}  // namespace
}  // namespace tvf::serve
