#include "tvf/scene/scene_json.h"

#include "tvf/core/error.h"
#include "tvf/core/error_location.h"
#include "support/test_paths.h"

#include <fmt/format.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>

namespace tvf {
namespace {

using json = nlohmann::json;

// --- exact comparison of two scenes, member by member

void expect_same_path(const std::vector<PathPoint>& a, const std::vector<PathPoint>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].position, b[i].position) << "point " << i;
    EXPECT_EQ(a[i].t, b[i].t) << "point " << i;
  }
}

void expect_same_transform(const std::vector<TransformKey>& a, const std::vector<TransformKey>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].t, b[i].t);
    EXPECT_EQ(a[i].sx, b[i].sx);
    EXPECT_EQ(a[i].sy, b[i].sy);
    EXPECT_EQ(a[i].theta, b[i].theta);
  }
}

void expect_same_element(const Element& a, const Element& b) {
  ASSERT_EQ(a.index(), b.index());
  if (const auto* s = std::get_if<SingularElement>(&a)) {
    const auto& t = std::get<SingularElement>(b);
    EXPECT_EQ(s->type, t.type);
    EXPECT_EQ(s->jacobian, t.jacobian);
    expect_same_path(s->path, t.path);
    expect_same_transform(s->transform, t.transform);
  } else if (const auto* r = std::get_if<RegularElement>(&a)) {
    const auto& q = std::get<RegularElement>(b);
    expect_same_path(r->pathline, q.pathline);
    EXPECT_EQ(r->attach, q.attach);
  } else if (const auto* l = std::get_if<StreaklineElement>(&a)) {
    const auto& m = std::get<StreaklineElement>(b);
    EXPECT_EQ(l->points, m.points);
    EXPECT_EQ(l->t, m.t);
    EXPECT_EQ(l->from, m.from);
    EXPECT_EQ(l->attach, m.attach);
  } else {
    const auto& x = std::get<BifurcationElement>(a);
    const auto& y = std::get<BifurcationElement>(b);
    EXPECT_EQ(x.type, y.type);
    EXPECT_EQ(x.at.position, y.at.position);
    EXPECT_EQ(x.at.t, y.at.t);
    EXPECT_EQ(x.scale, y.scale);
    EXPECT_EQ(x.time_scale, y.time_scale);
    EXPECT_EQ(x.angle, y.angle);
  }
}

void expect_same_scene(const Scene& a, const Scene& b) {
  EXPECT_EQ(a.version, b.version);
  EXPECT_EQ(a.description, b.description);
  ASSERT_EQ(a.domain.grid.has_value(), b.domain.grid.has_value());
  if (a.domain.grid) {
    EXPECT_EQ(a.domain.grid->nx, b.domain.grid->nx);
    EXPECT_EQ(a.domain.grid->ny, b.domain.grid->ny);
    EXPECT_EQ(a.domain.grid->min, b.domain.grid->min);
    EXPECT_EQ(a.domain.grid->max, b.domain.grid->max);
  }
  EXPECT_EQ(a.domain.mesh, b.domain.mesh);
  ASSERT_EQ(a.domain.sphere.has_value(), b.domain.sphere.has_value());
  if (a.domain.sphere) {
    EXPECT_EQ(a.domain.sphere->subdivisions, b.domain.sphere->subdivisions);
    EXPECT_EQ(a.domain.sphere->radius, b.domain.sphere->radius);
  }
  ASSERT_EQ(a.domain.torus.has_value(), b.domain.torus.has_value());
  if (a.domain.torus) {
    EXPECT_EQ(a.domain.torus->nu, b.domain.torus->nu);
    EXPECT_EQ(a.domain.torus->nv, b.domain.torus->nv);
    EXPECT_EQ(a.domain.torus->major_radius, b.domain.torus->major_radius);
    EXPECT_EQ(a.domain.torus->minor_radius, b.domain.torus->minor_radius);
  }
  EXPECT_EQ(a.time.t0, b.time.t0);
  EXPECT_EQ(a.time.t1, b.time.t1);
  EXPECT_EQ(a.time.frames, b.time.frames);
  EXPECT_EQ(a.generator, b.generator);
  EXPECT_EQ(a.solver.weights, b.solver.weights);
  EXPECT_EQ(a.solver.method, b.solver.method);
  EXPECT_EQ(a.solver.temporal_weight, b.solver.temporal_weight);
  EXPECT_EQ(a.solver.tolerance, b.solver.tolerance);
  EXPECT_EQ(a.solver.region_radius, b.solver.region_radius);
  EXPECT_EQ(a.falloff, b.falloff);
  ASSERT_EQ(a.elements.size(), b.elements.size());
  for (size_t i = 0; i < a.elements.size(); ++i) {
    SCOPED_TRACE("element " + std::to_string(i));
    expect_same_element(a.elements[i], b.elements[i]);
  }
  ASSERT_EQ(a.keyframes.size(), b.keyframes.size());
  for (size_t i = 0; i < a.keyframes.size(); ++i) {
    SCOPED_TRACE("key frame " + std::to_string(i));
    const Keyframe& x = a.keyframes[i];
    const Keyframe& y = b.keyframes[i];
    EXPECT_EQ(x.t, y.t);
    EXPECT_EQ(x.field, y.field);
    ASSERT_EQ(x.elements.size(), y.elements.size());
    for (size_t k = 0; k < x.elements.size(); ++k) {
      EXPECT_EQ(x.elements[k].kind, y.elements[k].kind);
      EXPECT_EQ(x.elements[k].type, y.elements[k].type);
      EXPECT_EQ(x.elements[k].jacobian, y.elements[k].jacobian);
      EXPECT_EQ(x.elements[k].at, y.elements[k].at);
      EXPECT_EQ(x.elements[k].vector, y.elements[k].vector);
    }
    ASSERT_EQ(x.streamlines.size(), y.streamlines.size());
    for (size_t k = 0; k < x.streamlines.size(); ++k) {
      EXPECT_EQ(x.streamlines[k].points, y.streamlines[k].points);
      EXPECT_EQ(x.streamlines[k].speed, y.streamlines[k].speed);
    }
  }
  const json ja = scene_to_json(a), jb = scene_to_json(b);
  EXPECT_EQ(a.deform.has_value(), b.deform.has_value());
  EXPECT_EQ(ja.value("deform", json()), jb.value("deform", json()));
  EXPECT_EQ(a.edits.size(), b.edits.size());
  EXPECT_EQ(ja["edits"], jb["edits"]);
  EXPECT_EQ(a.incompressible, b.incompressible);
  EXPECT_EQ(a.source_path, b.source_path);
}

// Parses, writes the canonical JSON, parses that again: both scenes must be equal, and so
// must the JSON and the text written from them.
void expect_round_trip(const Scene& s) {
  const json j = scene_to_json(s);
  const Scene back = scene_from_json(j, "round trip", s.source_path);
  expect_same_scene(s, back);
  EXPECT_EQ(scene_to_json(back), j);
  Scene from_text = parse_scene(scene_to_text(s), "round trip text");
  from_text.source_path = s.source_path;
  expect_same_scene(s, from_text);
  EXPECT_EQ(scene_to_text(from_text), scene_to_text(s));
}

// DESIGN §10's example, made valid: the deform block gives only transform keys (not both
// matrix and transform) and a real base element.
const char* kDesignExample = R"({
  "tvf": 1,
  "description": "DESIGN §10 example",
  "domain": {"grid": {"size": [65, 65], "min": [-1, -1], "max": [1, 1]}},
  "time": {"frames": 100, "range": [0, 1]},
  "generator": "basis",
  "solver": {"weights": "cotan", "temporal_weight": 30, "tolerance": 1e-10,
             "region_radius": 0.1},
  "falloff": 8.0,
  "elements": [
    {"kind": "singular", "type": "ccw_center",
     "path": [[-0.5, 0, 0], [0.5, 0, 1]],
     "transform": [{"t": 0, "sx": 1, "sy": 1, "theta": 0}]},
    {"kind": "singular", "jacobian": [[1, 0.5], [0, -1]], "path": [[0, 0, 0]]},
    {"kind": "bifurcation", "type": "saddle_sink_creation", "at": [0, 0.4, 0.5],
     "scale": 0.3, "time_scale": 0.2, "angle": 0},
    {"kind": "regular", "pathline": [[-1, -0.6, 0], [0, -0.4, 0.5], [1, -0.6, 1]],
     "attach": 2.0}
  ],
  "keyframes": [
    {"t": 0.0, "elements": [{"kind": "singular", "type": "source", "at": [0, 0]}]},
    {"t": 1.0, "streamlines": [{"points": [[-1, 0], [0, 0.3], [1, 0]]}]}
  ],
  "deform": {"base": {"elements": [{"kind": "singular", "type": "saddle", "path": [[0, 0, 0]]}]},
             "transform": [{"t": 0, "sx": 1, "sy": 1, "theta": 0},
                           {"t": 1, "sx": 1, "sy": 1, "theta": 3.14159}],
             "streamlines": [{"seed": [0, 0],
                              "keys": [{"t": 1, "translate": [0.2, 0], "rotate": 0.5, "scale": 1}]}]},
  "edits": [{"op": "cancel", "frame": 40, "pair": [[0.1, 0.2], [0.15, 0.22]]},
            {"op": "smooth", "strength": 0.5}]
})";

