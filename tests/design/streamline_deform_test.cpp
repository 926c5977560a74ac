// Streamline deformation on the sphere (paper §7, Fig. 12): the representative streamline
// is moved in the log-map chart around its seed, and each frame's constrained solve follows
// its tangents.
#include "tvf/design/streamline_deform.h"

#include "tvf/core/error.h"
#include "tvf/design/generate.h"
#include "tvf/scene/scene_json.h"
#include "tvf/field/field_sampler.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>

namespace tvf {
namespace {

// Unit icosphere (2,562 vertices); a storm (counter-clockwise centre) at the north pole;
// the streamline seeded 0.3 rad from it, on the x side.
Scene sphere_scene(const std::string& keys) {
  return parse_scene(R"({"tvf": 1, "domain": {"sphere": {"subdivisions": 4, "radius": 1}}, "time": {"frames": 6},
    "generator": "deform", "falloff": 10, "solver": {"region_radius": 0.15},
    "deform": {"base": {"elements": [{"kind": "singular", "type": "ccw_center", "path": [[0, 0, 1, 0]]}]}, )" +
                         keys + "}}",
                     "deform.json");
}
const std::string kStreamline = R"("streamlines": [{"seed": [0.29552020666133955, 0, 0.955336489125606], "keys": )";

double angle_between(const Vec3& a, const Vec3& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0));
}

// The base field V(t0) of a deform scene (the deform generator without streamlines).
std::vector<cplx> base_field(const DesignSpace& space, const Scene& scene) {
  nlohmann::json j = scene_to_json(scene);
  j["deform"].erase("streamlines");
  const Field f = generate(space, scene_from_json(j, "plain.json"));
  return std::vector<cplx>(f.frame(0).begin(), f.frame(0).end());
}

TEST(StreamlineDeformation, RotationOnTheSphereKeepsGeodesicDistancesFromTheSeed) {
  const Scene s = sphere_scene(kStreamline + R"([{"t": 1, "rotate": 1.0}]}])");
  const auto space = make_design_space(s);
  const std::vector<cplx> base = base_field(*space, s);
  const StreamlineDeformation deformation(*space, s, base);
  ASSERT_EQ(deformation.size(), 1u);
  const MovedStreamline a = deformation.at(0.0)[0], b = deformation.at(1.0)[0];
  ASSERT_EQ(a.points.size(), b.points.size());
  ASSERT_GT(a.points.size(), 20u);
  const double h = space->mesh().mean_edge_length();
  const Vec3 seed = a.points[a.seed].normalized();
  EXPECT_LT((b.points[b.seed] - a.points[a.seed]).norm(), 1e-6);
  // The streamline of a centre at the pole is a circle of latitude through the seed: its
  // points lie 0.3 rad from the pole, and it closes round it.
  for (const Vec3& p : a.points) EXPECT_NEAR(angle_between(p, Vec3(0, 0, 1)), 0.3, h);
  // Turned by 1 rad about the seed: every point keeps its geodesic distance from the seed
  // (the log map's distance is accurate to about an edge), and the turn seen from the seed
  // is 1 rad (counter-clockwise about the outward normal).
  double worst_r = 0, worst_turn = 0;
  for (size_t q = 0; q < a.points.size(); ++q) {
    const double ra = angle_between(a.points[q], seed), rb = angle_between(b.points[q], seed);
    worst_r = std::max(worst_r, std::abs(ra - rb));
    if (ra < 0.1) continue;  // directions are ill-defined next to the seed
    const Vec3 ua = (a.points[q].normalized() - seed.dot(a.points[q].normalized()) * seed).normalized();
    const Vec3 ub = (b.points[q].normalized() - seed.dot(b.points[q].normalized()) * seed).normalized();
    const double turn = std::atan2(seed.dot(ua.cross(ub)), ua.dot(ub));
    worst_turn = std::max(worst_turn, std::abs(turn - 1.0));
  }
  EXPECT_LT(worst_r, h) << worst_r;
  EXPECT_LT(worst_turn, 0.1) << worst_turn;
}

