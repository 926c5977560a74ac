// Every example scene generates, and its field holds the singularities the scene designs,
// where it puts them (the "must show"): each singular element's zero with its
// index, and each bifurcation's node and saddle while the template is well resolved; and
// the topology analysis finds every designed feature (check_design: paths over the whole
// life span with compatible types, bifurcations of the right kind at the right place and
// time, key-frame and deformed elements).
#include "support/test_paths.h"

#include "tvf/analysis/singularities.h"
#include "tvf/analysis/topology.h"
#include "tvf/design/design_check.h"
#include "tvf/design/element_field.h"
#include "tvf/design/generate.h"
#include "tvf/design/keyframes.h"
#include "tvf/scene/scene_json.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>

#include <filesystem>

namespace tvf {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> example_scenes() {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(test::source_dir() + "/examples"))
    if (fs::exists(e.path() / "scene.json")) out.push_back((e.path() / "scene.json").string());
  std::sort(out.begin(), out.end());
  return out;
}

// Nearest found singularity to x and its distance.
std::pair<const Singularity*, double> nearest(const std::vector<Singularity>& found, const Vec3& x) {
  const Singularity* best = nullptr;
  double d = 1e300;
  for (const auto& s : found) {
    const double e = (s.position - x).norm();
    if (e < d) d = e, best = &s;
  }
  return {best, d};
}

// One test per example (its folder's name), so that each reports on its own and ctest
// spreads them over the cores instead of running every example's solve in one test.
class EveryExample : public ::testing::TestWithParam<std::string> {};

TEST(Examples, ThereAreExamples) { EXPECT_GE(example_scenes().size(), 3u); }

TEST_P(EveryExample, HasItsDesignedSingularities) {
  const std::string path = GetParam();
  SCOPED_TRACE(path);
  const Scene scene = load_scene(path);
  const auto space = make_design_space(scene);
  // The design before its edits (the edits move or remove designed features on purpose;
  // tests/edit/examples_test.cpp checks what they do).
  GenerateReport report;
  const Field field = generate_unedited(*space, scene, {}, &report);
  // Within a couple of edge lengths: the zero of a sampled field moves by O(h), and the
  // neighbouring elements push it a little further.
  const double tol = 2.5 * space->mesh().mean_edge_length();
  int checked = 0;
  for (int j = 0; j < scene.time.frames; j += 9) {
    const double t = scene.time.time(j);
    const auto found = find_singularities(space->bundle(), field, j);
    for (size_t k = 0; k < scene.elements.size(); ++k) {
      const Element& e = scene.elements[k];
      const CompiledElement el(e);
      if (!el.active(t)) continue;
      const ElementState st = el.at(t);
      if (std::holds_alternative<SingularElement>(e)) {
        const SurfacePoint p = space->locate(st.position);
        const Vec3 x = surface_position(space->mesh(), p);
        const auto [s, d] = nearest(found, x);
        ASSERT_NE(s, nullptr);
        EXPECT_LT(d, tol) << "elements[" << k << "] at frame " << j;
        EXPECT_EQ(s->index, el.index()) << "elements[" << k << "] at frame " << j;
        ++checked;
      } else if (const auto* b = std::get_if<BifurcationElement>(&e)) {
        if (is_hopf(b->type)) {
          // A Hopf template's focus stays at its point (its cycle: periodic_orbits_test).
          const Vec3 x = surface_position(space->mesh(), space->locate(b->at.position));
          const auto [s, d] = nearest(found, x);
          ASSERT_NE(s, nullptr);
          EXPECT_LT(d, tol) << "elements[" << k << "] at frame " << j;
          EXPECT_EQ(s->index, 1) << "elements[" << k << "] at frame " << j;
          ++checked;
          continue;
        }
        if (!space->planar()) continue;
        const bool creation = b->type == BifurcationType::saddle_sink_creation ||
                              b->type == BifurcationType::saddle_source_creation;
        const double arg = creation ? st.field.local_time : -st.field.local_time;
        if (arg < 0.3 || arg > 2.5) continue;
        const cplx off = b->scale * std::sqrt(arg) * st.field.axis;
        for (double sign : {1.0, -1.0}) {
          const Vec3 x = b->at.position + sign * Vec3(off.real(), off.imag(), 0);
          const auto [s, d] = nearest(found, x);
          ASSERT_NE(s, nullptr);
          EXPECT_LT(d, 2 * tol) << "elements[" << k << "] at frame " << j;
          ++checked;
        }
      }
    }
  }
  // Key frames: every singular element of a key frame is in its frame.
  for (size_t k = 0; k < scene.keyframes.size(); ++k) {
    const int j = keyframe_frame(scene, scene.keyframes[k].t);
    const auto found = find_singularities(space->bundle(), field, j);
    for (const KeyframeElement& e : scene.keyframes[k].elements) {
      if (e.kind != "singular") continue;
      const Mat2 jac = e.type ? jacobian_of(*e.type) : e.jacobian;
      const auto [s, d] = nearest(found, surface_position(space->mesh(), space->locate(e.at)));
      ASSERT_NE(s, nullptr);
      EXPECT_LT(d, tol) << "keyframes[" << k << "]";
      EXPECT_EQ(s->index, jac.determinant() > 0 ? 1 : -1) << "keyframes[" << k << "]";
      ++checked;
    }
  }
  // Deformation: the base field's singular elements are in the first frame.
  if (scene.generator == Generator::deform) {
    nlohmann::json j = scene_to_json(scene);
    j["elements"] = j["deform"]["base"]["elements"];
    j["generator"] = "constrained";
    j.erase("deform");
    const Scene base = scene_from_json(j, "base");
    const auto found = find_singularities(space->bundle(), field, 0);
    for (const Element& e : base.elements) {
      const auto* s = std::get_if<SingularElement>(&e);
      if (!s) continue;
      const auto [f, d] = nearest(found, s->path.front().position);
      ASSERT_NE(f, nullptr);
      EXPECT_LT(d, tol);
      EXPECT_EQ(f->index, CompiledElement(e).index());
      ++checked;
    }
  }
  // An application example may design regular flow only (example 13, the crowd's
  // looping pathline; example 16, key frames of streamlines only): then there is no
  // singularity to find.
  const bool keyframe_singularities = std::any_of(
      scene.keyframes.begin(), scene.keyframes.end(), [](const Keyframe& k) {
        return std::any_of(k.elements.begin(), k.elements.end(),
                           [](const KeyframeElement& e) { return e.kind == "singular"; });
      });
  const bool designs_singularities =
      keyframe_singularities || scene.generator == Generator::deform ||
      std::any_of(scene.elements.begin(), scene.elements.end(),
                  [](const Element& e) { return !std::holds_alternative<RegularElement>(e); });
  if (!designs_singularities) return;
  EXPECT_GT(checked, 0);

  // The analysis finds every designed feature (of the design without its edits).
  Scene unedited = scene;
  unedited.edits.clear();
  const Topology topology = analyze_topology(space->bundle(), field);
  const DesignCheck check = check_design(unedited, *space, field, topology);
  EXPECT_FALSE(check.designed.empty());
  EXPECT_TRUE(check.all_found()) << check.summary();
  for (const DesignedFeature& f : check.designed) {
    EXPECT_FALSE(f.paths.empty()) << f.source;
    if (f.kind == FeatureKind::singularity) {
      EXPECT_EQ(f.frames_matched, f.frames) << f.source;
    }
  }
  if (scene.edits.empty()) return;
  // The edited design: what an edit removes is absent ("removed as edited"), what it
  // moves is at its new place and time, everything else as designed.
  const Field edited = generate(*space, scene);
  const DesignCheck after = check_design(scene, *space, edited, analyze_topology(space->bundle(), edited));
  EXPECT_TRUE(after.all_found()) << after.summary();
  int changed = 0;
  for (const DesignedFeature& f : after.designed) {
    if (f.edit.empty()) continue;
    ++changed;
    EXPECT_TRUE(f.expected_absent || f.moved) << f.source;
    EXPECT_EQ(f.paths.empty(), f.expected_absent) << f.source;
  }
  EXPECT_GT(changed, 0) << after.summary();
  // The unedited field does not pass the edited design's check: the removed bifurcation
  // is still there, the moved one is not at its new place.
  const DesignCheck before = check_design(scene, *space, field, topology);
  EXPECT_FALSE(before.all_found()) << before.summary();
  for (const DesignedFeature& f : before.designed)
    if (!f.edit.empty()) {
      EXPECT_FALSE(f.found) << f.source;
      EXPECT_NE(f.note.find(f.expected_absent ? "still there" : "where " + f.edit + " moves it"), std::string::npos)
          << f.note;
    }
}