// A surface scene using every part of the format with [x, y, z] positions.
const char* kSphereScene = R"({
  "tvf": 1,
  "domain": {"sphere": {"subdivisions": 3, "radius": 2}},
  "time": {"frames": 20, "range": [-1, 3]},
  "generator": "spacetime",
  "solver": {"weights": "mean_value", "temporal_weight": 0, "tolerance": 0.001, "region_radius": 0.3},
  "falloff": 12.5,
  "elements": [
    {"kind": "singular", "type": "repelling_focus", "path": [[2, 0, 0, -1], [0, 2, 0, 3]],
     "transform": [{"t": 0, "sx": 2, "sy": 0.5, "theta": 1}, {"t": 2, "theta": -1}]},
    {"kind": "singular", "jacobian": [[0.25, -2], [3, 0]], "path": [[0, 0, 2, 1]]},
    {"kind": "regular", "pathline": [[0, 0, -2, -1], [0, 2, 0, 3]]},
    {"kind": "bifurcation", "type": "saddle_source_creation", "at": [0, -2, 0, 0.5]}
  ],
  "keyframes": [
    {"t": -1, "elements": [{"kind": "singular", "jacobian": [[1, 2], [3, 4]], "at": [0, 0, 2]},
                           {"kind": "regular", "at": [2, 0, 0], "vector": [0, 1, 0]}],
              "streamlines": [{"points": [[2, 0, 0], [0, 2, 0]], "speed": 2.5}]},
    {"t": 3, "field": "fields/end.tvff"}
  ],
  "deform": {"base": {"elements": [{"kind": "regular", "pathline": [[2, 0, 0, -1], [0, 0, 2, 3]], "attach": 1}]},
             "matrix": [{"t": 1, "m": [[0, -1], [1, 0]]}, {"t": 3, "m": [[2, 0], [0, 2]]}],
             "streamlines": [{"seed": [0, 0, 2], "keys": [{"t": 0}, {"t": 3, "translate": [0, 0.5, 0]}]}]},
  "edits": [{"op": "cancel", "frame": 19, "pair": [[2, 0, 0], [0, 2, 0]]},
            {"op": "remove_bifurcation", "at": [0, -2, 0, 0.5]},
            {"op": "move_bifurcation", "at": [0, -2, 0, 0.5], "to": [0, 0, -2, 2]},
            {"op": "smooth", "strength": 1}]
})";

TEST(SceneJson, ReadsTheDesignExampleExactly) {
  const Scene s = parse_scene(kDesignExample, "scene.json");
  EXPECT_EQ(s.version, 1);
  EXPECT_EQ(s.description, "DESIGN §10 example");
  ASSERT_TRUE(s.domain.grid.has_value());
  EXPECT_EQ(s.domain.grid->nx, 65);
  EXPECT_EQ(s.domain.grid->ny, 65);
  EXPECT_EQ(s.domain.grid->min, Vec2(-1, -1));
  EXPECT_EQ(s.domain.grid->max, Vec2(1, 1));
  EXPECT_TRUE(s.domain.is_planar());
  EXPECT_EQ(s.time.frames, 100);
  EXPECT_EQ(s.time.t0, 0.0);
  EXPECT_EQ(s.time.t1, 1.0);
  EXPECT_EQ(s.generator, Generator::basis);
  EXPECT_EQ(s.solver.weights, Weights::cotan);
  EXPECT_EQ(s.solver.temporal_weight, 30.0);
  EXPECT_EQ(s.solver.tolerance, 1e-10);
  EXPECT_EQ(s.solver.region_radius, 0.1);
  EXPECT_EQ(s.falloff, 8.0);
  ASSERT_EQ(s.elements.size(), 4u);

  const auto& center = std::get<SingularElement>(s.elements[0]);
  EXPECT_EQ(center.type, SingularType::ccw_center);
  EXPECT_EQ(center.jacobian, jacobian_of(SingularType::ccw_center));
  ASSERT_EQ(center.path.size(), 2u);
  EXPECT_EQ(center.path[0].position, Vec3(-0.5, 0, 0));
  EXPECT_EQ(center.path[0].t, 0.0);
  EXPECT_EQ(center.path[1].position, Vec3(0.5, 0, 0));
  EXPECT_EQ(center.path[1].t, 1.0);
  ASSERT_EQ(center.transform.size(), 1u);
  EXPECT_EQ(center.transform[0].sx, 1.0);

  const auto& explicit_j = std::get<SingularElement>(s.elements[1]);
  EXPECT_FALSE(explicit_j.type.has_value());
  Mat2 j;
  j << 1, 0.5, 0, -1;
  EXPECT_EQ(explicit_j.jacobian, j);
  ASSERT_EQ(explicit_j.path.size(), 1u);

  const auto& b = std::get<BifurcationElement>(s.elements[2]);
  EXPECT_EQ(b.type, BifurcationType::saddle_sink_creation);
  EXPECT_EQ(b.at.position, Vec3(0, 0.4, 0));
  EXPECT_EQ(b.at.t, 0.5);
  EXPECT_EQ(b.scale, 0.3);
  EXPECT_EQ(b.time_scale, 0.2);
  EXPECT_EQ(b.angle, 0.0);

  const auto& r = std::get<RegularElement>(s.elements[3]);
  ASSERT_EQ(r.pathline.size(), 3u);
  EXPECT_EQ(r.pathline[1].position, Vec3(0, -0.4, 0));
  EXPECT_EQ(r.pathline[1].t, 0.5);
  EXPECT_EQ(r.attach, 2.0);

  ASSERT_EQ(s.keyframes.size(), 2u);
  EXPECT_EQ(s.keyframes[0].t, 0.0);
  ASSERT_EQ(s.keyframes[0].elements.size(), 1u);
  EXPECT_EQ(s.keyframes[0].elements[0].kind, "singular");
  EXPECT_EQ(s.keyframes[0].elements[0].type, SingularType::source);
  EXPECT_EQ(s.keyframes[0].elements[0].jacobian, Mat2::Identity());
  EXPECT_EQ(s.keyframes[0].elements[0].at, Vec3(0, 0, 0));
  EXPECT_TRUE(s.keyframes[0].streamlines.empty());
  EXPECT_EQ(s.keyframes[1].t, 1.0);
  ASSERT_EQ(s.keyframes[1].streamlines.size(), 1u);
  EXPECT_EQ(s.keyframes[1].streamlines[0].points,
            (std::vector<Vec3>{Vec3(-1, 0, 0), Vec3(0, 0.3, 0), Vec3(1, 0, 0)}));
  EXPECT_EQ(s.keyframes[1].streamlines[0].speed, 1.0);
  EXPECT_TRUE(s.keyframes[1].field.empty());

  // deform and edits are typed; written back in normalised form (every default written).
  const json deform = json::parse(R"({
    "base": {"elements": [{"kind": "singular", "type": "saddle", "path": [[0.0, 0.0, 0.0]], "transform": []}]},
    "transform": [{"t": 0.0, "sx": 1.0, "sy": 1.0, "theta": 0.0}, {"t": 1.0, "sx": 1.0, "sy": 1.0, "theta": 3.14159}],
    "streamlines": [{"seed": [0.0, 0.0], "keys": [{"t": 1.0, "translate": [0.2, 0.0], "rotate": 0.5, "scale": 1.0}]}]})");
  ASSERT_TRUE(s.deform.has_value());
  ASSERT_EQ(s.deform->base.size(), 1u);
  EXPECT_EQ(std::get<SingularElement>(s.deform->base[0]).type, SingularType::saddle);
  EXPECT_FALSE(s.deform->matrix.has_value());
  ASSERT_TRUE(s.deform->transform.has_value());
  EXPECT_EQ(s.deform->transform->at(1).theta, 3.14159);
  ASSERT_EQ(s.deform->streamlines.size(), 1u);
  EXPECT_EQ(s.deform->streamlines[0].keys[0].translate, Vec3(0.2, 0, 0));
  EXPECT_EQ(s.deform->streamlines[0].keys[0].rotate, 0.5);
  const json written = scene_to_json(s);
  EXPECT_EQ(written["deform"], deform);
  const json edits = json::parse(R"([
    {"op": "cancel", "frame": 40, "pair": [[0.1, 0.2], [0.15, 0.22]], "window": 0.1},
    {"op": "smooth", "strength": 0.5}])");
  ASSERT_EQ(s.edits.size(), 2u);
  EXPECT_EQ(std::get<CancelEdit>(s.edits[0]).frame, 40);
  EXPECT_EQ(std::get<SmoothEdit>(s.edits[1]).strength, 0.5);
  EXPECT_EQ(written["edits"], edits);
  EXPECT_TRUE(written["edits"][0]["frame"].is_number_integer());
  EXPECT_TRUE(s.source_path.empty());
}