TEST(StreamlineDeformation, TranslationOnTheSphereMovesTheSeedAlongAGeodesic) {
  // 0.4 towards +y (a tangent vector at the seed): the moved seed lies 0.4 rad away, due
  // "east" of it on the great circle through the seed in that direction.
  const Scene s = sphere_scene(kStreamline + R"([{"t": 1, "translate": [0, 0.4, 0]}]}])");
  const auto space = make_design_space(s);
  const StreamlineDeformation deformation(*space, s, base_field(*space, s));
  const MovedStreamline a = deformation.at(0.0)[0], b = deformation.at(1.0)[0], half = deformation.at(0.5)[0];
  const Vec3 seed = a.points[a.seed].normalized(), moved = b.points[b.seed].normalized();
  const double h = space->mesh().mean_edge_length();
  EXPECT_NEAR(angle_between(seed, moved), 0.4, h);
  EXPECT_NEAR(angle_between(seed, half.points[half.seed]), 0.2, h);
  const Vec3 great = (moved - seed.dot(moved) * seed).normalized();  // its direction at the seed
  EXPECT_LT(angle_between(great, Vec3(0, 1, 0)), 0.05);
}

TEST(StreamlineDeformation, SeedTranslationGivesTheKeyThatCarriesTheSeedToAPoint) {
  // The designer's drag on the sphere: from the seed to a point 0.35 rad away towards the
  // south-east; the key with the translate it gets puts the moved seed there.
  const Scene plain = sphere_scene(kStreamline + R"([{"t": 1}]}])");
  const auto space = make_design_space(plain);
  const Vec3 seed(0.29552020666133955, 0, 0.955336489125606);
  const Vec3 to = Vec3(0.55, 0.2, 0.8).normalized();
  const Vec3 translate = seed_translation(*space, seed, to);
  EXPECT_NEAR(translate.dot(seed), 0.0, 0.05);  // a tangent vector at the seed ...
  EXPECT_NEAR(translate.norm(), angle_between(seed, to), space->mesh().mean_edge_length());  // ... as long as the geodesic
  const Scene s = sphere_scene(kStreamline + fmt::format(R"([{{"t": 1, "translate": [{}, {}, {}]}}]}}])", translate.x(),
                                                         translate.y(), translate.z()));
  const StreamlineDeformation deformation(*space, s, base_field(*space, s));
  const MovedStreamline b = deformation.at(1.0)[0];
  EXPECT_LT((b.points[b.seed] - to).norm(), 0.25 * space->mesh().mean_edge_length()) << b.points[b.seed].transpose();
  // The antipode is beyond the chart.
  EXPECT_THROW(seed_translation(*space, seed, -seed), Error);
  // Planar domains: the difference.
  const Scene grid = parse_scene(R"({"tvf": 1, "domain": {"grid": {"size": [9, 9], "min": [-1, -1], "max": [1, 1]}}})",
                                 "grid.json");
  const auto flat = make_design_space(grid);
  EXPECT_LT((seed_translation(*flat, Vec3(0.1, 0.2, 0), Vec3(-0.3, 0.5, 0)) - Vec3(-0.4, 0.3, 0)).norm(), 1e-12);
}

// The designer's Bifurcation drag on a surface: angle = arg and scale = modulus of the
// chart coordinates of the drag's end around its start. A saddle–sink creation so placed
// has its axis along the geodesic towards the drag's end: one time scale after t0 its
// template is (1 − x², −y), so at its place the field runs along +axis (and with the
// opposite angle, against it).
TEST(StreamlineDeformation, ChartCoordinatesGiveABifurcationsAxisOnTheSphere) {
  const Scene plain = sphere_scene(kStreamline + R"([{"t": 1}]}])");
  const auto space = make_design_space(plain);
  const double h = space->mesh().mean_edge_length();
  const Vec3 at = Vec3(0.3, -0.8, 0.5).normalized();
  const Vec3 to = Vec3(0.55, -0.75, 0.3).normalized();
  const cplx w = chart_coordinates(*space, at, to);
  EXPECT_NEAR(std::abs(w), angle_between(at, to), h);  // the geodesic distance
  // Its direction, as a world vector in at's face, is the great circle's towards `to`.
  const Vec3 towards = (to - at.dot(to) * at).normalized();
  const Vec3 axis = space->bundle().face_to_world(space->locate(at).face, w / std::abs(w));
  EXPECT_GT(axis.dot(towards), 0.99);
  // The nearest vertex to `at`.
  int near = 0;
  for (int v = 0; v < space->mesh().num_vertices(); ++v)
    if ((space->mesh().position(v) - at).norm() < (space->mesh().position(near) - at).norm()) near = v;
  for (const double sign : {1.0, -1.0}) {
    const double angle = std::arg(w) + (sign > 0 ? 0.0 : 3.141592653589793);
    const Scene s = parse_scene(fmt::format(R"({{"tvf": 1, "domain": {{"sphere": {{"subdivisions": 4, "radius": 1}}}},
      "time": {{"frames": 2, "range": [0, 1]}}, "generator": "basis", "falloff": 10,
      "elements": [{{"kind": "bifurcation", "type": "saddle_sink_creation", "at": [{}, {}, {}, 0], "scale": {},
                    "time_scale": 1, "angle": {}}}]}})",
                                            at.x(), at.y(), at.z(), std::abs(w), angle),
                                "bifurcation.json");
    const Field f = generate(*space, s);
    const Vec3 v = space->bundle().vertex_to_world(near, f.frame(1)[static_cast<size_t>(near)]);
    EXPECT_GT(sign * v.normalized().dot(towards), 0.95) << "sign " << sign;
  }
  // Planar domains: the difference; beyond the chart: an error naming both points.
  const Scene grid = parse_scene(R"({"tvf": 1, "domain": {"grid": {"size": [9, 9], "min": [-1, -1], "max": [1, 1]}}})",
                                 "grid.json");
  EXPECT_LT(std::abs(chart_coordinates(*make_design_space(grid), Vec3(0.1, 0.2, 0), Vec3(-0.3, 0.5, 0)) - cplx(-0.4, 0.3)),
            1e-12);
  try {
    chart_coordinates(*space, at, -at);
    ADD_FAILURE() << "the antipode is beyond the chart";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("is too far from ("), std::string::npos) << e.what();
  }
}

