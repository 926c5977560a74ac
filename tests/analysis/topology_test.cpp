// Singularity paths and bifurcations in space-time (DESIGN §6, §9): closed forms of the
// bifurcation normal forms, moving and turning linear fields, zeros exactly on vertices
// and edges, Poincaré–Hopf along paths on closed meshes, and the analysis JSON.
#include "tvf/analysis/topology.h"

#include "support/test_meshes.h"
#include "tvf/core/error.h"
#include "tvf/design/element_field.h"
#include "tvf/mesh/grid.h"
#include "tvf/mesh/tangent_bundle.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

namespace tvf {
namespace {

using PlanarField = std::function<Vec2(const Vec2& x, double t)>;
using WorldField = std::function<Vec3(const Vec3& x, double t)>;

Field sample_planar(const Mesh& mesh, const TimeSampling& time, const PlanarField& f) {
  Field field(time, mesh.num_vertices());
  for (int j = 0; j < time.frames; ++j) {
    const double t = time.time(j);
    for (int v = 0; v < mesh.num_vertices(); ++v) field.at(j, v) = to_complex(f(mesh.position(v).head<2>(), t));
  }
  return field;
}

Field sample_world(const TangentBundle& bundle, const TimeSampling& time, const WorldField& f) {
  const Mesh& mesh = bundle.mesh();
  Field field(time, mesh.num_vertices());
  for (int j = 0; j < time.frames; ++j)
    for (int v = 0; v < mesh.num_vertices(); ++v)
      field.at(j, v) = bundle.world_to_vertex(v, f(mesh.position(v), time.time(j)));
  return field;
}

Mat2 rotation(double a) {
  Mat2 R;
  R << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
  return R;
}

// Structural invariants every result must satisfy.
void expect_consistent(const Topology& topo) {
  const int N = static_cast<int>(topo.times.size());
  ASSERT_EQ(static_cast<int>(topo.singularities.size()), N);
  ASSERT_EQ(static_cast<int>(topo.singularity_path.size()), N);
  for (size_t p = 0; p < topo.paths.size(); ++p) {
    const SingularityPath& path = topo.paths[p];
    EXPECT_EQ(path.id, static_cast<int>(p));
    ASSERT_FALSE(path.points.empty());
    EXPECT_EQ(path.birth, path.points.front().t);
    EXPECT_EQ(path.death, path.points.back().t);
    for (size_t k = 1; k < path.points.size(); ++k) EXPECT_LE(path.points[k - 1].t, path.points[k].t) << p;
    EXPECT_TRUE(path.index == 1 || path.index == -1) << path.index;
    EXPECT_EQ(path.type == SingularityType::saddle, path.index < 0) << p;
  }
  for (int j = 0; j < N; ++j) {
    const auto& sings = topo.singularities[static_cast<size_t>(j)];
    ASSERT_EQ(topo.singularity_path[static_cast<size_t>(j)].size(), sings.size());
    for (size_t k = 0; k < sings.size(); ++k) {
      const int id = topo.singularity_path[static_cast<size_t>(j)][k];
      ASSERT_GE(id, 0) << "frame " << j << " singularity " << k << " is on no path";
      ASSERT_LT(id, static_cast<int>(topo.paths.size()));
      const SingularityPath& path = topo.paths[static_cast<size_t>(id)];
      // The index is constant along a path, and the path is alive at the frame.
      EXPECT_EQ(path.index, sings[k].index) << "frame " << j;
      EXPECT_LE(path.birth, sings[k].t);
      EXPECT_GE(path.death, sings[k].t);
    }
  }
  for (const Bifurcation& b : topo.bifurcations) {
    ASSERT_GE(b.paths[0], 0);
    ASSERT_LT(b.paths[1], static_cast<int>(topo.paths.size()));
    ASSERT_NE(b.paths[0], b.paths[1]);
    const SingularityPath& p = topo.paths[static_cast<size_t>(b.paths[0])];
    const SingularityPath& q = topo.paths[static_cast<size_t>(b.paths[1])];
    // A saddle–node pair: opposite indices, both ending (cancellation) or beginning
    // (creation) at the bifurcation's point.
    EXPECT_EQ(p.index + q.index, 0);
    for (const SingularityPath* r : {&p, &q}) {
      const PathSample& s = b.kind == BifurcationKind::creation ? r->points.front() : r->points.back();
      EXPECT_EQ(s.t, b.t);
      EXPECT_EQ(s.position, b.position);
    }
  }
}

// analyze_topology, checking that its singularities are exactly find_singularities' in
// every frame (the frame triangles' crossings are the per-frame singularities).
Topology analyze(const TangentBundle& bundle, const Field& field, const TopologyOptions& options = {}) {
  Topology topo = analyze_topology(bundle, field, options);
  EXPECT_EQ(topo.singularities.size(), static_cast<size_t>(field.frames()));
  for (int j = 0; j < field.frames() && j < static_cast<int>(topo.singularities.size()); ++j) {
    const std::vector<Singularity> expected = find_singularities(bundle, field, j);
    const std::vector<Singularity>& got = topo.singularities[static_cast<size_t>(j)];
    EXPECT_EQ(got.size(), expected.size()) << "frame " << j;
    for (size_t k = 0; k < std::min(got.size(), expected.size()); ++k) {
      EXPECT_EQ(got[k].frame, expected[k].frame);
      EXPECT_EQ(got[k].t, expected[k].t);
      EXPECT_EQ(got[k].where.face, expected[k].where.face) << "frame " << j;
      EXPECT_EQ(got[k].where.bary, expected[k].where.bary) << "frame " << j;
      EXPECT_EQ(got[k].position, expected[k].position) << "frame " << j;
      EXPECT_EQ(got[k].index, expected[k].index) << "frame " << j;
      EXPECT_EQ(got[k].type, expected[k].type) << "frame " << j;
      EXPECT_EQ(got[k].jacobian, expected[k].jacobian) << "frame " << j;
    }
  }
  return topo;
}

// ---- The four normal forms ------------------------------------------------------------

struct NormalFormCase {
  BifurcationType type;
  BifurcationKind kind;
  SingularityType node;  // the non-saddle at p + s√|t′|·axis
};
const NormalFormCase kNormalForms[] = {
    {BifurcationType::saddle_source_cancellation, BifurcationKind::cancellation, SingularityType::source},
    {BifurcationType::saddle_sink_creation, BifurcationKind::creation, SingularityType::sink},
    {BifurcationType::saddle_source_creation, BifurcationKind::creation, SingularityType::source},
    {BifurcationType::saddle_sink_cancellation, BifurcationKind::cancellation, SingularityType::sink},
};

struct Placement {
  Vec2 p;
  double t0;
  double scale;       // s
  double time_scale;  // τ
  double angle;       // θ
};

// Checks a field that holds one bifurcation template: one bifurcation at (p, t0), the node
// at p + s√|t′|·(cos θ, sin θ) and the saddle at p − s√|t′|·(cos θ, sin θ), t′ = (t − t0)/τ,
// on the side of t0 where the template has zeros.
void expect_template(const Topology& topo, const NormalFormCase& c, const Placement& at, double cell,
                     double dt) {
  expect_consistent(topo);
  ASSERT_EQ(topo.bifurcations.size(), 1u);
  const Bifurcation& b = topo.bifurcations[0];
  EXPECT_EQ(b.kind, c.kind);
  EXPECT_NEAR(b.t, at.t0, dt);
  EXPECT_LE((b.position.head<2>() - at.p).norm(), cell) << b.position.transpose();
  EXPECT_EQ(b.position.z(), 0.0);
  ASSERT_EQ(topo.paths.size(), 2u);
  EXPECT_EQ(b.paths, (std::array<int, 2>{0, 1}));
  const Vec2 axis(std::cos(at.angle), std::sin(at.angle));
  const double side = c.kind == BifurcationKind::creation ? 1.0 : -1.0;  // sign of t′ with zeros
  int saddles = 0;
  for (const SingularityPath& path : topo.paths) {
    const bool saddle = path.type == SingularityType::saddle;
    saddles += saddle;
    if (!saddle) {
      EXPECT_EQ(path.type, c.node);
    }
    const double sign = saddle ? -1.0 : 1.0;
    // The path lives on the side of t0 where the template has zeros, from the time range's
    // end to the bifurcation.
    if (c.kind == BifurcationKind::creation) {
      EXPECT_EQ(path.birth, b.t);
      EXPECT_EQ(path.death, topo.times.back());
    } else {
      EXPECT_EQ(path.birth, topo.times.front());
      EXPECT_EQ(path.death, b.t);
    }
    for (const PathSample& s : path.points) {
      const double tp = side * (s.t - at.t0) / at.time_scale;
      const Vec2 expected = at.p + sign * at.scale * std::sqrt(std::max(tp, 0.0)) * axis;
      EXPECT_LE((s.position.head<2>() - expected).norm(), cell)
          << (saddle ? "saddle" : "node") << " at t = " << s.t << ": " << s.position.transpose()
          << " expected " << expected.transpose();
    }
  }
  EXPECT_EQ(saddles, 1);
  // Every frame on the template's side holds the pair, the other side nothing.
  for (size_t j = 0; j < topo.times.size(); ++j) {
    const double tp = side * (topo.times[j] - at.t0) / at.time_scale;
    if (tp > 0.05) {
      EXPECT_EQ(topo.singularities[j].size(), 2u) << "t = " << topo.times[j];
    } else if (tp < -0.05) {
      EXPECT_EQ(topo.singularities[j].size(), 0u) << "t = " << topo.times[j];
    }
  }
}

// 81 × 81 on [-1, 1]², 41 frames on [-0.5, 0.5].
const Mesh& normal_form_grid() {
  static const Mesh m = make_grid(GridSpec{81, 81, {-1, -1}, {1, 1}});
  return m;
}
constexpr double kCell = 2.0 / 80 * 1.4142135623730951;  // a cell's diagonal
const TimeSampling kNormalFormTime{-0.5, 0.5, 41};
constexpr double kNormalFormDt = 1.0 / 40;

TEST(Topology, NormalFormsGiveOneBifurcationAndTheSquareRootPaths) {
  const Mesh& mesh = normal_form_grid();
  const TangentBundle bundle(mesh);
  const Placement at{{0.0123, -0.0311}, 0.0137, 1.0, 1.0, 0.0};
  for (const auto& c : kNormalForms) {
    SCOPED_TRACE(to_string(c.type));
    const Field field = sample_planar(mesh, kNormalFormTime, [&](const Vec2& x, double t) {
      return bifurcation_normal_form(c.type, x.x() - at.p.x(), x.y() - at.p.y(), t - at.t0);
    });
    expect_template(analyze(bundle, field), c, at, kCell, kNormalFormDt);
  }
}

TEST(Topology, RotatedAndScaledTemplatesKeepTheirClosedForms) {
  const Mesh& mesh = normal_form_grid();
  const TangentBundle bundle(mesh);
  const Placement placements[] = {{{0.1, -0.05}, -0.1137, 0.35, 0.4, 0.9},
                                  {{-0.0731, 0.0917}, 0.0619, 0.5, 0.7, -2.3}};
  for (const auto& at : placements) {
    for (const auto& c : kNormalForms) {
      SCOPED_TRACE(std::string(to_string(c.type)) + " angle " + std::to_string(at.angle));
      BifurcationElement e;
      e.type = c.type;
      e.at = {Vec3(at.p.x(), at.p.y(), 0), at.t0};
      e.scale = at.scale;
      e.time_scale = at.time_scale;
      e.angle = at.angle;
      const CompiledElement element(Element{e});
      Field field(kNormalFormTime, mesh.num_vertices());
      for (int j = 0; j < field.frames(); ++j) {
        const ElementState st = element.at(kNormalFormTime.time(j));
        for (int v = 0; v < mesh.num_vertices(); ++v)
          field.at(j, v) = st.field(to_complex(mesh.position(v).head<2>() - st.position.head<2>()));
      }
      expect_template(analyze(bundle, field), c, at, kCell, kNormalFormDt);
    }
  }
}

// ---- Moving and turning linear fields ---------------------------------------------------

TEST(Topology, MovingSourceIsOnePathOnItsTrajectory) {
  const Mesh mesh = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle(mesh);
  Mat2 J;
  J << 1.2, 0.3, 0.1, 0.9;
  auto p = [](double t) { return Vec2(0.5 * std::cos(kPi * t) + 0.013, 0.5 * std::sin(kPi * t) - 0.021); };
  const TimeSampling time{0.0, 1.0, 41};
  const Field field = sample_planar(mesh, time, [&](const Vec2& x, double t) -> Vec2 { return J * (x - p(t)); });
  const Topology topo = analyze(bundle, field);
  expect_consistent(topo);
  EXPECT_TRUE(topo.bifurcations.empty());
  ASSERT_EQ(topo.paths.size(), 1u);
  const SingularityPath& path = topo.paths[0];
  EXPECT_EQ(path.type, SingularityType::source);
  EXPECT_EQ(path.index, 1);
  EXPECT_EQ(path.birth, 0.0);
  EXPECT_EQ(path.death, 1.0);
  EXPECT_GT(path.points.size(), 41u);  // frames and the crossings between them
  const double cell = 2.0 / 40 * std::sqrt(2.0);
  for (const PathSample& s : path.points) EXPECT_LE((s.position.head<2>() - p(s.t)).norm(), cell) << s.t;
  // At the frames the field is linear in space: the positions are exact.
  for (int j = 0; j < time.frames; ++j) {
    ASSERT_EQ(topo.singularities[static_cast<size_t>(j)].size(), 1u);
    EXPECT_LE((topo.singularities[static_cast<size_t>(j)][0].position.head<2>() - p(time.time(j))).norm(), 1e-12);
  }
}

TEST(Topology, SourceCrossingTheBoundaryIsBornAndDiesThere) {
  const Mesh mesh = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle(mesh);
  auto p = [](double t) { return Vec2(-1.4877 + 3.0 * t, 0.1 + 0.2 * t); };
  const TimeSampling time{0.0, 1.0, 31};
  const Field field = sample_planar(mesh, time, [&](const Vec2& x, double t) -> Vec2 { return -(x - p(t)); });
  const Topology topo = analyze(bundle, field);
  expect_consistent(topo);
  EXPECT_TRUE(topo.bifurcations.empty());
  ASSERT_EQ(topo.paths.size(), 1u);
  const SingularityPath& path = topo.paths[0];
  EXPECT_EQ(path.type, SingularityType::sink);
  // x(t) = ±1 at t = 0.4877/3 and 2.4877/3: the path enters and leaves through the
  // boundary; the field is linear in space and time, so the crossings are exact.
  EXPECT_NEAR(path.birth, 0.4877 / 3, 1e-12);
  EXPECT_NEAR(path.death, 2.4877 / 3, 1e-12);
  for (const PathSample& s : path.points) EXPECT_LE((s.position.head<2>() - p(s.t)).norm(), 1e-12);
}

TEST(Topology, SourceTurnedIntoSinkReportsTypeChanges) {
  const Mesh mesh = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle(mesh);
  const Vec2 p(0.0731, -0.0417);
  // J(t) = R(θ(t)): θ = 0 a source, π/2 a center, π a sink, foci in between.
  auto theta = [](double t) { return kPi * std::clamp((t - 0.2) / 0.6, 0.0, 1.0); };
  const TimeSampling time{0.0, 1.0, 61};
  const Field field =
      sample_planar(mesh, time, [&](const Vec2& x, double t) -> Vec2 { return rotation(theta(t)) * (x - p); });
  TopologyOptions every_type;
  every_type.node_focus_changes = true;
  const Topology topo = analyze(bundle, field, every_type);
  expect_consistent(topo);
  EXPECT_TRUE(topo.bifurcations.empty());
  const std::vector<SingularityType> expected = {SingularityType::source, SingularityType::repelling_focus,
                                                 SingularityType::center, SingularityType::attracting_focus,
                                                 SingularityType::sink};
  ASSERT_EQ(topo.paths.size(), expected.size());
  EXPECT_EQ(topo.stats.type_changes, 4);
  for (size_t k = 0; k < expected.size(); ++k) {
    const SingularityPath& path = topo.paths[k];
    EXPECT_EQ(path.type, expected[k]) << k;
    EXPECT_EQ(path.index, 1);
    // Between frames the field is bilinear in (x, t), so the space-time tetrahedra place
    // the zero within a cell of p; at the frames it is exact.
    for (const PathSample& s : path.points) EXPECT_LE((s.position.head<2>() - p).norm(), 0.05);
    if (k + 1 < expected.size()) {
      // The old singularity dies where the new one is born.
      EXPECT_EQ(path.death, topo.paths[k + 1].birth);
      EXPECT_LT(path.birth, path.death);
    }
    // The type changes where classify_jacobian's thresholds say: the death is the first
    // frame whose Jacobian has the next type.
    if (k + 1 < expected.size()) {
      const int j = static_cast<int>(std::lround(path.death * 60));
      EXPECT_EQ(classify_jacobian(rotation(theta(time.time(j)))), expected[k + 1]);
      EXPECT_EQ(classify_jacobian(rotation(theta(time.time(j - 1)))), expected[k]);
    }
  }
  EXPECT_EQ(topo.paths.front().birth, 0.0);
  EXPECT_EQ(topo.paths.back().death, 1.0);
  for (const auto& frame : topo.singularities) {
    ASSERT_EQ(frame.size(), 1u);
    EXPECT_LE((frame[0].position.head<2>() - p).norm(), 1e-12);
  }
}

// By default a path changes type only where its topological type changes: the stability
// of the index +1 singularity (repelling → center → attracting). Node and focus of one
// stability are one path, named by the type most of its frames have.
TEST(Topology, SourceTurnedIntoSinkChangesTopologicalTypeTwice) {
  const Mesh mesh = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle(mesh);
  const Vec2 p(0.0731, -0.0417);
  auto theta = [](double t) { return kPi * std::clamp((t - 0.2) / 0.6, 0.0, 1.0); };
  const TimeSampling time{0.0, 1.0, 61};
  const Field field =
      sample_planar(mesh, time, [&](const Vec2& x, double t) -> Vec2 { return rotation(theta(t)) * (x - p); });
  const Topology topo = analyze(bundle, field);
  expect_consistent(topo);
  EXPECT_TRUE(topo.bifurcations.empty());
  ASSERT_EQ(topo.paths.size(), 3u);
  EXPECT_EQ(topo.stats.type_changes, 2);
  // Stability class of a Jacobian: +1 repelling, 0 center, −1 attracting.
  auto stability = [](SingularityType t) {
    switch (t) {
      case SingularityType::source:
      case SingularityType::repelling_focus: return 1;
      case SingularityType::center: return 0;
      default: return -1;
    }
  };
  for (int k = 0; k < 3; ++k) {
    const SingularityPath& path = topo.paths[static_cast<size_t>(k)];
    EXPECT_EQ(stability(path.type), 1 - k) << to_string(path.type);
    // The path's name is the type most of its frames have.
    std::map<SingularityType, int> count;
    for (int j = 0; j < time.frames; ++j) {
      const double t = time.time(j);
      const bool last = k == 2;
      if (t >= path.birth && (t < path.death || (last && t <= path.death))) {
        const SingularityType type = classify_jacobian(rotation(theta(t)));
        if (stability(type) == 1 - k) ++count[type];
      }
    }
    const auto most = std::max_element(count.begin(), count.end(),
                                       [](const auto& a, const auto& b) { return a.second < b.second; });
    ASSERT_NE(most, count.end());
    EXPECT_EQ(path.type, most->first) << k;
    if (k < 2) {
      EXPECT_EQ(path.death, topo.paths[static_cast<size_t>(k + 1)].birth);
      const int j = static_cast<int>(std::lround(path.death * 60));
      EXPECT_EQ(stability(classify_jacobian(rotation(theta(time.time(j))))), -k);
      EXPECT_EQ(stability(classify_jacobian(rotation(theta(time.time(j - 1))))), 1 - k);
    }
  }
}

// A sink whose eigenvalues pass through equality, back and forth (degenerate-node
// territory): one sink path; with node_focus_changes, one path per run.
TEST(Topology, NodeFocusAlternationIsOnePath) {
  const Mesh mesh = make_grid(GridSpec{21, 21, {-1, -1}, {1, 1}});
  const TangentBundle bundle(mesh);
  const Vec2 p(0.031, 0.017);
  const TimeSampling time{0.0, 1.0, 21};
  // Runs of 3 frames: −I plus a small rotation (attracting focus, |Im λ| = 0.3·|Re λ|) or
  // a small shear of the eigenvalues (sink, λ = −1 ± 0.3).
  Field field(time, mesh.num_vertices());
  int sinks = 0;
  for (int j = 0; j < time.frames; ++j) {
    Mat2 J;
    const bool focus = (j / 3) % 2 == 1;
    if (focus)
      J << -1, -0.3, 0.3, -1;
    else
      J << -1.3, 0, 0, -0.7;
    sinks += !focus;
    for (int v = 0; v < mesh.num_vertices(); ++v) field.at(j, v) = to_complex(J * (mesh.position(v).head<2>() - p));
  }
  const Topology topo = analyze(bundle, field);
  expect_consistent(topo);
  ASSERT_EQ(topo.paths.size(), 1u);
  EXPECT_EQ(topo.paths[0].type, sinks * 2 > time.frames ? SingularityType::sink : SingularityType::attracting_focus);
  EXPECT_EQ(topo.stats.type_changes, 0);
  TopologyOptions split;
  split.node_focus_changes = true;
  const Topology every = analyze(bundle, field, split);
  expect_consistent(every);
  EXPECT_EQ(every.paths.size(), 7u);  // runs of 3 frames: 0–2, 3–5, …, 18–20
}

TEST(Topology, CenterFocusFlickerIsNotATypeChange) {
  const Mesh mesh = make_grid(GridSpec{21, 21, {-1, -1}, {1, 1}});
  const TangentBundle bundle(mesh);
  const Vec2 p(0.031, 0.017);
  const TimeSampling time{0.0, 1.0, 21};
  // Frames alternate between a center (θ = π/2) and a slowly repelling focus (θ = π/2 − 0.2).
  Field field(time, mesh.num_vertices());
  for (int j = 0; j < time.frames; ++j) {
    const Mat2 J = rotation(kPi / 2 - (j % 2 ? 0.2 : 0.0));
    for (int v = 0; v < mesh.num_vertices(); ++v)
      field.at(j, v) = to_complex(J * (mesh.position(v).head<2>() - p));
  }
  const Topology topo = analyze(bundle, field);
  expect_consistent(topo);
  ASSERT_EQ(topo.paths.size(), 1u);
  EXPECT_EQ(topo.paths[0].type, SingularityType::center);
  EXPECT_EQ(topo.stats.type_changes, 0);
  EXPECT_GT(topo.stats.suppressed_flickers, 0);
  // With every change taken at face value, each frame is its own path.
  TopologyOptions strict;
  strict.type_change_samples = 1;
  const Topology every = analyze(bundle, field, strict);
  expect_consistent(every);
  EXPECT_EQ(every.paths.size(), 21u);
  EXPECT_TRUE(every.bifurcations.empty());
}

// ---- Degenerate positions: simulation of simplicity in space-time ----------------------

TEST(Topology, ZerosOnVerticesAndEdgesGiveOnePath) {
  // A dyadic grid: the zero passes exactly through vertices at the frames and along edges
  // (horizontal, diagonal) or stays on one vertex between them.
  const Mesh mesh = make_grid(GridSpec{17, 17, {-1, -1}, {1, 1}});
  const TangentBundle bundle(mesh);
  const TimeSampling time{0.0, 1.0, 9};
  struct Motion {
    const char* name;
    std::function<Vec2(double)> p;
  };
  const Motion motions[] = {
      {"along a horizontal edge", [](double t) { return Vec2(-0.5 + t, 0.0); }},
      {"along diagonals", [](double t) { return Vec2(-0.5 + t, -0.5 + t); }},
      {"along a vertical edge, half steps", [](double t) { return Vec2(0.25, -0.25 + 0.5 * t); }},
      {"resting on a vertex", [](double) { return Vec2(0.25, 0.375); }},
  };
  Mat2 saddle;
  saddle << 1, 0.5, 0, -1;
  for (const auto& m : motions) {
    for (const Mat2& J : {Mat2(Mat2::Identity()), saddle, Mat2(rotation(kPi / 2))}) {
      SCOPED_TRACE(std::string(m.name) + " det " + std::to_string(J.determinant()));
      const Field field = sample_planar(mesh, time, [&](const Vec2& x, double t) -> Vec2 { return J * (x - m.p(t)); });
      const Topology topo = analyze(bundle, field);
      expect_consistent(topo);
      for (int j = 0; j < time.frames; ++j) {
        ASSERT_EQ(topo.singularities[static_cast<size_t>(j)].size(), 1u) << j;
        EXPECT_LE((topo.singularities[static_cast<size_t>(j)][0].position.head<2>() - m.p(time.time(j))).norm(), 1e-12);
      }
      EXPECT_TRUE(topo.bifurcations.empty());
      ASSERT_EQ(topo.paths.size(), 1u);
      EXPECT_EQ(topo.paths[0].birth, 0.0);
      EXPECT_EQ(topo.paths[0].death, 1.0);
      for (const PathSample& s : topo.paths[0].points) EXPECT_LE((s.position.head<2>() - m.p(s.t)).norm(), 1e-12);
    }
  }
}

TEST(Topology, PathsDoNotDependOnTheScaleOfEachFrame) {
  const Mesh& mesh = normal_form_grid();
  const TangentBundle bundle(mesh);
  const Field field = sample_planar(mesh, kNormalFormTime, [](const Vec2& x, double t) {
    return bifurcation_normal_form(BifurcationType::saddle_sink_creation, x.x() - 0.01, x.y() + 0.02, t);
  });
  Field scaled = field;
  for (int j = 0; j < scaled.frames(); ++j)
    for (cplx& z : scaled.frame(j)) z *= std::ldexp(1.0, j % 2 ? 300 : -300);
  const Topology a = analyze(bundle, field);
  const Topology b = analyze(bundle, scaled);
  EXPECT_EQ(a.singularity_path, b.singularity_path);
  ASSERT_EQ(a.paths.size(), b.paths.size());
  ASSERT_EQ(a.bifurcations.size(), b.bifurcations.size());
  EXPECT_EQ(a.bifurcations[0].kind, b.bifurcations[0].kind);
  for (size_t p = 0; p < a.paths.size(); ++p) EXPECT_EQ(a.paths[p].type, b.paths[p].type);
}

// ---- Closed meshes --------------------------------------------------------------------

// A smooth field with moving sources, sinks and vortices that meet and part.
Vec3 closed_mesh_field(const Vec3& x, double t) {
  const Vec3 c[3] = {Vec3(std::cos(3 * t), std::sin(3 * t), 0.3), Vec3(0.2, std::cos(2 * t + 1), std::sin(2 * t + 1)),
                     Vec3(std::sin(t) - 0.5, 0.4, std::cos(t))};
  const Vec3 axis[3] = {Vec3(0, 0, 1), Vec3(1, 0, 0), Vec3(0.3, 0.9, 0.2)};
  Vec3 w = Vec3(0.3 * std::cos(2 * t), 0.2, 0.3 * std::sin(2 * t));
  for (int k = 0; k < 3; ++k) {
    const Vec3 d = x - c[k];
    const double g = std::exp(-1.5 * d.squaredNorm());
    w += g * ((1 - k) * d + axis[k].cross(d) * (1.0 + t));
  }
  return w;
}

TEST(Topology, IndexIsConstantOnPathsAndSumsToEulerCharacteristicOnClosedMeshes) {
  for (const auto& named : test::closed_meshes()) {
    SCOPED_TRACE(named.name);
    const Mesh& mesh = *named.mesh;
    const TangentBundle bundle(mesh);
    const Field field = sample_world(bundle, TimeSampling{0.0, 2.0, 25}, closed_mesh_field);
    const Topology topo = analyze(bundle, field);
    expect_consistent(topo);
    const int chi = mesh.euler_characteristic();
    for (size_t j = 0; j < topo.times.size(); ++j) {
      int sum = 0, path_sum = 0;
      for (size_t k = 0; k < topo.singularities[j].size(); ++k) {
        sum += topo.singularities[j][k].index;
        path_sum += topo.paths[static_cast<size_t>(topo.singularity_path[j][k])].index;
      }
      EXPECT_EQ(sum, chi) << "frame " << j;
      EXPECT_EQ(path_sum, chi) << "frame " << j;
    }
    EXPECT_FALSE(topo.paths.empty());
    // On a closed surface nothing enters or leaves through a boundary: every path begins
    // at the first frame, at a creation or at a type change, and ends likewise.
    std::multiset<std::pair<double, int>> bif_ends;
    for (const Bifurcation& b : topo.bifurcations)
      for (const int p : b.paths) bif_ends.insert({b.t, p});
    for (const SingularityPath& p : topo.paths) {
      const bool born_at_start = p.birth == topo.times.front();
      const bool born_at_bif = bif_ends.count({p.birth, p.id}) > 0;
      const bool born_at_change = std::any_of(topo.paths.begin(), topo.paths.end(), [&](const SingularityPath& q) {
        return q.id != p.id && q.death == p.birth && q.points.back().position == p.points.front().position;
      });
      EXPECT_TRUE(born_at_start || born_at_bif || born_at_change) << "path " << p.id << " born at " << p.birth;
    }
  }
}

// Rough fields: i.i.d. values, and small integers (exact zeros at vertices, exactly
// opposite vectors on edges and in time, whole frames repeated) on every catalogue mesh.
// The tracking's internal checks (every tetrahedron's indices sum to 0, every crossing has
// its two neighbours) and the invariants of expect_consistent must hold throughout.
TEST(Topology, RandomAndDegenerateFieldsKeepEveryInvariant) {
  std::mt19937 rng(7);
  std::normal_distribution<double> gauss;
  const cplx small[] = {0, 1, -1, {0, 1}, {0, -1}, {1, 1}, {-1, -1}, {1, -1}, 2};
  std::uniform_int_distribution<int> pick(0, 8);
  for (const auto& named : test::all_meshes()) {
    SCOPED_TRACE(named.name);
    const Mesh& mesh = *named.mesh;
    const TangentBundle bundle(mesh);
    for (int trial = 0; trial < 4; ++trial) {
      Field field(TimeSampling{0.0, 1.0, 6}, mesh.num_vertices());
      for (int j = 0; j < field.frames(); ++j)
        for (int v = 0; v < mesh.num_vertices(); ++v)
          field.at(j, v) = trial % 2 ? small[pick(rng)] : cplx(gauss(rng), gauss(rng));
      if (trial == 3) {
        // Repeated frames and a frame of zeros.
        for (int v = 0; v < mesh.num_vertices(); ++v) {
          field.at(2, v) = field.at(1, v);
          field.at(4, v) = 0;
        }
      }
      const Topology topo = analyze(bundle, field);
      expect_consistent(topo);
      if (mesh.is_closed()) {
        for (const auto& frame : topo.singularities) {
          int sum = 0;
          for (const Singularity& x : frame) sum += x.index;
          EXPECT_EQ(sum, mesh.euler_characteristic());
        }
      }
    }
  }
}

TEST(Topology, ParallelAndSerialAgree) {
  const Mesh& mesh = test::torus_mesh();
  const TangentBundle bundle(mesh);
  const Field field = sample_world(bundle, TimeSampling{0.0, 2.0, 17}, closed_mesh_field);
  TopologyOptions serial;
  serial.parallel = false;
  EXPECT_EQ(topology_to_json(analyze_topology(bundle, field)).dump(),
            topology_to_json(analyze_topology(bundle, field, serial)).dump());
}

TEST(Topology, OneFrameGivesOnePointPaths) {
  const Mesh mesh = make_grid(GridSpec{11, 11, {-1, -1}, {1, 1}});
  const TangentBundle bundle(mesh);
  const Field field = sample_planar(mesh, TimeSampling{0.5, 0.5, 1}, [](const Vec2& x, double) {
    return Vec2(x.x() * x.x() - 0.25, x.y());  // a saddle and a source
  });
  const Topology topo = analyze(bundle, field);
  expect_consistent(topo);
  ASSERT_EQ(topo.paths.size(), 2u);
  for (const SingularityPath& p : topo.paths) EXPECT_EQ(p.points.size(), 1u);
  EXPECT_TRUE(topo.coherence.empty());
}

TEST(Topology, NonFiniteValuesAreRejected) {
  const Mesh mesh = make_grid(GridSpec{5, 5, {-1, -1}, {1, 1}});
  const TangentBundle bundle(mesh);
  Field field(TimeSampling{0, 1, 3}, mesh.num_vertices());
  field.at(1, 7) = {std::nan(""), 0};
  EXPECT_THROW(analyze_topology(bundle, field), Error);
}

// ---- JSON ------------------------------------------------------------------------------

std::set<std::string> keys(const nlohmann::json& j) {
  std::set<std::string> out;
  for (auto it = j.begin(); it != j.end(); ++it) out.insert(it.key());
  return out;
}

TEST(Topology, JsonHasExactlyTheKeysOfDesign9) {
  const Mesh& mesh = normal_form_grid();
  const TangentBundle bundle(mesh);
  const Field field = sample_planar(mesh, kNormalFormTime, [](const Vec2& x, double t) {
    return bifurcation_normal_form(BifurcationType::saddle_source_cancellation, x.x() - 0.01, x.y() + 0.02, t);
  });
  const Topology topo = analyze(bundle, field);
  const nlohmann::json j = nlohmann::json::parse(topology_to_json(topo).dump());
  EXPECT_EQ(keys(j), (std::set<std::string>{"frames", "times", "singularities", "paths", "bifurcations", "coherence"}));
  EXPECT_EQ(j["frames"], 41);
  ASSERT_EQ(j["times"].size(), 41u);
  EXPECT_EQ(j["times"][40].get<double>(), 0.5);
  EXPECT_EQ(j["coherence"].size(), 40u);
  const std::set<std::string> types = {"source", "sink", "saddle", "center", "repelling_focus", "attracting_focus"};
  size_t count = 0;
  for (const auto& s : j["singularities"]) {
    EXPECT_EQ(keys(s), (std::set<std::string>{"frame", "t", "position", "face", "index", "type", "jacobian"}));
    EXPECT_TRUE(s["frame"].is_number_integer());
    EXPECT_TRUE(s["face"].is_number_integer());
    EXPECT_TRUE(s["index"] == 1 || s["index"] == -1);
    EXPECT_TRUE(types.count(s["type"].get<std::string>())) << s["type"];
    ASSERT_EQ(s["position"].size(), 3u);
    ASSERT_EQ(s["jacobian"].size(), 2u);
    for (const auto& row : s["jacobian"]) EXPECT_EQ(row.size(), 2u);
    EXPECT_EQ(s["t"].get<double>(), topo.times[s["frame"].get<size_t>()]);
    ++count;
  }
  size_t expected = 0;
  for (const auto& f : topo.singularities) expected += f.size();
  EXPECT_EQ(count, expected);
  ASSERT_EQ(j["paths"].size(), 2u);
  for (size_t p = 0; p < j["paths"].size(); ++p) {
    const auto& path = j["paths"][p];
    EXPECT_EQ(keys(path), (std::set<std::string>{"id", "type", "birth", "death", "points"}));
    EXPECT_EQ(path["id"], p);
    EXPECT_TRUE(types.count(path["type"].get<std::string>()));
    for (const auto& pt : path["points"]) EXPECT_EQ(pt.size(), 4u);
    EXPECT_EQ(path["birth"], path["points"].front()[3]);
    EXPECT_EQ(path["death"], path["points"].back()[3]);
  }
  ASSERT_EQ(j["bifurcations"].size(), 1u);
  const auto& b = j["bifurcations"][0];
  EXPECT_EQ(keys(b), (std::set<std::string>{"t", "position", "kind", "paths"}));
  EXPECT_EQ(b["kind"], "cancellation");
  EXPECT_EQ(b["position"].size(), 3u);
  EXPECT_EQ(b["paths"], nlohmann::json::array({0, 1}));
  EXPECT_STREQ(to_string(BifurcationKind::creation), "creation");
  EXPECT_STREQ(to_string(BifurcationKind::cancellation), "cancellation");
}

}  // namespace
}  // namespace tvf