TEST(SceneJson, ReadsASurfaceSceneWithThreeDimensionalPositions) {
  const Scene s = parse_scene(kSphereScene, "sphere.json");
  ASSERT_TRUE(s.domain.sphere.has_value());
  EXPECT_FALSE(s.domain.is_planar());
  EXPECT_EQ(s.domain.sphere->subdivisions, 3);
  EXPECT_EQ(s.domain.sphere->radius, 2.0);
  EXPECT_EQ(s.time.t0, -1.0);
  EXPECT_EQ(s.time.t1, 3.0);
  EXPECT_EQ(s.generator, Generator::spacetime);
  EXPECT_EQ(s.solver.weights, Weights::mean_value);
  EXPECT_EQ(s.solver.temporal_weight, 0.0);
  const auto& focus = std::get<SingularElement>(s.elements[0]);
  EXPECT_EQ(focus.path[1].position, Vec3(0, 2, 0));
  EXPECT_EQ(focus.path[1].t, 3.0);
  ASSERT_EQ(focus.transform.size(), 2u);
  EXPECT_EQ(focus.transform[1].t, 2.0);
  EXPECT_EQ(focus.transform[1].sx, 1.0);  // defaults for omitted keys
  EXPECT_EQ(focus.transform[1].sy, 1.0);
  EXPECT_EQ(focus.transform[1].theta, -1.0);
  EXPECT_EQ(std::get<SingularElement>(s.elements[1]).path[0].position, Vec3(0, 0, 2));
  EXPECT_EQ(std::get<RegularElement>(s.elements[2]).attach, 0.0);
  const auto& b = std::get<BifurcationElement>(s.elements[3]);
  EXPECT_EQ(b.type, BifurcationType::saddle_source_creation);
  EXPECT_EQ(b.at.position, Vec3(0, -2, 0));
  EXPECT_EQ(b.scale, 0.25);
  EXPECT_EQ(b.time_scale, 0.25);
  EXPECT_EQ(b.angle, 0.0);
  const Keyframe& k0 = s.keyframes[0];
  Mat2 j;
  j << 1, 2, 3, 4;
  EXPECT_FALSE(k0.elements[0].type.has_value());
  EXPECT_EQ(k0.elements[0].jacobian, j);
  EXPECT_EQ(k0.elements[0].at, Vec3(0, 0, 2));
  EXPECT_EQ(k0.elements[1].kind, "regular");
  EXPECT_EQ(k0.elements[1].vector, Vec3(0, 1, 0));
  EXPECT_EQ(k0.streamlines[0].speed, 2.5);
  EXPECT_EQ(s.keyframes[1].field, "fields/end.tvff");
  ASSERT_TRUE(s.deform && s.deform->matrix);
  EXPECT_EQ(s.deform->matrix->at(1).m, Mat2(2 * Mat2::Identity()));
  EXPECT_FALSE(s.deform->transform.has_value());
  const json written = scene_to_json(s);
  EXPECT_EQ(written["deform"]["matrix"][1]["m"], json::parse("[[2.0, 0.0], [0.0, 2.0]]"));
  EXPECT_FALSE(written["deform"].contains("transform"));
  EXPECT_EQ(written["deform"]["streamlines"][0]["keys"][0],
            json::parse(R"({"t": 0.0, "translate": [0.0, 0.0, 0.0], "rotate": 0.0, "scale": 1.0})"));
  EXPECT_EQ(std::get<MoveBifurcationEdit>(s.edits[2]).to.position, Vec3(0, 0, -2));
  EXPECT_EQ(written["edits"][2]["to"], json::parse("[0.0, 0.0, -2.0, 2.0]"));
}

TEST(SceneJson, OmittedKeysTakeTheDefaultsOfSceneH) {
  const Scene s = parse_scene(R"({"tvf": 1, "domain": {"grid": {}}})", "minimal.json");
  const Scene d;
  const GridSpec g;
  ASSERT_TRUE(s.domain.grid.has_value());
  EXPECT_EQ(s.domain.grid->nx, g.nx);
  EXPECT_EQ(s.domain.grid->ny, g.ny);
  EXPECT_EQ(s.domain.grid->min, g.min);
  EXPECT_EQ(s.domain.grid->max, g.max);
  EXPECT_EQ(s.description, "");
  EXPECT_EQ(s.time.frames, d.time.frames);
  EXPECT_EQ(s.time.t0, d.time.t0);
  EXPECT_EQ(s.time.t1, d.time.t1);
  EXPECT_EQ(s.generator, d.generator);
  EXPECT_EQ(s.solver.weights, d.solver.weights);
  EXPECT_EQ(s.solver.temporal_weight, d.solver.temporal_weight);
  EXPECT_EQ(s.solver.tolerance, d.solver.tolerance);
  EXPECT_EQ(s.solver.region_radius, d.solver.region_radius);
  EXPECT_EQ(s.falloff, d.falloff);
  EXPECT_TRUE(s.elements.empty());
  EXPECT_TRUE(s.keyframes.empty());
  EXPECT_FALSE(s.deform.has_value());
  EXPECT_TRUE(s.edits.empty());
  EXPECT_EQ(scene_to_json(s)["edits"], json::array());

  const Scene sphere = parse_scene(R"({"tvf": 1, "domain": {"sphere": {}}})", "s.json");
  EXPECT_EQ(sphere.domain.sphere->subdivisions, SphereSpec{}.subdivisions);
  EXPECT_EQ(sphere.domain.sphere->radius, SphereSpec{}.radius);
  const Scene torus = parse_scene(R"({"tvf": 1, "domain": {"torus": {}}})", "t.json");
  EXPECT_EQ(torus.domain.torus->nu, TorusSpec{}.nu);
  EXPECT_EQ(torus.domain.torus->nv, TorusSpec{}.nv);
  EXPECT_EQ(torus.domain.torus->major_radius, TorusSpec{}.major_radius);
  EXPECT_EQ(torus.domain.torus->minor_radius, TorusSpec{}.minor_radius);
}

TEST(SceneJson, IntegerValuedNumbersCountAsIntegers) {
  const Scene s = parse_scene(
      R"({"tvf": 1.0, "domain": {"grid": {"size": [9.0, 1e1]}}, "time": {"frames": 2e1}})", "x.json");
  EXPECT_EQ(s.domain.grid->nx, 9);
  EXPECT_EQ(s.domain.grid->ny, 10);
  EXPECT_EQ(s.time.frames, 20);
}

TEST(SceneJson, RoundTripsTheDesignExampleAndSurfaceScenes) {
  {
    SCOPED_TRACE("design example");
    expect_round_trip(parse_scene(kDesignExample, "scene.json"));
  }
  {
    SCOPED_TRACE("sphere");
    expect_round_trip(parse_scene(kSphereScene, "sphere.json"));
  }
  for (const char* domain : {R"({"mesh": "meshes/bunny.obj"})", R"({"torus": {"nu": 12, "nv": 5}})"}) {
    SCOPED_TRACE(domain);
    const std::string text = std::string(R"({"tvf": 1, "domain": )") + domain + R"(,
      "elements": [{"kind": "singular", "type": "cw_center", "path": [[1, 2, 3, 0.5]]},
                   {"kind": "bifurcation", "type": "saddle_sink_cancellation", "at": [1, 0, 0, 1],
                    "scale": 0.5, "time_scale": 2, "angle": -3}]})";
    const Scene s = scene_from_json(json::parse(text), "mesh.json", "/somewhere/mesh.json");
    EXPECT_EQ(std::get<SingularElement>(s.elements[0]).path[0].position, Vec3(1, 2, 3));
    expect_round_trip(s);
  }
}

TEST(SceneJson, RoundTripsEveryElementKindBuiltInCode) {
  // Values whose shortest decimal form is long, to catch any loss of precision.
  const double third = 1.0 / 3.0, tiny = 1e-300, odd = 0.1 + 0.2;
  Scene s;
  s.domain.grid = GridSpec{3, 4, {-third, -2}, {odd, 7}};
  s.time = {-odd, 10 * third, 7};
  s.generator = Generator::constrained;
  s.solver = {Weights::uniform, third, tiny, odd};
  s.falloff = third;
  s.description = "tabs\tand \"quotes\" and ünïcode";
  SingularElement a;
  a.type = SingularType::attracting_focus;
  a.jacobian = jacobian_of(*a.type);
  a.path = {{Vec3(third, odd, 0), -odd}, {Vec3(-third, tiny, 0), 0.0}, {Vec3(1, 1, 0), third}};
  a.transform = {{-odd, third, odd, -third}, {third, 1, 2, 3}};
  SingularElement b;
  b.jacobian << third, -odd, tiny, 5;
  b.path = {{Vec3(0, 0, 0), 10 * third}};
  RegularElement r;
  r.pathline = {{Vec3(0, 0, 0), 0.0}, {Vec3(odd, third, 0), 1.0}};
  r.attach = third;
  BifurcationElement f;
  f.type = BifurcationType::saddle_source_cancellation;
  f.at = {Vec3(odd, -odd, 0), odd};
  f.scale = 1e-12;  // the smallest a scale may be (scene_reference.md, "Limits")
  f.time_scale = third;
  f.angle = -third;
  StreaklineElement sl;
  sl.points = {Vec3(-third, odd, 0), Vec3(odd, third, 0), Vec3(0.25, 2, 0)};
  sl.t = 3.0;
  sl.from = -odd;
  sl.attach = third;
  s.elements = {a, b, r, f, sl};
  Keyframe k;
  k.t = third;
  KeyframeElement ke;
  ke.kind = "regular";
  ke.at = Vec3(odd, third, 0);
  ke.vector = Vec3(-third, 0, 0);
  k.elements.push_back(ke);
  KeyframeStreamline ks;
  ks.points = {Vec3(0, 0, 0), Vec3(third, odd, 0)};
  ks.speed = odd;
  k.streamlines.push_back(ks);
  s.keyframes.push_back(k);
  Keyframe kf;
  kf.t = 3.0;
  kf.field = "/abs/field.tvff";
  s.keyframes.push_back(kf);
  expect_round_trip(s);

  const json j = scene_to_json(s);
  // Planar scenes are written with 2-D points, key frames with field files keep only t and
  // field, and the canonical form writes every key.
  EXPECT_EQ(j["elements"][0]["path"][0].size(), 3u);
  EXPECT_EQ(j["keyframes"][0]["elements"][0]["vector"].size(), 2u);
  EXPECT_EQ(j["keyframes"][1], json::parse(R"({"t": 3.0, "field": "/abs/field.tvff"})"));
  EXPECT_EQ(j["elements"][1]["jacobian"][1][0].get<double>(), tiny);
  for (const char* key : {"tvf", "description", "domain", "time", "generator", "solver", "falloff",
                          "elements", "keyframes", "edits"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_FALSE(j.contains("deform"));
  EXPECT_EQ(j["elements"][2], json::parse(R"({"kind": "regular", "pathline": [[0.0, 0.0, 0.0],
      [0.30000000000000004, 0.3333333333333333, 1.0]], "attach": 0.3333333333333333})"));
  EXPECT_EQ(j["elements"][4], json::parse(R"({"kind": "streakline", "points": [[-0.3333333333333333,
      0.30000000000000004], [0.30000000000000004, 0.3333333333333333], [0.25, 2.0]], "t": 3.0,
      "from": -0.30000000000000004, "attach": 0.3333333333333333})"));
}

