#include "tvf/design/generate.h"

#include "tvf/core/error.h"
#include "tvf/design/element_field.h"
#include "tvf/solve/connection_laplacian.h"

#include <gtest/gtest.h>

#include "tvf/analysis/coherence.h"
#include "tvf/analysis/singularities.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>
#include <span>
#include <vector>

namespace tvf {
namespace {

Scene grid_scene(int n, double half, int frames) {
  Scene s;
  s.domain.grid = GridSpec{n, n, {-half, -half}, {half, half}};
  s.time.frames = frames;
  s.falloff = 8.0;
  return s;
}

SingularElement singular(SingularType type, std::vector<PathPoint> path) {
  SingularElement e;
  e.type = type;
  e.jacobian = jacobian_of(type);
  e.path = std::move(path);
  return e;
}

TEST(BasisSum, PlanarFieldIsTheClosedFormSum) {
  Scene s = grid_scene(21, 1.0, 5);
  s.elements.push_back(singular(SingularType::ccw_center, {{Vec3(-0.5, 0.2, 0), 0}, {Vec3(0.5, -0.1, 0), 1}}));
  BifurcationElement b;
  b.type = BifurcationType::saddle_sink_creation;
  b.at = {Vec3(0.3, 0.4, 0), 0.5};
  b.scale = 0.3;
  b.time_scale = 0.4;
  b.angle = 0.7;
  s.elements.push_back(b);
  const auto space = make_design_space(s);
  const Field field = generate(*space, s);
  const double d = s.falloff / (space->diameter() * space->diameter());
  EXPECT_DOUBLE_EQ(space->diameter(), std::sqrt(8.0));
  for (int j = 0; j < s.time.frames; ++j) {
    const double t = s.time.time(j);
    for (int v = 0; v < space->mesh().num_vertices(); v += 7) {
      const Vec3& x = space->mesh().position(v);
      cplx expected(0, 0);
      for (const Element& e : s.elements) {
        const ElementState st = CompiledElement(e).at(t);
        const cplx w(x.x() - st.position.x(), x.y() - st.position.y());
        expected += std::exp(-d * std::norm(w)) * st.field(w);
      }
      EXPECT_LT(std::abs(field.at(j, v) - expected), 1e-14) << j << " " << v;
    }
  }
}

TEST(BasisSum, SingularElementVanishesExactlyAtItsPosition) {
  // A grid vertex at the element's position carries a zero vector in every frame in which
  // the element is alone.
  Scene s = grid_scene(11, 1.0, 3);
  const int v = 3 * 11 + 6;  // (ix, iy) = (6, 3), near (0.2, -0.4)
  const Vec3 at = make_grid(*s.domain.grid).position(v);
  s.elements.push_back(singular(SingularType::saddle, {{at, 0}}));
  const auto space = make_design_space(s);
  const Field field = generate(*space, s);
  for (int j = 0; j < 3; ++j) EXPECT_EQ(field.at(j, v), cplx(0, 0));
  EXPECT_NE(field.at(0, v + 1), cplx(0, 0));
}

TEST(BasisSum, InvariantUnderScalingTheDomain) {
  for (double scale : {1e-3, 1e3}) {
    Scene a = grid_scene(15, 1.0, 4), b = grid_scene(15, scale, 4);
    a.elements.push_back(singular(SingularType::repelling_focus, {{Vec3(0.1, 0.2, 0), 0}, {Vec3(-0.3, 0.1, 0), 1}}));
    b.elements.push_back(singular(SingularType::repelling_focus,
                                  {{Vec3(0.1 * scale, 0.2 * scale, 0), 0}, {Vec3(-0.3 * scale, 0.1 * scale, 0), 1}}));
    const auto sa = make_design_space(a);
    const auto sb = make_design_space(b);
    const Field fa = generate(*sa, a), fb = generate(*sb, b);
    for (size_t k = 0; k < fa.data().size(); ++k)
      EXPECT_LT(std::abs(fb.data()[k] / scale - fa.data()[k]), 1e-12) << k;
  }
}

TEST(BasisSum, ParallelAndSerialAgreeBitForBit) {
  Scene s = grid_scene(33, 1.0, 20);
  s.elements.push_back(singular(SingularType::source, {{Vec3(-0.5, 0, 0), 0}, {Vec3(0.5, 0.1, 0), 1}}));
  RegularElement r;
  r.pathline = {{Vec3(-0.8, -0.6, 0), 0}, {Vec3(0.8, -0.5, 0), 1}};
  r.attach = 2;
  s.elements.push_back(r);
  const auto space = make_design_space(s);
  GenerateOptions serial;
  serial.parallel = false;
  const Field a = generate(*space, s), b = generate(*space, s, serial);
  EXPECT_EQ(a.data(), b.data());
}

// The constrained generator's blocks, their frames' constraints (log maps on a surface,
// a static element's kept per thread) and their solves run at once: the field is the one
// of a serial run bit for bit; on the sphere, with a moving and a static element, over
// two blocks of frames.
TEST(Constrained, ParallelAndSerialAgreeBitForBit) {
  Scene s;
  s.domain.sphere = SphereSpec{3, 1.0};
  s.time.frames = 30;
  s.falloff = 20;
  s.generator = Generator::constrained;
  const Vec3 p = Vec3(0.3, -0.4, 0.8).normalized(), q = Vec3(-0.5, 0.2, 0.6).normalized();
  s.elements.push_back(singular(SingularType::source, {{p, 0}, {q, 1}}));
  s.elements.push_back(singular(SingularType::ccw_center, {{-p, 0}}));
  const auto space = make_design_space(s);
  GenerateOptions serial;
  serial.parallel = false;
  const Field a = generate(*space, s), b = generate(*space, s, serial);
  EXPECT_EQ(a.data(), b.data());
}

TEST(BasisSum, SourceOnTheSphereIsRadialLikeOnThePlane) {
  Scene s;
  s.domain.sphere = SphereSpec{5, 1.0};
  s.time.frames = 2;
  s.falloff = 20;
  const Vec3 p = Vec3(0.3, -0.4, 0.8).normalized();
  s.elements.push_back(singular(SingularType::source, {{p, 0}}));
  s.elements.push_back(singular(SingularType::ccw_center, {{-p, 0}}));
  const auto space = make_design_space(s);
  const Field field = generate(*space, s);
  const double d = s.falloff / (space->diameter() * space->diameter());
  int checked = 0;
  for (int v = 0; v < space->mesh().num_vertices(); ++v) {
    const Vec3& x = space->mesh().position(v);
    const double r = std::acos(std::clamp(p.dot(x), -1.0, 1.0));
    if (r < 0.1 || r > 1.0) continue;
    // Geodesic direction away from p at x, and the closed-form magnitude r·exp(−d r²)
    // (the ccw center at −p contributes exp(−d (π − r)²)·(π − r) ≤ 2e-3 here).
    const Vec3 away = (x.dot(p) * x - p).normalized();
    const Vec3 got = space->bundle().vertex_to_world(v, field.at(0, v));
    const double angle = std::acos(std::clamp(got.normalized().dot(away), -1.0, 1.0));
    EXPECT_LT(angle, 0.06) << "vertex " << v << " at distance " << r;
    EXPECT_NEAR(got.norm(), r * std::exp(-d * r * r), 0.05 * r * std::exp(-d * r * r) + 3e-3);
    ++checked;
  }
  EXPECT_GT(checked, 1000);
}

TEST(Generate, AppliesTheScenesEditsAfterTheGenerator) {
  Scene s = grid_scene(9, 1.0, 4);
  s.elements.push_back(singular(SingularType::source, {{Vec3(-0.3, 0.2, 0), 0}, {Vec3(0.3, -0.1, 0), 1}}));
  s.source_path = "my.json";
  s.edits = {SmoothEdit{0.5}};
  const auto space = make_design_space(s);
  GenerateReport report;
  const Field edited = generate(*space, s, {}, &report);
  const Field plain = generate_unedited(*space, s);
  ASSERT_EQ(report.edits.size(), 1u);
  EXPECT_NE(report.edits[0].find("smoothed"), std::string::npos) << report.edits[0];
  double change = 0;
  for (size_t k = 0; k < plain.data().size(); ++k) change += std::abs(edited.data()[k] - plain.data()[k]);
  EXPECT_GT(change, 0.0);
}

TEST(Generate, StopsWhenCancelled) {
  Scene s = grid_scene(17, 1.0, 30);
  s.generator = Generator::constrained;
  s.elements.push_back(singular(SingularType::source, {{Vec3(0.2, 0.1, 0), 0}}));
  const auto space = make_design_space(s);
  std::atomic<bool> cancel{false};
  GenerateOptions o;
  o.parallel = false;
  o.cancel = &cancel;
  int done = 0;
  o.progress = [&](int d, int) {
    done = d;
    if (d == 3) cancel = true;  // a newer request arrives after three frames
  };
  EXPECT_THROW(generate(*space, s, o), GenerationCancelled);
  EXPECT_EQ(done, 3);  // no frame started after the flag was set
  cancel = false;
  done = 0;
  o.progress = [&](int d, int) { done = d; };
  EXPECT_EQ(generate(*space, s, o).frames(), 30);
  EXPECT_EQ(done, 30);
  for (Generator g : {Generator::basis, Generator::spacetime}) {
    s.generator = g;
    cancel = true;
    EXPECT_THROW(generate(*space, s, o), GenerationCancelled) << to_string(g);
  }
}

// Issue 15: the frame a viewer shows comes first, for the generators that solve frame by
// frame; its values are exactly the finished field's frame, and no other frame is done
// before it. Not for spacetime (one solve of all frames) nor for a scene whose edits change
// frames afterwards.
TEST(Generate, MakesTheShownFrameFirstWithItsFinalValues) {
  Scene s = grid_scene(17, 1.0, 12);
  s.elements.push_back(singular(SingularType::source, {{Vec3(-0.3, 0.2, 0), 0}, {Vec3(0.3, -0.1, 0), 1}}));
  s.elements.push_back(singular(SingularType::ccw_center, {{Vec3(0.4, 0.5, 0), 0}}));
  const auto space = make_design_space(s);
  for (Generator g : {Generator::basis, Generator::constrained}) {
    for (bool parallel : {false, true}) {
      s.generator = g;
      GenerateOptions o;
      o.parallel = parallel;
      o.first_frame = 7;
      int calls = 0, done_before = -1, done = 0;
      std::vector<cplx> first;
      o.progress = [&](int d, int) { done = d; };
      o.first_frame_done = [&](int frame, std::span<const cplx> values) {
        ++calls;
        EXPECT_EQ(frame, 7);
        done_before = done;
        first.assign(values.begin(), values.end());
      };
      const Field f = generate(*space, s, o);
      EXPECT_EQ(calls, 1) << to_string(g);
      EXPECT_EQ(done_before, 1) << to_string(g) << ": only the shown frame was done when it was handed out";
      ASSERT_EQ(first.size(), static_cast<size_t>(f.num_vertices()));
      const auto frame = f.frame(7);
      for (size_t v = 0; v < first.size(); ++v) ASSERT_EQ(first[v], frame[v]) << to_string(g) << " vertex " << v;
    }
  }
  int calls = 0;
  GenerateOptions o;
  o.first_frame = 3;
  o.first_frame_done = [&](int, std::span<const cplx>) { ++calls; };
  s.generator = Generator::spacetime;
  generate(*space, s, o);
  s.generator = Generator::basis;
  s.edits = {SmoothEdit{0.5}};
  generate(*space, s, o);
  EXPECT_EQ(calls, 0);
}

TEST(Generate, RefusesFieldsThatWouldNotFitInMemory) {
  // 200 × 200 × 100,000 frames: 112 GB. Refused before the grid is even built.
  Scene s = grid_scene(200, 1.0, 100000);
  s.source_path = "big.json";
  try {
    make_design_space(s);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("big.json: time.frames:"), std::string::npos) << e.what();
  }
}

TEST(Generate, RefusesPointsFarOffTheSurface) {
  // The unit sphere (bounding-box diagonal 2√3, a quarter 0.87): points are moved onto the
  // surface, 0.5 off is taken (along the radius), 2 off is refused with the JSON place —
  // in the elements, the key frames and the deform block.
  auto sphere_scene = [] {
    Scene s;
    s.domain.sphere = SphereSpec{};
    s.domain.sphere->subdivisions = 2;
    s.time.frames = 3;
    s.source_path = "sphere.json";
    return s;
  };
  auto refusal = [](const Scene& s) {
    try {
      generate(*make_design_space(s), s);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  Scene near = sphere_scene();
  near.elements.push_back(singular(SingularType::source, {{{0, 0, 1.5}, 0}}));
  EXPECT_EQ(refusal(near), "");
  Scene far = sphere_scene();
  far.elements.push_back(singular(SingularType::source, {{{0, 0, 1}, 0}, {{0, 3, 0}, 1}}));
  EXPECT_EQ(refusal(far).rfind("sphere.json: elements[0].path[1]: (0, 3, 0) is 2 from the surface, more than a "
                               "quarter of its size (0.866,",
                               0),
            0u)
      << refusal(far);
  Scene keyframe = sphere_scene();
  keyframe.generator = Generator::spacetime;
  keyframe.keyframes.push_back(Keyframe{0.5, {}, {KeyframeStreamline{{{1, 0, 0}, {0, 1, 0}, {0, 0, -3}}, 1.0}}, ""});
  EXPECT_NE(refusal(keyframe).find("sphere.json: keyframes[0].streamlines[0].points[2]: (0, 0, -3) is 2 from"),
            std::string::npos)
      << refusal(keyframe);
  Scene deform = sphere_scene();
  deform.generator = Generator::deform;
  deform.deform = Deform{};
  deform.deform->base.push_back(singular(SingularType::ccw_center, {{{0, 0, 1}, 0}}));
  deform.deform->streamlines.push_back(DeformStreamline{{-4, 0, 0}, {StreamlineKey{}}});
  EXPECT_NE(refusal(deform).find("sphere.json: deform.streamlines[0].seed: (-4, 0, 0) is 3 from"), std::string::npos)
      << refusal(deform);
}

TEST(DesignWarnings, PathEndingInsideTheRangeWithoutBifurcation) {
  Scene s = grid_scene(5, 1.0, 10);
  s.elements.push_back(singular(SingularType::source, {{Vec3(0, 0, 0), 0}, {Vec3(0.2, 0, 0), 0.5}}));
  auto w = design_warnings(s);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("elements[0]"), std::string::npos);
  EXPECT_NE(w[0].find("ends at t = 0.5"), std::string::npos);
  // A saddle path meeting it there provides the other half of the cancellation.
  s.elements.push_back(singular(SingularType::saddle, {{Vec3(0.4, 0, 0), 0}, {Vec3(0.2, 0, 0), 0.5}}));
  EXPECT_TRUE(design_warnings(s).empty());
}

}  // namespace
}  // namespace tvf