TEST(StreamlineDeformation, TheFieldFollowsTheMovedStreamlineAndStartsFromTheBase) {
  const Scene s = sphere_scene(kStreamline + R"([{"t": 1, "translate": [0, 0.3, 0], "rotate": 0.6, "scale": 1.2}]}])");
  const auto space = make_design_space(s);
  const std::vector<cplx> base = base_field(*space, s);
  GenerateReport report;
  const Field f = generate(*space, s, {}, &report);
  EXPECT_NE(report.method.find("streamline"), std::string::npos);
  // t0 reproduces the base field: the streamline is where it was traced, its tangents are
  // V(t0)'s own, up to the discretisation of the polyline.
  double diff = 0, norm = 0;
  for (int v = 0; v < space->mesh().num_vertices(); ++v) {
    diff += std::norm(f.at(0, v) - base[static_cast<size_t>(v)]);
    norm += std::norm(base[static_cast<size_t>(v)]);
  }
  const double initial = std::sqrt(diff / norm);
  EXPECT_LT(initial, 0.2);
  // At every frame the field is tangent to the moved streamline: at its points (sampled
  // inside the faces) and at the constrained vertices (the corners of the faces it crosses).
  const StreamlineDeformation deformation(*space, s, base);
  const FieldSampler sampler(space->bundle(), f);
  double later = 0;
  for (int j = 0; j < s.time.frames; ++j) {
    const double t = s.time.time(j);
    const MovedStreamline m = deformation.at(t)[0];
    double sum = 0, worst = 0;
    int count = 0;
    for (size_t q = 1; q + 1 < m.points.size(); ++q) {
      const Vec3 tangent = m.points[q + 1] - m.points[q - 1];
      const SurfacePoint p = space->locate(m.points[q]);
      const double a = angle_between(sampler.world(p, t), tangent);
      sum += a;
      worst = std::max(worst, a);
      ++count;
      for (int c : space->mesh().face(p.face)) {
        const Vec3 at_vertex = space->bundle().vertex_to_world(c, f.at(j, c));
        worst = std::max(worst, angle_between(at_vertex, tangent));
      }
    }
    EXPECT_LT(sum / count, 0.05) << "frame " << j;
    EXPECT_LT(worst, 0.35) << "frame " << j;
    if (j == s.time.frames - 1)
      for (int v = 0; v < space->mesh().num_vertices(); ++v) later += std::norm(f.at(j, v) - base[static_cast<size_t>(v)]);
  }
  // Once moved, the field differs much more from the base.
  EXPECT_GT(std::sqrt(later / norm), 2 * initial);
}

TEST(StreamlineDeformation, AStreamlineMovedOutOfItsChartIsAnError) {
  const Scene s = sphere_scene(kStreamline + R"([{"t": 1, "translate": [0, 2.5, 0]}]}])");
  const auto space = make_design_space(s);
  std::string message;
  try {
    generate(*space, s);
  } catch (const Error& e) {
    message = e.what();
  }
  EXPECT_NE(message.find("deform.streamlines[0].keys: at t = "), std::string::npos) << message;
  EXPECT_NE(message.find("leaves the disc"), std::string::npos) << message;
}

}  // namespace
}  // namespace tvf