TEST(SceneJson, TextIsOrderedAndCompact) {
  const Scene s = parse_scene(kDesignExample, "scene.json");
  const std::string text = scene_to_text(s);
  EXPECT_EQ(text.rfind("{\n  \"tvf\": 1,\n  \"description\": \"DESIGN §10 example\",\n  \"domain\": ", 0), 0u)
      << text;
  EXPECT_EQ(text.back(), '\n');
  // Points, paths and transform keys stay on one line, keys in the order of DESIGN §10.
  EXPECT_NE(text.find("\n      \"kind\": \"singular\",\n      \"type\": \"ccw_center\",\n"
                      "      \"path\": [[-0.5, 0.0, 0.0], [0.5, 0.0, 1.0]],\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find(R"("elements": [{"kind": "singular", "type": "source", "at": [0.0, 0.0]}],)"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find(R"({"t": 1.0, "sx": 1.0, "sy": 1.0, "theta": 3.14159})"), std::string::npos) << text;
  EXPECT_NE(text.find(R"({"op": "cancel", "frame": 40, "pair": [[0.1, 0.2], [0.15, 0.22]], "window": 0.1})"),
            std::string::npos)
      << text;
  const size_t elements = text.find("\"elements\"");
  const size_t keyframes = text.find("\"keyframes\"");
  const size_t deform = text.find("\"deform\"");
  const size_t edits = text.find("\"edits\"");
  EXPECT_LT(text.find("\"falloff\""), elements);
  EXPECT_LT(elements, keyframes);
  EXPECT_LT(keyframes, deform);
  EXPECT_LT(deform, edits);
  for (size_t start = 0, end; start < text.size(); start = end + 1) {
    end = text.find('\n', start);
    EXPECT_LE(end - start, 96u) << text.substr(start, end - start);
  }
}

TEST(SceneJson, SaveAndLoadRoundTripThroughAFile) {
  test::TempDir dir;
  Scene s = parse_scene(kSphereScene, "sphere.json");
  const std::string path = (dir / "saved.json").string();
  save_scene(s, path);
  const Scene back = load_scene(path);
  EXPECT_EQ(back.source_path, path);
  s.source_path = path;
  expect_same_scene(s, back);
  EXPECT_EQ(test::read_text(path), scene_to_text(s));
  // The write went through a temporary name: only the file itself is left.
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dir.path()))
    names.push_back(e.path().filename().string());
  EXPECT_EQ(names, std::vector<std::string>{"saved.json"});
}

TEST(SceneJson, SaveRefusesAnInvalidSceneAndWritesNothing) {
  test::TempDir dir;
  Scene s;  // no domain
  const std::string path = (dir / "bad.json").string();
  try {
    save_scene(s, path);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              "cannot save the scene to '" + path +
                  "': domain: must name exactly one domain (grid, mesh, sphere or torus), got none");
  }
  s.domain.grid = GridSpec{};
  SingularElement late;
  late.type = SingularType::source;
  late.path = {{Vec3(0, 0, 0), 5.0}};
  s.elements.push_back(late);
  EXPECT_THROW(save_scene(s, path), Error);
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(SceneJson, LoadResolvesTheMeshAgainstTheSceneFolder) {
  test::TempDir dir;
  std::filesystem::create_directories(dir / "scenes");
  const std::string path = (dir / "scenes" / "bunny.json").string();
  test::write_text(path, R"({"tvf": 1, "domain": {"mesh": "../meshes/bunny.obj"},
    "keyframes": [{"t": 0.5, "field": "key.tvff"}]})");
  const Scene s = load_scene(path);
  EXPECT_EQ(s.domain.mesh, "../meshes/bunny.obj");
  EXPECT_EQ(s.resolved_mesh_path(), (dir / "scenes" / "../meshes/bunny.obj").string());
  EXPECT_EQ(s.resolve_path(s.keyframes[0].field), (dir / "scenes" / "key.tvff").string());
  EXPECT_EQ(s.label(), path);
}

using test::error_of;

TEST(SceneJson, MissingOrUnreadableFilesAreOneSentenceNamingThePath) {
  test::TempDir dir;
  const std::string missing = (dir / "nope.json").string();
  EXPECT_EQ(error_of([&] { load_scene(missing); }),
            "cannot read the scene file '" + missing + "': it does not exist");
  EXPECT_EQ(error_of([&] { load_scene(dir.path().string()); }),
            "cannot read the scene file '" + dir.path().string() + "': it is a folder");
}

TEST(SceneJson, SyntaxErrorsFromFilesNameTheFileLineAndColumn) {
  test::TempDir dir;
  const std::string path = (dir / "broken.json").string();
  // The column is that of the last character read (the closing quote of "domain"), counted
  // in characters, not bytes: "§" is two bytes.
  test::write_text(path, "{\"tvf\": 1,\n  \"description\": \"§\" \"domain\": {}}");
  const std::string message = error_of([&] { load_scene(path); });
  EXPECT_EQ(message.rfind(path + ": line 2, column 29: syntax error while parsing object", 0), 0u)
      << message;
}

TEST(SceneJson, DuplicateKeysAreErrorsNamingThePath) {
  EXPECT_EQ(error_of([] {
              parse_scene(R"({"tvf": 1, "domain": {"grid": {"size": [3, 3], "size": [4, 4]}}})", "d.json");
            }),
            "d.json: domain.grid.size: the key appears twice in the same object (JSON keys must be unique)");
  EXPECT_EQ(error_of([] {
              parse_scene(R"({"tvf": 1, "domain": {"grid": {}},
                "elements": [{}, {"kind": "regular", "kind": "singular"}]})", "d.json");
            }),
            "d.json: elements[1].kind: the key appears twice in the same object (JSON keys must be unique)");
}