namespace tvf {
namespace {

Scene constrained_scene() {
  Scene s = grid_scene(41, 1.0, 12);
  s.generator = Generator::constrained;
  s.falloff = 100;
  s.solver.region_radius = 0.12;
  s.elements.push_back(singular(SingularType::ccw_center, {{Vec3(-0.5, 0.4, 0), 0}, {Vec3(0.4, 0.5, 0), 1}}));
  s.elements.push_back(singular(SingularType::saddle, {{Vec3(0.1, -0.3, 0), 0}}));
  s.elements.push_back(singular(SingularType::source, {{Vec3(-0.6, -0.5, 0), 0}, {Vec3(-0.4, -0.55, 0), 1}}));
  return s;
}

TEST(Constrained, RegionsTakeTheirElementsFieldExactly) {
  const Scene s = constrained_scene();
  const auto space = make_design_space(s);
  GenerateReport report;
  const Field field = generate(*space, s, {}, &report);
  EXPECT_LT(report.residual, 1e-12);
  EXPECT_NE(report.method.find("constrained"), std::string::npos);
  const double d = s.falloff / (space->diameter() * space->diameter());
  int checked = 0;
  for (int j = 0; j < s.time.frames; ++j) {
    const double t = s.time.time(j);
    for (int v = 0; v < space->mesh().num_vertices(); ++v) {
      const Vec3& x = space->mesh().position(v);
      cplx expected(0, 0);
      bool inside = false;
      for (const Element& e : s.elements) {
        const ElementState st = CompiledElement(e).at(t);
        const cplx w(x.x() - st.position.x(), x.y() - st.position.y());
        if (std::abs(w) > s.solver.region_radius) continue;
        inside = true;
        expected += std::exp(-d * std::norm(w)) * st.field(w);
      }
      if (!inside) continue;
      EXPECT_EQ(field.at(j, v), expected) << j << " " << v;
      ++checked;
    }
  }
  EXPECT_GT(checked, 500);
}

TEST(Constrained, OutsideTheRegionsTheFieldIsHarmonic) {
  const Scene s = constrained_scene();
  const auto space = make_design_space(s);
  const Field field = generate(*space, s);
  const ConnectionLaplacian l = connection_laplacian(space->bundle());
  // Free vertices: L z = 0 there. A vertex is free beyond every element's region and
  // its ramp of two mean edge lengths (0.12 + 2 · 0.05); test those at least 0.25 away.
  for (int j : {0, 5, 11}) {
    const double t = s.time.time(j);
    const auto frame = field.frame(j);
    const Eigen::VectorXcd z = Eigen::Map<const Eigen::VectorXcd>(frame.data(), static_cast<Eigen::Index>(frame.size()));
    const Eigen::VectorXcd lz = l.matrix * z;
    for (int v = 0; v < space->mesh().num_vertices(); ++v) {
      const Vec3& x = space->mesh().position(v);
      bool far = true;
      for (const Element& e : s.elements)
        far = far && (x - CompiledElement(e).at(t).position).norm() > 0.25;
      if (far) {
        EXPECT_LT(std::abs(lz[v]), 1e-12) << j << " " << v;
      }
    }
  }
}

// Requirement 1 of the paper (temporal coherence) for the per-frame generator (issue 15):
// a vortex moving steadily past a fixed source on the 65² grid. With regions that switch
// vertices on and off as the vortex crosses them, the far field's direction turned by
// up to 70° between frames and the coherence series' largest step was 2.4× its median;
// with constraints that fade in over a ramp, every frame is a continuous function of the
// vortex's position.
TEST(Constrained, AMovingVortexTurnsTheFieldSmoothlyFromFrameToFrame) {
  Scene s = grid_scene(65, 1.0, 50);
  s.generator = Generator::constrained;
  // 0.012 per frame, as over 1.2 in 100 frames.
  s.elements.push_back(singular(SingularType::ccw_center, {{Vec3(-0.6, -0.3, 0), 0}, {Vec3(0.0, -0.3, 0), 1}}));
  s.elements.push_back(singular(SingularType::source, {{Vec3(0, 0.5, 0), 0}}));
  const auto space = make_design_space(s);
  const Field field = generate(*space, s);
  const Mesh& mesh = space->mesh();
  const int nv = mesh.num_vertices();
  std::vector<std::vector<Singularity>> found;
  for (int j = 0; j < s.time.frames; ++j) found.push_back(find_singularities(space->bundle(), field, j));
  double worst = 0;
  for (int j = 0; j + 1 < s.time.frames; ++j) {
    ASSERT_FALSE(found[static_cast<size_t>(j)].empty());
    for (int v = 0; v < nv; ++v) {
      bool far = true;
      for (int k : {j, j + 1})
        for (const Singularity& p : found[static_cast<size_t>(k)])
          far = far && (mesh.position(v) - p.position).norm() > 0.15;
      if (!far) continue;
      const cplx a = field.at(j, v), b = field.at(j + 1, v);
      worst = std::max(worst, std::abs(std::arg(b / a)));
    }
  }
  EXPECT_LT(worst * 180 / std::numbers::pi, 10.0);
  const std::vector<double> y = coherence(field);
  std::vector<double> sorted = y;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2), sorted.end());
  const double median = sorted[sorted.size() / 2];
  EXPECT_LE(*std::max_element(y.begin(), y.end()), 2 * median);
}

}  // namespace
}  // namespace tvf