INSTANTIATE_TEST_SUITE_P(Examples, EveryExample, ::testing::ValuesIn(example_scenes()),
                         [](const ::testing::TestParamInfo<std::string>& scene) {
                           std::string name = fs::path(scene.param).parent_path().filename().string();
                           for (char& c : name)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return name;
                         });

}  // namespace
}  // namespace tvf

namespace tvf {
namespace {

SingularityType expected_type(SingularType t) {
  switch (t) {
    case SingularType::source: return SingularityType::source;
    case SingularType::sink: return SingularityType::sink;
    case SingularType::saddle: return SingularityType::saddle;
    case SingularType::ccw_center:
    case SingularType::cw_center: return SingularityType::center;
    case SingularType::repelling_focus: return SingularityType::repelling_focus;
    case SingularType::attracting_focus: return SingularityType::attracting_focus;
  }
  return SingularityType::source;
}

// The constrained generator keeps every designed singularity at its place with its type
// in every frame (issue 3's "must show").
TEST(Examples, ConstrainedKeepsEverySingularElementsPlaceAndTypeInEveryFrame) {
  const Scene scene = load_scene(test::source_dir() + "/examples/05_constrained_elements/scene.json");
  ASSERT_EQ(scene.generator, Generator::constrained);
  const auto space = make_design_space(scene);
  const Field field = generate(*space, scene);
  const double tol = 1.0 * space->mesh().mean_edge_length();
  int checked = 0;
  for (int j = 0; j < scene.time.frames; ++j) {
    const double t = scene.time.time(j);
    const auto found = find_singularities(space->bundle(), field, j);
    for (size_t k = 0; k < scene.elements.size(); ++k) {
      const auto* s = std::get_if<SingularElement>(&scene.elements[k]);
      if (!s || !s->type) continue;
      const CompiledElement el(scene.elements[k]);
      if (!el.active(t)) continue;
      const auto [f, d] = nearest(found, el.at(t).position);
      ASSERT_NE(f, nullptr);
      EXPECT_LT(d, tol) << "elements[" << k << "] at frame " << j;
      EXPECT_EQ(f->type, expected_type(*s->type)) << "elements[" << k << "] at frame " << j << ": "
                                                  << to_string(f->type);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 300);
}

}  // namespace
}  // namespace tvf