// Issue 17 items 1 and 2: deep nesting used to crash the message (a recursive print of
// the value) and take memory quadratic in the depth (a path string per open container).
TEST(SceneJson, DeepNestingIsRefusedAtOneThousandLevelsWithABoundedMessage) {
  // 1,000 levels in all are read; the message quoting such a value stays short.
  const std::string deep999 = std::string(999, '[') + std::string(999, ']');
  const std::string message = error_of([&] {
    parse_scene("{\"tvf\": 1, \"domain\": {\"grid\": {}}, \"description\": " + deep999 + "}", "s.json");
  });
  EXPECT_EQ(message.rfind("s.json: description: must be a string, got [[[[", 0), 0u) << message.substr(0, 200);
  EXPECT_LT(message.size(), 120u);
  // A smooth edit's strength as an array 100,000 deep (the server's crash), and a megabyte
  // of '[' (which took 8 GB): refused at level 1,001.
  const std::string strength = std::string(100'000, '[') + std::string(100'000, ']');
  const std::string edit_message = error_of([&] {
    parse_scene("{\"tvf\": 1, \"domain\": {\"grid\": {}}, \"edits\": [{\"op\": \"smooth\", \"strength\": " + strength +
                    "}]}",
                "s.json");
  });
  EXPECT_EQ(edit_message,
            "s.json: line 1, column 1072: arrays and objects nest more than 1000 deep, more than tvf reads");
  EXPECT_EQ(error_of([&] { parse_scene(std::string(1 << 20, '['), "s.json"); }),
            "s.json: line 1, column 1001: arrays and objects nest more than 1000 deep, more than tvf reads");
  // A key repeated deep inside names its path, built only then.
  std::string nested = "{\"tvf\": 1, \"description\": ";
  for (int k = 0; k < 3; ++k) nested += "[0, {\"a\": ";
  nested += "{\"b\": 1, \"b\": 2}";
  for (int k = 0; k < 3; ++k) nested += "}]";
  EXPECT_EQ(error_of([&] { parse_scene(nested + "}", "s.json"); }),
            "s.json: description[1].a[1].a[1].a.b: the key appears twice in the same object (JSON keys must be "
            "unique)");
}

// Issue 17 item 10: a scene is read up to a size limit (/dev/zero used to be read until
// memory ran out), and a NUL byte anywhere is refused rather than ending the text.
TEST(SceneJson, EndlessFilesAndNulBytesAreRefused) {
  if (std::filesystem::exists("/dev/zero")) {
    EXPECT_EQ(error_of([] { load_scene("/dev/zero"); }),
              "cannot read the scene file '/dev/zero': it is longer than 67108864 bytes, the limit for a JSON file");
  }
  // A NUL inside a string (written \u0000) is legal JSON; the message shows it visibly.
  const std::string message = error_of([] {
    parse_scene(R"({"tvf": 1, "domain": {"grid": {}}, "generator": "ba\u0000sis"})", "s.json");
  });
  EXPECT_EQ(message, "s.json: generator: unknown generator \"ba\\u0000sis\" (expected one of basis, constrained, "
                     "spacetime, deform)");
}

TEST(SceneJson, NonFiniteNumbersBuiltInCodeAreRejected) {
  json j = json::parse(R"({"tvf": 1, "domain": {"grid": {}}})");
  j["falloff"] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(error_of([&] { scene_from_json(j, "code"); }), "code: falloff: must be a finite number, got nan");
  j["falloff"] = 1.0;
  j["time"]["range"] = {0.0, std::numeric_limits<double>::infinity()};
  EXPECT_EQ(error_of([&] { scene_from_json(j, "code"); }),
            "code: time.range[1]: must be a finite number, got inf");
  j["time"]["range"] = {0.0, 1.0};
  j["time"]["frames"] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(error_of([&] { scene_from_json(j, "code"); }),
            "code: time.frames: must be an integer in [2, 100000], got inf");
  j["time"].erase("frames");
  j["elements"] = json::parse(R"([{"kind": "streakline", "points": [[0, 0], [0.5, 0]], "t": 1, "from": 0}])");
  EXPECT_NO_THROW(scene_from_json(j, "code"));
  j["elements"][0]["points"][1][1] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(error_of([&] { scene_from_json(j, "code"); }),
            "code: elements[0].points[1][1]: must be a finite number, got nan");
  j["elements"][0]["points"][1][1] = 0.0;
  j["elements"][0]["from"] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(error_of([&] { scene_from_json(j, "code"); }), "code: elements[0].from: must be a finite number, got nan");
}

// --- the table of bad inputs

json planar_base() {
  return json::parse(R"({
    "tvf": 1,
    "domain": {"grid": {"size": [9, 9]}},
    "time": {"frames": 10, "range": [0, 1]},
    "elements": [
      {"kind": "singular", "type": "ccw_center", "path": [[-0.5, 0, 0], [0.5, 0, 1]],
       "transform": [{"t": 0}, {"t": 1, "theta": 1}]},
      {"kind": "regular", "pathline": [[-1, -0.6, 0], [1, -0.6, 1]], "attach": 1},
      {"kind": "bifurcation", "type": "saddle_sink_creation", "at": [0, 0.4, 0.5]},
      {"kind": "streakline", "points": [[-0.5, -0.5], [0, -0.3], [0.5, -0.5]], "t": 0.8, "from": 0.2}
    ],
    "keyframes": [
      {"t": 0, "elements": [{"kind": "singular", "type": "source", "at": [0, 0]}]},
      {"t": 1, "streamlines": [{"points": [[-1, 0], [1, 0]]}]}
    ],
    "deform": {"base": {"elements": [{"kind": "singular", "type": "saddle", "path": [[0, 0, 0]]}]},
               "transform": [{"t": 1, "theta": 1}],
               "streamlines": [{"seed": [0, 0], "keys": [{"t": 0}, {"t": 1, "translate": [0.2, 0]}]}]},
    "edits": [{"op": "cancel", "frame": 4, "pair": [[0.1, 0.2], [0.15, 0.22]]},
              {"op": "smooth", "strength": 0.5},
              {"op": "remove_bifurcation", "at": [0, 0.4, 0.5]},
              {"op": "move_bifurcation", "at": [0, 0.4, 0.5], "to": [0, 0.3, 0.6]}]
  })");
}

// What the self-crossing check lets through: a sharp V (its sides meet only at the
// corner they share), a repeated point, a closed loop (the oldest dye back at the seed as
// the youngest is released), a hairpin whose sides stay apart.
TEST(SceneJson, StreaklineSketchesThatDoNotMeetThemselvesAreTaken) {
  json j = planar_base();
  for (const char* points : {"[[-0.6, -0.5], [0.2, -0.5], [-0.6, -0.45]]", "[[-0.5, 0], [0, 0], [0, 0], [0.5, 0]]",
                             "[[-0.5, -0.5], [0.5, -0.5], [0, 0.5], [-0.5, -0.5]]",
                             "[[-0.5, -0.5], [0.5, -0.5], [-0.5, -0.4999]]"}) {
    j["elements"][3]["points"] = json::parse(points);
    EXPECT_NO_THROW(scene_from_json(j, "scene.json")) << points;
  }
}

json sphere_base() {
  return json::parse(R"({
    "tvf": 1,
    "domain": {"sphere": {"subdivisions": 2}},
    "elements": [{"kind": "singular", "type": "source", "path": [[0, 0, 1, 0]]}],
    "keyframes": [{"t": 0.5, "elements": [{"kind": "regular", "at": [1, 0, 0], "vector": [0, 1, 0]}]}],
    "edits": [{"op": "cancel", "frame": 4, "pair": [[1, 0, 0], [0, 1, 0]]}]
  })");
}

std::string planar(const std::function<void(json&)>& change) {
  json j = planar_base();
  change(j);
  return j.dump();
}
std::string sphere(const std::function<void(json&)>& change) {
  json j = sphere_base();
  change(j);
  return j.dump();
}

struct BadCase {
  const char* name;
  std::string text;
  std::string where;     // JSON path (or "line L, column C"); empty: the scene as a whole
  std::string fragment;  // part of the sentence that follows
  bool schema_rejects;   // the JSON Schema can express this rule (the text is plain JSON)
};