#include "tvf/analysis/coherence.h"
#include "tvf/analysis/singularities.h"
#include "tvf/design/keyframes.h"

namespace tvf {
namespace {

Scene keyframe_scene(int n = 33) {
  Scene s = grid_scene(n, 1.0, 40);
  s.generator = Generator::spacetime;
  s.falloff = 40;
  s.solver.tolerance = 1e-10;
  // Regions that meet between the pair: the flow between them is then one trough, as in
  // the normal form (t + x², y), and the pair cancels in the middle.
  s.solver.region_radius = 0.25;
  Keyframe k0, k1;
  k0.t = 0;
  KeyframeElement src;
  src.kind = "singular";
  src.type = SingularType::source;
  src.at = Vec3(0.25, 0, 0);
  KeyframeElement sad;
  sad.kind = "singular";
  sad.jacobian << -1, 0, 0, 1;
  sad.at = Vec3(-0.25, 0, 0);
  k0.elements = {sad, src};
  k0.streamlines = {{{Vec3(-1, -0.7, 0), Vec3(1, -0.7, 0)}, 0.1}, {{Vec3(-1, 0.7, 0), Vec3(1, 0.7, 0)}, 0.1}};
  k1.t = 1;
  k1.streamlines = {{{Vec3(-1, -0.7, 0), Vec3(1, -0.7, 0)}, 0.1}, {{Vec3(-1, 0.7, 0), Vec3(1, 0.7, 0)}, 0.1}};
  s.keyframes = {k0, k1};
  return s;
}

TEST(SpaceTimeGenerator, ReproducesItsKeyFramesExactly) {
  const Scene s = keyframe_scene();
  const auto space = make_design_space(s);
  GenerateReport report;
  const Field field = generate(*space, s, {}, &report);
  EXPECT_LE(report.residual, 1e-10);
  EXPECT_GT(report.iterations, 0);
  const ConnectionLaplacian l = connection_laplacian(space->bundle());
  for (size_t k = 0; k < s.keyframes.size(); ++k) {
    const int j = keyframe_frame(s, s.keyframes[k].t);
    const std::vector<cplx> key = keyframe_field(*space, s, k, l);
    for (int v = 0; v < space->mesh().num_vertices(); ++v)
      EXPECT_EQ(field.at(j, v), key[static_cast<size_t>(v)]) << k << " " << v;
  }
}

// Fig. 4: the saddle–source pair of the first key frame cancels on the way to the
// second, and the change is smooth in time (no spikes in the coherence series, Fig. 18).
TEST(SpaceTimeGenerator, PairCancelsBetweenKeyFramesSmoothly) {
  const Scene s = keyframe_scene(65);
  const auto space = make_design_space(s);
  const Field field = generate(*space, s);
  const auto first = find_singularities(space->bundle(), field, 0);
  ASSERT_EQ(first.size(), 2u);
  EXPECT_EQ(first[0].index + first[1].index, 0);
  EXPECT_TRUE(find_singularities(space->bundle(), field, s.time.frames - 1).empty());
  // The count never grows: pairs only disappear.
  size_t last = first.size();
  for (int j = 1; j < s.time.frames; ++j) {
    const size_t now = find_singularities(space->bundle(), field, j).size();
    EXPECT_LE(now, last) << "frame " << j;
    last = now;
  }
  const std::vector<double> y = coherence(field);
  const double top = *std::max_element(y.begin(), y.end());
  for (size_t i = 1; i < y.size(); ++i) EXPECT_LT(std::abs(y[i] - y[i - 1]), 0.1 * top) << i;
}

TEST(SpaceTimeGenerator, KeyFramesAndMovingElementsCombine) {
  Scene s = keyframe_scene();
  // A vortex crossing the top half while the key frames hold the ends.
  s.elements.push_back(singular(SingularType::ccw_center, {{Vec3(-0.5, 0.45, 0), 0.2}, {Vec3(0.5, 0.45, 0), 0.8}}));
  const auto space = make_design_space(s);
  const Field field = generate(*space, s);
  const CompiledElement el(s.elements[0]);
  for (int j = 10; j <= 30; j += 5) {
    const double t = s.time.time(j);
    const Vec3 p = el.at(t).position;
    bool found = false;
    for (const auto& sg : find_singularities(space->bundle(), field, j))
      found = found || ((sg.position - p).norm() < 0.07 && sg.index == 1);
    EXPECT_TRUE(found) << "frame " << j;
  }
}

// solver.method picks the space-time solve; every method meets the tolerance, so they
// agree; "modes" is refused, naming the key, when an element moves.
TEST(SpaceTimeGenerator, SolverMethodsAgreeAndModesNeedAStillFixedSet) {
  Scene s = keyframe_scene();
  const auto space = make_design_space(s);
  GenerateReport auto_report, cg_report;
  const Field a = generate(*space, s, {}, &auto_report);
  s.solver.method = SolverMethod::cg;
  const Field c = generate(*space, s, {}, &cg_report);
  EXPECT_NE(auto_report.method.find("temporal eigenmodes"), std::string::npos) << auto_report.method;
  EXPECT_NE(cg_report.method.find("CG (temporal line solves)"), std::string::npos) << cg_report.method;
  double scale = 0, diff = 0;
  for (size_t k = 0; k < a.data().size(); ++k) {
    scale = std::max(scale, std::abs(a.data()[k]));
    diff = std::max(diff, std::abs(a.data()[k] - c.data()[k]));
  }
  EXPECT_LT(diff, 1e-7 * scale);

  s.solver.method = SolverMethod::modes;
  s.source_path = "m.json";
  s.elements.push_back(singular(SingularType::ccw_center, {{Vec3(-0.5, 0.45, 0), 0.2}, {Vec3(0.5, 0.45, 0), 0.8}}));
  try {
    generate(*space, s);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("m.json: solver.method:"), std::string::npos) << e.what();
  }
}

TEST(SpaceTimeGenerator, RefusesMeanValueWeights) {
  Scene s = keyframe_scene();
  s.solver.weights = Weights::mean_value;
  s.source_path = "k.json";
  const auto space = make_design_space(s);
  try {
    generate(*space, s);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("k.json: solver.weights:"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace tvf

#include "tvf/scene/scene_json.h"

namespace tvf {
namespace {

Scene deform_scene(const std::string& keys) {
  return parse_scene(R"({"tvf": 1, "domain": {"grid": {"size": [33, 33]}}, "time": {"frames": 11},
    "generator": "deform", "falloff": 10, "solver": {"region_radius": 0.15},
    "deform": {"base": {"elements": [{"kind": "singular", "type": "source", "path": [[0.1, -0.2, 0]]}]}, )" +
                         keys + "}}",
                     "deform.json");
}

TEST(Deform, TransformKeysRotateTheBaseField) {
  const Scene s = deform_scene(R"("transform": [{"t": 1, "sx": 1, "sy": 1, "theta": 3.141592653589793}])");
  const auto space = make_design_space(s);
  const Field f = generate(*space, s);
  for (int j = 0; j < s.time.frames; ++j) {
    const double theta = kPi * s.time.time(j);
    const Mat2 m = transform_matrix({0, 1, 1, theta});
    for (int v = 0; v < space->mesh().num_vertices(); v += 5)
      EXPECT_LT(std::abs(f.at(j, v) - to_complex(m * to_vec2(f.at(0, v)))), 1e-13) << j << " " << v;
  }
  // Source → center → sink (paper Fig. 10).
  const auto type_at = [&](int j) {
    const auto sg = find_singularities(space->bundle(), f, j);
    EXPECT_EQ(sg.size(), 1u) << j;
    return sg.empty() ? SingularityType::saddle : sg[0].type;
  };
  EXPECT_EQ(type_at(0), SingularityType::source);
  EXPECT_EQ(type_at(5), SingularityType::center);
  EXPECT_EQ(type_at(10), SingularityType::sink);
}

TEST(Deform, MatrixKeysInterpolateFromTheIdentity) {
  const Scene s = deform_scene(R"("matrix": [{"t": 0.5, "m": [[2, 0], [0, 0.5]]}, {"t": 1, "m": [[0, -1], [1, 0]]}])");
  const auto space = make_design_space(s);
  const Field f = generate(*space, s);
  Mat2 half, key1, key2;
  half << 1.5, 0, 0, 0.75;  // t = 0.25: half way from I to diag(2, 0.5)
  key1 << 2, 0, 0, 0.5;
  key2 << 0, -1, 1, 0;
  const std::pair<int, Mat2> checks[] = {{0, Mat2::Identity()}, {5, key1}, {10, key2}};
  for (const auto& [j, m] : checks)
    for (int v = 0; v < space->mesh().num_vertices(); v += 7)
      EXPECT_LT(std::abs(f.at(j, v) - to_complex(m * to_vec2(f.at(0, v)))), 1e-13) << j;
  // Frame 2.5 does not exist; check t = 0.2 (frame 2): 0.4 of the way to key 1.
  Mat2 m2 = 0.6 * Mat2::Identity() + 0.4 * key1;
  for (int v = 0; v < space->mesh().num_vertices(); v += 7)
    EXPECT_LT(std::abs(f.at(2, v) - to_complex(m2 * to_vec2(f.at(0, v)))), 1e-13);
  (void)half;
}

TEST(Deform, StreamlineDeformationStartsFromTheBaseField) {
  const Scene plain = deform_scene(R"("transform": [])");
  const Scene moved = deform_scene(
      R"("streamlines": [{"seed": [0.5, 0.3], "keys": [{"t": 1, "translate": [0, -0.3], "rotate": 0.5, "scale": 1}]}])");
  const auto space = make_design_space(plain);
  const Field a = generate(*space, plain);
  GenerateReport report;
  const Field b = generate(*space, moved, {}, &report);
  EXPECT_NE(report.method.find("streamline"), std::string::npos);
  // At t0 the streamline is where it was traced: its tangents agree with V(t0), so the
  // frame is the base field again up to the discretisation of the polyline.
  double diff = 0, norm = 0;
  for (int v = 0; v < space->mesh().num_vertices(); ++v) {
    diff += std::norm(b.at(0, v) - a.at(0, v));
    norm += std::norm(a.at(0, v));
  }
  const double initial = std::sqrt(diff / norm);
  EXPECT_LT(initial, 0.2);
  // Once the streamline has moved, the field differs much more.
  double later = 0;
  for (int v = 0; v < space->mesh().num_vertices(); ++v) later += std::norm(b.at(10, v) - a.at(10, v));
  EXPECT_GT(std::sqrt(later / norm), 2 * initial);
}

}  // namespace
}  // namespace tvf

namespace tvf {
namespace {

// "incompressible": generate() projects after the generator (and the edits); the report
// carries the divergence before and after; generate_unedited and project = false do not.
TEST(Generate, IncompressibleScenesAreProjectedLastAndReported) {
  Scene s;
  s.domain.grid = GridSpec{21, 21, {-1, -1}, {1, 1}};
  s.time.frames = 5;
  SingularElement source;
  source.type = SingularType::source;
  source.jacobian = jacobian_of(SingularType::source);
  source.path = {{Vec3(-0.3, 0.1, 0), 0.0}, {Vec3(0.3, -0.1, 0), 1.0}};
  s.elements.push_back(source);
  SingularElement centre = source;
  centre.type = SingularType::ccw_center;
  centre.jacobian = jacobian_of(SingularType::ccw_center);
  centre.path = {{Vec3(0.4, 0.4, 0), 0.0}};
  s.elements.push_back(centre);
  const auto space = make_design_space(s);
  const Field plain = generate(*space, s);
  for (FluxBoundary b : {FluxBoundary::no_flux, FluxBoundary::open}) {
    s.incompressible = b;
    GenerateReport report;
    const Field field = generate(*space, s, {}, &report);
    ASSERT_TRUE(report.incompressible.has_value());
    EXPECT_EQ(report.incompressible->boundary, b);
    const DivergenceFreeProjector p(space->bundle(), b);
    for (int j = 0; j < s.time.frames; ++j) {
      const double before = p.divergence_rms(plain.frame(j));
      EXPECT_DOUBLE_EQ(report.incompressible->before[static_cast<size_t>(j)], before);
      EXPECT_LT(p.divergence_rms(field.frame(j)), 1e-11 * before);
      EXPECT_LT(report.incompressible->after[static_cast<size_t>(j)], 1e-11 * before);
    }
    EXPECT_EQ(generate_unedited(*space, s).data(), plain.data());
    GenerateOptions off;
    off.project = false;
    GenerateReport none;
    EXPECT_EQ(generate(*space, s, off, &none).data(), plain.data());
    EXPECT_FALSE(none.incompressible.has_value());
  }
}

}  // namespace
}  // namespace tvf

// Regular elements and key-frame streamlines on surfaces, as the designer draws them:
// points picked on the surface, [x, y, z] (and t for pathlines).
#include "tvf/integrate/pathline.h"
#include "tvf/integrate/streamline.h"

namespace tvf {
namespace {

// The point at angle a along the great circle from p towards q (unit vectors).
Vec3 along_great_circle(const Vec3& p, const Vec3& q, double a) {
  const Vec3 u = (q - p.dot(q) * p).normalized();
  return std::cos(a) * p + std::sin(a) * u;
}

// Distance from x to the great circle through p and q (both unit), along the sphere.
double off_great_circle(const Vec3& p, const Vec3& q, const Vec3& x) {
  const Vec3 n = p.cross(q).normalized();
  return std::asin(std::clamp(std::abs(n.dot(x.normalized())), 0.0, 1.0));
}

}  // namespace

TEST(SurfaceDesign, AParticleReleasedOnAPathlineOnTheSphereFollowsIt) {
  // A pathline drawn along a great circle over 0.9 rad, picked at 7 points on the sphere.
  const Vec3 p = Vec3(0.2, -1, 0.1).normalized(), q = Vec3(1, -0.3, 0.3).normalized();
  const double arc = 0.9;
  for (Generator g : {Generator::basis, Generator::constrained, Generator::spacetime}) {
    Scene s;
    s.domain.sphere = SphereSpec{4, 1.0};
    s.time.frames = 21;
    s.generator = g;
    s.falloff = 12;
    RegularElement r;
    for (int k = 0; k <= 6; ++k) r.pathline.push_back({along_great_circle(p, q, arc * k / 6), k / 6.0});
    s.elements.push_back(r);
    const auto space = make_design_space(s);
    const Field field = generate(*space, s);
    PathlineOptions po;
    po.t_start = 0;
    po.t_end = 1;
    const Pathline line = trace_pathline(space->bundle(), field, r.pathline.front().position, po);
    ASSERT_GE(line.times.size(), 10u) << to_string(g);
    EXPECT_NEAR(line.times.back(), 1.0, 1e-9) << to_string(g);
    for (size_t i = 0; i < line.points.size(); ++i) {
      // On the sphere, on the great circle, where the pathline is at that time.
      const Vec3 want = along_great_circle(p, q, arc * line.times[i]);
      EXPECT_NEAR(line.points[i].norm(), 1.0, 0.01);
      EXPECT_LT((line.points[i] - want).norm(), 0.06)
          << to_string(g) << " at t = " << line.times[i] << ": " << line.points[i].transpose() << " instead of "
          << want.transpose();
    }
  }
}

TEST(SurfaceDesign, AKeyFrameStreamlineOnTheSphereIsAStreamlineOfItsFrame) {
  const Vec3 p = Vec3(-0.3, -1, 0.4).normalized(), q = Vec3(0.6, -0.6, -0.2).normalized();
  const double arc = 1.0;
  Scene s;
  s.domain.sphere = SphereSpec{4, 1.0};
  s.time.frames = 11;
  s.generator = Generator::spacetime;
  Keyframe k;
  k.t = 0.5;
  KeyframeStreamline line;
  for (int i = 0; i <= 9; ++i) line.points.push_back(along_great_circle(p, q, arc * i / 9));
  k.streamlines.push_back(line);
  s.keyframes.push_back(k);
  const auto space = make_design_space(s);
  const Field field = generate(*space, s);
  const int j = keyframe_frame(s, k.t);
  StreamlineOptions so;
  so.both_directions = false;
  so.max_length = 0.9 * arc;
  const Streamline traced = trace_streamline(space->bundle(), field.frame(j), line.points.front(), so);
  EXPECT_GT(traced.length(), 0.85 * arc);
  for (const Vec3& x : traced.points) EXPECT_LT(off_great_circle(p, q, x), 0.03) << x.transpose();
  // It runs in the drawn direction, with the key frame's speed 1 along it.
  EXPECT_GT((traced.points.back() - line.points.front()).dot(q - p), 0);
  for (size_t i = 0; i < traced.speeds.size(); i += 5) EXPECT_NEAR(traced.speeds[i], 1.0, 0.15) << i;
}

}  // namespace tvf

namespace tvf {

TEST(GenerateCache, WarmReSolvesAgreeWithColdOnesAndRebuildWhatChanged) {
  Scene s;
  s.domain.grid = GridSpec{17, 17, {-1, -1}, {1, 1}};
  s.time.frames = 12;
  s.generator = Generator::spacetime;
  s.falloff = 8;
  auto key = [](double t, SingularType type, Vec3 at) {
    Keyframe k;
    k.t = t;
    KeyframeElement e;
    e.kind = "singular";
    e.type = type;
    e.at = at;
    k.elements.push_back(e);
    return k;
  };
  s.keyframes = {key(0, SingularType::ccw_center, Vec3(-0.3, 0.1, 0)), key(1, SingularType::source, Vec3(0.3, 0, 0))};
  const auto space = make_design_space(s);
  GenerateCache cache;
  GenerateOptions cached;
  cached.cache = &cache;
  auto worst_difference = [](const Field& a, const Field& b) {
    double worst = 0, largest = 0;
    for (size_t k = 0; k < a.data().size(); ++k) {
      worst = std::max(worst, std::abs(a.data()[k] - b.data()[k]));
      largest = std::max(largest, std::abs(b.data()[k]));
    }
    return worst / largest;
  };
  // Cold, through the cache: the same as without it.
  GenerateReport report;
  const Field first = generate(*space, s, cached, &report);
  EXPECT_LT(worst_difference(first, generate(*space, s)), 1e-12);
  EXPECT_EQ(cache.warm_starts(), 0);
  EXPECT_EQ(report.method.find("warm"), std::string::npos) << report.method;
  // A nudged key-frame element: warm, and the same field as a cold solve to the tolerance.
  s.keyframes[0].elements[0].at = Vec3(-0.28, 0.1, 0);
  const Field warm = generate(*space, s, cached, &report);
  EXPECT_EQ(cache.warm_starts(), 1);
  EXPECT_EQ(cache.reused_laplacians(), 1);
  EXPECT_NE(report.method.find("warm start"), std::string::npos) << report.method;
  EXPECT_LT(worst_difference(warm, generate(*space, s)), 1e-7);
  EXPECT_GT(worst_difference(warm, first), 1e-4);  // it did change
  // Other weights: a new Laplacian, and no warm start from a field of the old one.
  s.solver.weights = Weights::uniform;
  const Field uniform = generate(*space, s, cached);
  EXPECT_EQ(cache.reused_laplacians(), 1);
  EXPECT_EQ(cache.warm_starts(), 1);
  EXPECT_LT(worst_difference(uniform, generate(*space, s)), 1e-12);
  // Another frame count: a new space-time solver, cold again.
  s.time.frames = 9;
  EXPECT_LT(worst_difference(generate(*space, s, cached), generate(*space, s)), 1e-12);
  EXPECT_EQ(cache.warm_starts(), 1);
  // Another domain: everything rebuilt (a field of the right size, as without the cache).
  Scene other = s;
  other.domain.grid = GridSpec{9, 9, {-1, -1}, {1, 1}};
  const auto small = make_design_space(other);
  EXPECT_LT(worst_difference(generate(*small, other, cached), generate(*small, other)), 1e-12);
  // The constrained generator through the cache: the same field, bit for bit, each time.
  other.generator = Generator::constrained;
  SingularElement c;
  c.type = SingularType::ccw_center;
  c.jacobian = jacobian_of(*c.type);
  c.path = {{Vec3(-0.2, 0, 0), 0}, {Vec3(0.3, 0.1, 0), 1}};
  other.elements = {c};
  const Field plain = generate(*small, other);
  EXPECT_EQ(generate(*small, other, cached).data(), plain.data());
  EXPECT_EQ(generate(*small, other, cached).data(), plain.data());
}

// The designer's click with key frames and elements that stay put: moving an element keeps
// the key frames' designed fields (the same inputs) and the solve starts from the last
// result's temporal modes, patched where the fixed set changed; the field is a cold
// generation's to the tolerance. A changed key frame is designed again, the other kept.
TEST(GenerateCache, KeyFramesAreKeptAndAMovedElementKeepsTheModes) {
  Scene s;
  s.domain.grid = GridSpec{25, 25, {-1, -1}, {1, 1}};
  s.time.frames = 16;
  s.generator = Generator::spacetime;
  s.falloff = 8;
  auto key = [](double t, SingularType type, Vec3 at) {
    Keyframe k;
    k.t = t;
    KeyframeElement e;
    e.kind = "singular";
    e.type = type;
    e.at = at;
    k.elements.push_back(e);
    return k;
  };
  s.keyframes = {key(0, SingularType::ccw_center, Vec3(-0.3, 0.1, 0)), key(1, SingularType::source, Vec3(0.3, 0, 0))};
  SingularElement source;
  source.type = SingularType::source;
  source.jacobian = jacobian_of(*source.type);
  source.path = {{Vec3(0.0, -0.5, 0), 0}};
  s.elements = {source};
  const auto space = make_design_space(s);
  GenerateCache cache;
  GenerateOptions cached;
  cached.cache = &cache;
  auto worst_difference = [](const Field& a, const Field& b) {
    double worst = 0, largest = 0;
    for (size_t k = 0; k < a.data().size(); ++k) {
      worst = std::max(worst, std::abs(a.data()[k] - b.data()[k]));
      largest = std::max(largest, std::abs(b.data()[k]));
    }
    return worst / largest;
  };
  GenerateReport report;
  generate(*space, s, cached, &report);
  EXPECT_EQ(cache.reused_keyframes(), 0);
  for (int move = 1; move <= 3; ++move) {
    std::get<SingularElement>(s.elements[0]).path[0].position = Vec3(0.2 * move - 0.3, -0.5 + 0.1 * (move % 2), 0);
    const Field warm = generate(*space, s, cached, &report);
    EXPECT_EQ(cache.reused_keyframes(), 2 * move);
    EXPECT_NE(report.method.find("with the fixed set changed at"), std::string::npos) << report.method;
    EXPECT_LT(worst_difference(warm, generate(*space, s)), 1e-7) << move;
  }
  // A key frame's element moved: that key frame designed again, the other kept.
  s.keyframes[1].elements[0].at = Vec3(0.35, 0.05, 0);
  const Field changed = generate(*space, s, cached, &report);
  EXPECT_EQ(cache.reused_keyframes(), 7);
  EXPECT_LT(worst_difference(changed, generate(*space, s)), 1e-7);
}

}  // namespace tvf