std::vector<BadCase> bad_cases() {
  return {
      {"broken JSON", "{\"tvf\": 1,\n  \"domain\": {\"grid\": {}},\n  \"falloff\": 8,,\n}",
       "line 3, column 16", "syntax error while parsing object key - unexpected ','", false},
      {"NaN", "{\"tvf\": 1,\n \"domain\": {\"grid\": {}},\n \"falloff\": NaN}", "line 3, column 13",
       "NaN is not a JSON number (numbers must be finite)", false},
      {"-Infinity", "{\"tvf\": 1,\n \"domain\": {\"grid\": {}},\n \"falloff\": -Infinity}",
       "line 3, column 13", "-Infinity is not a JSON number", false},
      {"inf", "{\"tvf\": 1, \"domain\": {\"grid\": {}}, \"time\": {\"range\": [0, 1e999]}}",
       "time.range[1] (line 1, column 58)", "the number 1e999 is out of range (numbers must be finite)", false},
      {"not an object", "[1, 2]", "", "a scene must be a JSON object {\"tvf\": 1, ...}, got [1, 2]", true},
      {"missing tvf", planar([](json& j) { j.erase("tvf"); }), "",
       "missing key \"tvf\" (a tvf scene starts with \"tvf\": 1, the format version)", true},
      {"version 2", planar([](json& j) { j["tvf"] = 2; }), "tvf",
       "version 2 is not supported (this tvf reads version 1)", true},
      {"version as text", planar([](json& j) { j["tvf"] = "1"; }), "tvf",
       "must be the number 1 (the format version), got \"1\"", true},
      {"unknown top-level key", planar([](json& j) { j["fallof"] = 8; }), "",
       "unknown key \"fallof\" (expected one of tvf, description, domain, time, generator, solver, "
       "falloff, elements, keyframes, deform, edits, incompressible)",
       true},
      {"unknown element key", planar([](json& j) { j["elements"][0]["pth"] = json::array(); }),
       "elements[0]", "unknown key \"pth\" (expected one of kind, type, jacobian, path, transform)", true},
      {"wrong type", planar([](json& j) { j["time"]["frames"] = "100"; }), "time.frames",
       "must be an integer in [2, 100000], got \"100\"", true},
      {"elements not an array", planar([](json& j) { j["elements"] = json::object(); }), "elements",
       "must be an array of design elements, got {}", true},
      {"description not a string", planar([](json& j) { j["description"] = 3; }), "description",
       "must be a string, got 3", true},
      {"t out of range", planar([](json& j) { j["elements"][0]["path"][1] = {0.5, 0, 7}; }),
       "elements[0].path[1]", "t = 7 is outside the time range [0, 1]", false},
      {"path times not increasing", planar([](json& j) { j["elements"][0]["path"][1][2] = 0; }),
       "elements[0].path[1]", "t = 0 does not come after the previous point's t = 0", false},
      {"frames 1e12", planar([](json& j) { j["time"]["frames"] = 1e12; }), "time.frames",
       "must be an integer in [2, 100000], got 1000000000000", true},
      {"frames as a huge integer", planar([](json& j) { j["time"]["frames"] = 1000000000000LL; }),
       "time.frames", "must be an integer in [2, 100000], got 1000000000000", true},
      {"frames beyond 64 bits",
       R"({"tvf": 1, "domain": {"grid": {}}, "time": {"frames": 99999999999999999999999}})",
       "time.frames", "must be an integer in [2, 100000], got 1e+23", true},
      {"one frame", planar([](json& j) { j["time"]["frames"] = 1; }), "time.frames",
       "must be an integer in [2, 100000], got 1", true},
      {"grid size not an integer", planar([](json& j) { j["domain"]["grid"]["size"][0] = 1.5; }),
       "domain.grid.size[0]", "must be an integer ≥ 2, got 1.5", true},
      {"grid too large", planar([](json& j) { j["domain"]["grid"]["size"] = {100000, 100000}; }),
       "domain.grid.size", "100000 × 100000 vertices is more than the 50000000 a grid may have", false},
      {"grid box inverted", planar([](json& j) { j["domain"]["grid"]["max"] = {1, -1}; }),
       "domain.grid.max", "must be greater than min in both coordinates, got min [-1, -1] and max [1, -1]",
       false},
      {"empty domain", planar([](json& j) { j["domain"] = json::object(); }), "domain",
       "must name exactly one domain (grid, mesh, sphere or torus), got none", true},
      {"two domains", planar([](json& j) { j["domain"]["mesh"] = "bunny.obj"; }), "domain",
       "must name exactly one domain (grid, mesh, sphere or torus), got grid and mesh", true},
      {"missing domain", planar([](json& j) { j.erase("domain"); }), "",
       "missing key \"domain\" (grid, mesh, sphere or torus)", true},
      {"empty mesh path", planar([](json& j) { j["domain"] = {{"mesh", ""}}; }), "domain.mesh",
       "must be the path of an OBJ, PLY or OFF file, got an empty string", true},
      {"sphere subdivisions", sphere([](json& j) { j["domain"]["sphere"]["subdivisions"] = 12; }),
       "domain.sphere.subdivisions", "must be an integer in [0, 9], got 12", true},
      {"torus crosses itself",
       sphere([](json& j) { j["domain"] = {{"torus", {{"major_radius", 1}, {"minor_radius", 1}}}}; }),
       "domain.torus.minor_radius", "must be less than major_radius (1)", false},
      {"time range inverted", planar([](json& j) { j["time"]["range"] = {1, 1}; }), "time.range",
       "must have t0 < t1, got [1, 1]", false},
      {"unknown generator", planar([](json& j) { j["generator"] = "magic"; }), "generator",
       "unknown generator \"magic\" (expected one of basis, constrained, spacetime, deform)", true},
      {"unknown weights", planar([](json& j) { j["solver"]["weights"] = "cot"; }), "solver.weights",
       "unknown weights \"cot\" (expected one of cotan, uniform, mean_value)", true},
      {"unknown solver method", planar([](json& j) { j["solver"]["method"] = "lu"; }), "solver.method",
       "unknown solver method \"lu\" (expected one of auto, modes, cg, bicgstab)", true},
      {"tolerance 1", planar([](json& j) { j["solver"]["tolerance"] = 1; }), "solver.tolerance",
       "must be in (0, 1), got 1", true},
      {"negative temporal weight", planar([](json& j) { j["solver"]["temporal_weight"] = -1; }),
       "solver.temporal_weight", "must be a number ≥ 0, got -1", true},
      {"falloff 0", planar([](json& j) { j["falloff"] = 0; }), "falloff", "must be a number > 0, got 0",
       true},
      {"wrong arity on a grid", planar([](json& j) { j["elements"][0]["path"][0] = {0, 0, 0, 0}; }),
       "elements[0].path[0]",
       "must be [x, y, t] (3 numbers) on a grid domain, got 4 numbers: [0, 0, 0, 0]", true},
      {"wrong arity on a sphere", sphere([](json& j) { j["elements"][0]["path"][0] = {0, 1, 0}; }),
       "elements[0].path[0]",
       "must be [x, y, z, t] (4 numbers) on a surface domain, got 3 numbers: [0, 1, 0]", true},
      {"wrong arity of a key-frame position",
       planar([](json& j) { j["keyframes"][0]["elements"][0]["at"] = {0, 0, 0}; }),
       "keyframes[0].elements[0].at", "must be [x, y] (2 numbers) on a grid domain, got 3 numbers", true},
      {"wrong arity of an edit", sphere([](json& j) { j["edits"][0]["pair"][1] = {0, 1}; }),
       "edits[0].pair[1]", "must be [x, y, z] (3 numbers) on a surface domain, got 2 numbers", true},
      {"type and jacobian", planar([](json& j) { j["elements"][0]["jacobian"] = {{1, 0}, {0, 1}}; }),
       "elements[0]", "give either \"type\" or \"jacobian\", not both", true},
      {"neither type nor jacobian", planar([](json& j) { j["elements"][0].erase("type"); }),
       "elements[0]", "a singular element needs a \"type\"", true},
      {"unknown singular type", planar([](json& j) { j["elements"][0]["type"] = "center"; }),
       "elements[0].type", "unknown singular type \"center\" (expected one of source, sink, saddle, "
       "ccw_center, cw_center, repelling_focus, attracting_focus)", true},
      {"jacobian not 2x2", planar([](json& j) {
         j["elements"][0].erase("type");
         j["elements"][0]["jacobian"] = {1, 0, 0, 1};
       }),
       "elements[0].jacobian", "must be a 2×2 matrix [[a, b], [c, d]], got [1, 0, 0, 1]", true},
      {"singular jacobian", planar([](json& j) {
         j["elements"][0].erase("type");
         j["elements"][0]["jacobian"] = {{1, 2}, {2, 4}};
       }),
       "elements[0].jacobian", "must be invertible (det ≠ 0) so that the singularity is isolated, "
       "got [[1, 2], [2, 4]]", false},
      {"comment", "{\"tvf\": 1, // version\n \"domain\": {\"grid\": {}}}", "line 1, column 12",
       "comments are not allowed in JSON", false},
      {"empty text", " \n ", "", "the text is empty; a scene is a JSON object {\"tvf\": 1, ...}", false},
      {"empty path", planar([](json& j) { j["elements"][0]["path"] = json::array(); }),
       "elements[0].path", "needs at least 1 [x, y, t] points, got 0", true},
      {"missing path", planar([](json& j) { j["elements"][0].erase("path"); }), "elements[0]",
       "missing key \"path\"", true},
      {"transform scale 0", planar([](json& j) { j["elements"][0]["transform"][0]["sx"] = 0; }),
       "elements[0].transform[0].sx", "must be a number > 0, got 0", true},
      {"transform keys unsorted", planar([](json& j) { j["elements"][0]["transform"][1]["t"] = 0; }),
       "elements[0].transform[1].t", "t = 0 does not come after the previous key's t = 0", false},
      {"unknown element kind", planar([](json& j) { j["elements"][1]["kind"] = "attachment"; }),
       "elements[1].kind",
       "unknown element kind \"attachment\" (expected one of singular, regular, bifurcation, streakline)", true},
      {"missing kind", planar([](json& j) { j["elements"][1].erase("kind"); }), "elements[1]",
       "missing key \"kind\" (singular, regular, bifurcation or streakline)", true},
      // A sketched streakline (issue 20): elements[3] of the planar base.
      {"streakline with one point", planar([](json& j) { j["elements"][3]["points"] = json::parse("[[-0.5, -0.5]]"); }),
       "elements[3].points", "needs at least 2 [x, y] points, got 1", true},
      {"streakline point outside the grid", planar([](json& j) { j["elements"][3]["points"][1] = {1.5, 0}; }),
       "elements[3].points[1]", "(1.5, 0) is outside the domain [-1, 1] × [-1, 1]", false},
      // An element or streamline wholly off a grid domain would constrain nothing there.
      {"key-frame element outside the grid", planar([](json& j) { j["keyframes"][0]["elements"][0]["at"] = {5, 0}; }),
       "keyframes[0].elements[0].at", "(5, 0) is outside the domain [-1, 1] × [-1, 1]", false},
      {"fixed element outside the grid", planar([](json& j) { j["elements"][0]["path"] = {{0, -3, 0}}; }),
       "elements[0].path", "the element lies wholly outside the domain [-1, 1] × [-1, 1]: it would constrain "
       "nothing there", false},
      {"moving element never on the grid", planar([](json& j) { j["elements"][0]["path"] = {{2, 0, 0}, {3, 0, 1}}; }),
       "elements[0].path", "the element's path lies wholly outside the domain", false},
      {"moving element passing by the grid's corner",
       planar([](json& j) { j["elements"][0]["path"] = {{0.5, 1.6, 0}, {1.6, 0.5, 1}}; }),
       "elements[0].path", "the element's path lies wholly outside the domain", false},
      {"pathline never on the grid", planar([](json& j) { j["elements"][1]["pathline"] = {{-3, 2, 0}, {3, 2, 1}}; }),
       "elements[1].pathline", "the pathline lies wholly outside the domain", false},
      {"bifurcation outside the grid", planar([](json& j) { j["elements"][2]["at"] = {0, 1.4, 0.5}; }),
       "elements[2].at", "(0, 1.4) is outside the domain [-1, 1] × [-1, 1]", false},
      {"key-frame streamline never on the grid",
       planar([](json& j) { j["keyframes"][1]["streamlines"][0]["points"] = {{-1, 2}, {1, 2}}; }),
       "keyframes[1].streamlines[0].points", "the streamline lies wholly outside the domain", false},
      {"streakline from after t", planar([](json& j) { j["elements"][3]["from"] = 0.9; }),
       "elements[3].from", "from = 0.9 must come before t = 0.8 (the dye is released over [from, t])", false},
      {"streakline from equal to t", planar([](json& j) { j["elements"][3]["from"] = 0.8; }),
       "elements[3].from", "from = 0.8 must come before t = 0.8", false},
      {"streakline t outside the time range", planar([](json& j) { j["elements"][3]["t"] = 2; }),
       "elements[3].t", "t = 2 is outside the time range [0, 1]", false},
      {"streakline without from", planar([](json& j) { j["elements"][3].erase("from"); }), "elements[3]",
       "missing key \"from\" (the time the dye's release starts, before t)", true},
      // Two parts of the dye at one point at t: a crossing, a fold back along itself, a
      // touch (a corner on another segment), also across a repeated point.
      {"streakline crossing itself",
       planar([](json& j) { j["elements"][3]["points"] = {{-0.6, -0.6}, {0.6, 0.6}, {0.6, -0.6}, {-0.6, 0.6}}; }),
       "elements[3].points", "the sketch crosses or folds back onto itself (its segments from points[0] and points[2])",
       false},
      {"streakline folding back",
       planar([](json& j) { j["elements"][3]["points"] = {{-0.5, -0.5}, {0.5, -0.5}, {0.5, -0.5}, {0, -0.5}}; }),
       "elements[3].points", "(its segments from points[0] and points[2])", false},
      {"streakline touching itself",
       planar([](json& j) { j["elements"][3]["points"] = {{-0.5, 0}, {0.5, 0}, {0.5, 0.5}, {0, 0.5}, {0, 0}}; }),
       "elements[3].points", "(its segments from points[0] and points[3])", false},
      {"streakline of zero length", planar([](json& j) { j["elements"][3]["points"] = {{0.1, 0.2}, {0.1, 0.2}}; }),
       "elements[3].points", "must have a length > 0", false},
      {"streakline point as a path point", planar([](json& j) { j["elements"][3]["points"][0] = {0.1, 0.2, 0.3}; }),
       "elements[3].points[0]", "must be [x, y] (2 numbers) on a grid domain", false},
      {"streakline negative attach", planar([](json& j) { j["elements"][3]["attach"] = -1; }),
       "elements[3].attach", "must be a number ≥ 0, got -1", true},
      {"streakline in a deform base",
       planar([](json& j) { j["deform"]["base"]["elements"].push_back(j["elements"][3]); }),
       "deform.base.elements[1].kind", "a streakline needs the dye's time-varying flow", false},
      {"pathline with one point", planar([](json& j) { j["elements"][1]["pathline"].erase(1); }),
       "elements[1].pathline", "needs at least 2 [x, y, t] points, got 1", true},
      {"negative attach", planar([](json& j) { j["elements"][1]["attach"] = -2; }),
       "elements[1].attach", "must be a number ≥ 0, got -2", true},
      {"bifurcation scale 0", planar([](json& j) { j["elements"][2]["scale"] = 0; }),
       "elements[2].scale", "must be a number > 0, got 0", true},
      {"bifurcation time out of range", planar([](json& j) { j["elements"][2]["at"][2] = -0.5; }),
       "elements[2].at", "t = -0.5 is outside the time range [0, 1]", false},
      {"unknown bifurcation type", planar([](json& j) { j["elements"][2]["type"] = "saddle_node"; }),
       "elements[2].type", "unknown bifurcation type \"saddle_node\"", true},
      {"unsorted keyframes", planar([](json& j) { j["keyframes"][1]["t"] = 0; }), "keyframes[1].t",
       "t = 0 does not come after the previous key frame's t = 0 (times must strictly increase)", false},
      {"key frame out of range", planar([](json& j) { j["keyframes"][1]["t"] = 2; }),
       "keyframes[1].t", "t = 2 is outside the time range [0, 1]", false},
      {"empty key frame", planar([](json& j) { j["keyframes"][0].erase("elements"); }), "keyframes[0]",
       "a key frame needs at least one element or streamline, or a \"field\" file", true},
      {"key frame field and elements", planar([](json& j) { j["keyframes"][0]["field"] = "f.tvff"; }),
       "keyframes[0]", "give either a \"field\" file or \"elements\" and \"streamlines\", not both", true},
      {"key-frame bifurcation", planar([](json& j) { j["keyframes"][0]["elements"][0]["kind"] = "bifurcation"; }),
       "keyframes[0].elements[0].kind",
       "unknown key-frame element kind \"bifurcation\" (expected one of singular, regular)", true},
      {"key-frame element with a path",
       planar([](json& j) { j["keyframes"][0]["elements"][0]["path"] = {{0, 0, 0}}; }),
       "keyframes[0].elements[0]", "unknown key \"path\" (expected one of kind, type, jacobian, at)", true},
      {"streamline with one point",
       planar([](json& j) { j["keyframes"][1]["streamlines"][0]["points"].erase(1); }),
       "keyframes[1].streamlines[0].points", "needs at least 2 [x, y] points, got 1", true},
      {"streamline speed 0", planar([](json& j) { j["keyframes"][1]["streamlines"][0]["speed"] = 0; }),
       "keyframes[1].streamlines[0].speed", "must be a number > 0, got 0", true},
      {"zero key-frame vector",
       sphere([](json& j) { j["keyframes"][0]["elements"][0]["vector"] = {0, 0, 0}; }),
       "keyframes[0].elements[0].vector", "must not be zero", false},
      {"deform matrix and transform",
       planar([](json& j) { j["deform"]["matrix"] = {{{"t", 1}, {"m", {{0, -1}, {1, 0}}}}}; }), "deform",
       "give either \"matrix\" or \"transform\" keys, not both", true},
      {"deform without base", planar([](json& j) { j["deform"].erase("base"); }), "deform",
       "missing key \"base\"", true},
      {"deform base element", planar([](json& j) { j["deform"]["base"]["elements"][0]["at"] = 1; }),
       "deform.base.elements[0]", "unknown key \"at\"", true},
      {"deform streamline keys unsorted",
       planar([](json& j) { j["deform"]["streamlines"][0]["keys"][1]["t"] = 0; }),
       "deform.streamlines[0].keys[1].t", "does not come after the previous key's t = 0", false},
      {"deform streamline translate arity",
       planar([](json& j) { j["deform"]["streamlines"][0]["keys"][1]["translate"] = {1, 2, 3}; }),
       "deform.streamlines[0].keys[1].translate", "must be [x, y] (2 numbers) on a grid domain", true},
      {"deform generator without deform", planar([](json& j) {
         j["generator"] = "deform";
         j.erase("deform");
       }),
       "", "missing key \"deform\" (the deform generator needs a deform block with its base field)", true},
      {"cancel frame out of range", planar([](json& j) { j["edits"][0]["frame"] = 10; }),
       "edits[0].frame", "must be an integer in [0, 9], got 10", false},
      {"cancel the same point twice",
       planar([](json& j) { j["edits"][0]["pair"][1] = j["edits"][0]["pair"][0]; }), "edits[0].pair",
       "names the same position twice", false},
      {"unknown edit", planar([](json& j) { j["edits"][1]["op"] = "undo"; }), "edits[1].op",
       "unknown edit \"undo\" (expected one of cancel, smooth, remove_bifurcation, move_bifurcation)", true},
      {"smooth strength 2", planar([](json& j) { j["edits"][1]["strength"] = 2; }),
       "edits[1].strength", "must be in (0, 1], got 2", true},
      {"move without destination", planar([](json& j) { j["edits"][3].erase("to"); }), "edits[3]",
       "missing key \"to\"", true},
      {"edit with an unknown key", planar([](json& j) { j["edits"][2]["frame"] = 3; }), "edits[2]",
       "unknown key \"frame\" (expected one of op, at, window)", true},
      {"incompressible boundary", planar([](json& j) { j["incompressible"] = {{"boundary", "closed"}}; }),
       "incompressible.boundary", "unknown boundary \"closed\" (expected one of no_flux, open)", true},
      {"incompressible unknown key", planar([](json& j) { j["incompressible"] = {{"tolerance", 1e-9}}; }),
       "incompressible", "unknown key \"tolerance\" (expected one of boundary)", true},
      {"incompressible as a number", planar([](json& j) { j["incompressible"] = 1; }), "incompressible",
       "must be true, false or an object", true},
      // Issue 17: numbers that overflow the computations are refused where they are read.
      {"huge time range", planar([](json& j) { j["time"]["range"] = {-1e308, 1e308}; }), "time.range[0]",
       "must be a number of magnitude at most 1e+15 (larger values overflow in the computations), got -1e+308",
       false},
      {"time range too short for its magnitude", planar([](json& j) { j["time"]["range"] = {1e12, 1e12 + 1}; }),
       "time.range", "is too short for its magnitude", false},
      {"subnormal time_scale", planar([](json& j) { j["elements"][2]["time_scale"] = 1e-320; }),
       "elements[2].time_scale", "must be at least 1e-12 (smaller values overflow what is divided by them)", false},
      {"huge jacobian", planar([](json& j) {
         j["elements"][0].erase("type");
         j["elements"][0]["jacobian"] = {{1e200, 0}, {0, 1}};
       }),
       "elements[0].jacobian[0][0]", "must be a number of magnitude at most 1e+15", false},
      {"huge temporal weight", planar([](json& j) { j["solver"]["temporal_weight"] = 1e308; }),
       "solver.temporal_weight", "must be a number of magnitude at most 1e+15", false},
      {"large temporal weight", planar([](json& j) { j["solver"]["temporal_weight"] = 1e9; }),
       "solver.temporal_weight", "must be at most 1e+06 (a larger weight makes the space-time system", false},
      {"huge grid box", planar([](json& j) { j["domain"]["grid"]["max"] = {1e200, 1}; }), "domain.grid.max[0]",
       "must be a number of magnitude at most 1e+15", false},
      {"grid box too narrow for its magnitude", planar([](json& j) {
         j["domain"]["grid"]["min"] = {1e14, -1};
         j["domain"]["grid"]["max"] = {1e14 + 1, 1};
       }),
       "domain.grid.max", "is too narrow for its magnitude along x", false},
      {"grid box too elongated", planar([](json& j) {
         j["domain"]["grid"]["min"] = {-1, -1};
         j["domain"]["grid"]["max"] = {1e15, 1};
       }),
       "domain.grid.max", "is too elongated for a grid of 9 × 9 vertices", false},
      {"huge smooth strength", planar([](json& j) { j["edits"][1]["strength"] = 1e300; }), "edits[1].strength",
       "must be a number of magnitude at most 1e+15", false},
      {"NUL after the scene", std::string("{\"tvf\": 1, \"domain\": {\"grid\": {}}}\0garbage", 42), "line 1, column 35",
       "the text contains a NUL byte", false},
      {"nested too deep", "{\"tvf\": 1, \"description\": " + std::string(1001, '[') + std::string(1001, ']') + "}",
       "line 1, column 1026", "arrays and objects nest more than 1000 deep, more than tvf reads", false},
  };
}

TEST(SceneJson, BaseScenesOfTheBadInputTableAreValid) {
  EXPECT_NO_THROW(scene_from_json(planar_base(), "scene.json"));
  EXPECT_NO_THROW(scene_from_json(sphere_base(), "scene.json"));
}

// A moving element may enter, leave or cross a grid domain: only one that never meets it is
// refused (the bad-input table's cases).
TEST(SceneJson, MovingElementsMayEnterLeaveOrCrossTheGrid) {
  for (const json& path : {json{{-3, 0, 0}, {3, 0.2, 1}}, json{{0, 0, 0}, {4, 0, 1}}, json{{-4, 0.9, 0}, {0.5, 0.5, 1}},
                           json{{0.5, 1.4, 0}, {1.4, 0.5, 1}}}) {
    SCOPED_TRACE(path.dump());
    json j = planar_base();
    j["elements"][0]["path"] = path;
    j["elements"][1]["pathline"] = path;
    EXPECT_NO_THROW(scene_from_json(j, "scene.json"));
  }
}

TEST(SceneJson, BadInputIsOneSentenceNamingTheFileAndTheJsonPath) {
  for (const BadCase& c : bad_cases()) {
    SCOPED_TRACE(c.name);
    const std::string message = error_of([&] { parse_scene(c.text, "scene.json"); });
    const std::string prefix = "scene.json: " + (c.where.empty() ? std::string() : c.where + ": ");
    EXPECT_EQ(message.rfind(prefix, 0), 0u) << message;
    EXPECT_NE(message.find(c.fragment, prefix.size()), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

// --- the JSON Schema agrees with the parser

std::filesystem::path schema_path() {
  return std::filesystem::path(test::source_dir()) / "schema" / "scene.schema.json";
}

bool have_jsonschema() {
  if (test::python().empty()) return false;
  return test::run_command(fmt::format("'{}' -c 'import jsonschema'", test::python())).exit_code == 0;
}

// Validates each file against the schema; returns "ok" or "invalid: ..." per file.
std::vector<std::string> validate_with_schema(const std::vector<std::filesystem::path>& files,
                                              const test::TempDir& dir) {
  const auto script = dir / "validate.py";
  test::write_text(script, R"(import json, sys
import jsonschema
schema = json.load(open(sys.argv[1], encoding="utf-8"))
jsonschema.Draft202012Validator.check_schema(schema)
validator = jsonschema.Draft202012Validator(schema)
for name in sys.argv[2:]:
    errors = list(validator.iter_errors(json.load(open(name, encoding="utf-8"))))
    print("ok" if not errors else "invalid: " + errors[0].message.replace("\n", " ")[:200])
)");
  std::string cmd = fmt::format("'{}' '{}' '{}'", test::python(), script.string(), schema_path().string());
  for (const auto& f : files) cmd += fmt::format(" '{}'", f.string());
  const test::CommandResult r = test::run_command(cmd);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  std::vector<std::string> lines;
  for (size_t start = 0, end; start < r.output.size(); start = end + 1) {
    end = r.output.find('\n', start);
    if (end == std::string::npos) end = r.output.size();
    if (end > start) lines.push_back(r.output.substr(start, end - start));
  }
  return lines;
}

TEST(SceneSchema, AcceptsEveryWrittenSceneAndEveryExample) {
  if (!have_jsonschema()) GTEST_SKIP() << "python3-jsonschema is not installed";
  test::TempDir dir;
  std::vector<std::filesystem::path> files;
  std::vector<std::string> texts = {kDesignExample, kSphereScene, planar_base().dump(), sphere_base().dump(),
                                    R"({"tvf": 1, "domain": {"grid": {}}})",
                                    R"({"tvf": 1, "domain": {"torus": {}}, "generator": "deform",
                                        "deform": {"base": {}}})"};
  for (size_t i = 0; i < texts.size(); ++i) {
    // The input itself and the canonical JSON written from it.
    const Scene s = parse_scene(texts[i], "input " + std::to_string(i));
    files.push_back(dir / ("input" + std::to_string(i) + ".json"));
    test::write_text(files.back(), texts[i]);
    files.push_back(dir / ("written" + std::to_string(i) + ".json"));
    save_scene(s, files.back().string());
  }
  for (const auto& e : std::filesystem::directory_iterator(std::filesystem::path(test::source_dir()) / "examples")) {
    const auto scene = e.path() / "scene.json";
    if (!std::filesystem::exists(scene)) continue;
    EXPECT_NO_THROW(load_scene(scene.string())) << scene;
    files.push_back(scene);
  }
  const auto results = validate_with_schema(files, dir);
  ASSERT_EQ(results.size(), files.size());
  for (size_t i = 0; i < files.size(); ++i) EXPECT_EQ(results[i], "ok") << files[i];
}

TEST(SceneSchema, RejectsTheBadInputsItCanExpress) {
  if (!have_jsonschema()) GTEST_SKIP() << "python3-jsonschema is not installed";
  test::TempDir dir;
  std::vector<std::filesystem::path> files;
  std::vector<std::string> names;
  for (const BadCase& c : bad_cases()) {
    if (!c.schema_rejects) continue;
    files.push_back(dir / ("bad" + std::to_string(files.size()) + ".json"));
    test::write_text(files.back(), c.text);
    names.push_back(c.name);
  }
  const auto results = validate_with_schema(files, dir);
  ASSERT_EQ(results.size(), files.size());
  for (size_t i = 0; i < files.size(); ++i)
    EXPECT_EQ(results[i].rfind("invalid: ", 0), 0u) << names[i] << ": " << results[i];
}

}  // namespace
}  // namespace tvf

namespace tvf {
namespace {

TEST(SceneJson, IncompressibleTakesABooleanOrABoundaryAndRoundTrips) {
  auto read = [](const std::string& value) {
    return parse_scene(R"({"tvf": 1, "domain": {"grid": {}}, "incompressible": )" + value + "}", "i.json");
  };
  EXPECT_FALSE(parse_scene(R"({"tvf": 1, "domain": {"grid": {}}})", "i.json").incompressible);
  EXPECT_FALSE(read("false").incompressible);
  EXPECT_EQ(read("true").incompressible, FluxBoundary::no_flux);
  EXPECT_EQ(read("{}").incompressible, FluxBoundary::no_flux);
  EXPECT_EQ(read(R"({"boundary": "open"})").incompressible, FluxBoundary::open);
  for (const char* v : {"true", R"({"boundary": "open"})", "false"}) {
    const Scene s = read(v);
    const Scene back = parse_scene(scene_to_text(s), "back.json");
    EXPECT_EQ(back.incompressible, s.incompressible) << v;
    EXPECT_EQ(scene_to_text(back), scene_to_text(s)) << v;
  }
  EXPECT_EQ(scene_to_json(read("true"))["incompressible"], nlohmann::json({{"boundary", "no_flux"}}));
}

TEST(SceneJson, BadIncompressibleValuesNameThePath) {
  auto error = [](const std::string& value) {
    return test::error_of(
        [&] { parse_scene(R"({"tvf": 1, "domain": {"grid": {}}, "incompressible": )" + value + "}", "i.json"); });
  };
  EXPECT_EQ(error(R"({"boundary": "wall"})"),
            "i.json: incompressible.boundary: unknown boundary \"wall\" (expected one of no_flux, open)");
  EXPECT_EQ(error(R"({"boundry": "open"})"),
            "i.json: incompressible: unknown key \"boundry\" (expected one of boundary)");
  EXPECT_NE(error("1").find("i.json: incompressible: must be true, false or an object"), std::string::npos);
  EXPECT_NE(error(R"("yes")").find("i.json: incompressible:"), std::string::npos);
}

// Issue 18: an error names its place in what() and as fields; the line and column are the
// value's in the text (from its JSON path), for parsed text and files alike.
TEST(SceneJson, ErrorsCarryTheFileJsonPathLineAndColumn) {
  const std::string text = "{\"tvf\": 1, \"domain\": {\"grid\": {}},\n"
                           "  \"elements\": [\n"
                           "    {\"kind\": \"singular\", \"type\": \"sourse\", \"path\": [[0, 0, 0]]}]}";
  auto check = [&](const std::function<void()>& f, const std::string& file) {
    try {
      f();
      ADD_FAILURE() << "no error";
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()).rfind(file + ": elements[0].type: ", 0), 0u) << e.what();
      EXPECT_EQ(location_of(e).file, file);
      EXPECT_EQ(location_of(e).json_path, "elements[0].type");
      EXPECT_EQ(location_of(e).line, 3);
      EXPECT_EQ(location_of(e).column, 34);
    }
  };
  check([&] { parse_scene(text, "t.json"); }, "t.json");
  test::TempDir dir;
  const std::string path = (dir.path() / "bad.json").string();
  std::ofstream(path) << text;
  check([&] { load_scene(path); }, path);
  // Scenes from parsed JSON have no text: the path, and no line.
  try {
    scene_from_json(json::parse(text), "j");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(location_of(e).json_path, "elements[0].type");
    EXPECT_EQ(location_of(e).line, 0);
  }
}

}  // namespace
}  // namespace tvf
