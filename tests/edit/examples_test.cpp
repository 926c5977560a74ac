// The editing examples show exactly the intended change (issue 5's "must show"): the
// analysis of the design before its edits and after them differ by the edited bifurcation
// alone.
#include "support/test_paths.h"

#include "tvf/analysis/topology.h"
#include "tvf/scene/design_space.h"
#include "tvf/design/generate.h"
#include "tvf/scene/scene_json.h"
#include "tvf/scene/edits.h"
#include "tvf/field/field_sampler.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace tvf {
namespace {

struct BeforeAfter {
  Scene scene;
  std::unique_ptr<DesignSpace> space;
  Topology before, after;
  double cell = 0, dt = 0;
  explicit BeforeAfter(const std::string& example)
      : scene(load_scene(test::source_dir() + "/examples/" + example + "/scene.json")) {
    space = make_design_space(scene);
    before = analyze_topology(space->bundle(), generate_unedited(*space, scene));
    after = analyze_topology(space->bundle(), generate(*space, scene));
    cell = space->mesh().mean_edge_length();
    dt = scene.time.time(1) - scene.time.time(0);
  }
};

// The bifurcation of `list` nearest to b (same kind), and its distance in cells and frames.
const Bifurcation* match(const std::vector<Bifurcation>& list, const Bifurcation& b, double cell, double dt) {
  const Bifurcation* best = nullptr;
  double best_d = 1e300;
  for (const auto& x : list) {
    if (x.kind != b.kind) continue;
    const double d = (x.position - b.position).norm() / cell + std::abs(x.t - b.t) / dt;
    if (d < best_d) best_d = d, best = &x;
  }
  return best && best_d <= 2.0 ? best : nullptr;
}

TEST(EditExamples, BifurcationRemovalRemovesOneBifurcationAndItsTwoPaths) {
  BeforeAfter e("10_bifurcation_removal");
  const std::vector<Edit>& edits = e.scene.edits;
  ASSERT_EQ(edits.size(), 1u);
  const PathPoint at = std::get<RemoveBifurcationEdit>(edits[0]).at;
  ASSERT_EQ(e.before.bifurcations.size(), 4u);
  EXPECT_EQ(e.after.bifurcations.size(), 3u);
  // The two paths the bifurcation joins, with their continuations past type changes (a
  // path whose first point is another's last), are gone; every other path stays.
  const Bifurcation* removed = nullptr;
  for (const auto& b : e.before.bifurcations)
    if ((b.position - at.position).norm() < 0.1 && std::abs(b.t - at.t) < 0.05) removed = &b;
  ASSERT_NE(removed, nullptr);
  std::vector<char> on_track(e.before.paths.size(), 0);
  for (int p : removed->paths) on_track[static_cast<size_t>(p)] = 1;
  for (bool grew = true; grew;) {
    grew = false;
    for (size_t p = 0; p < e.before.paths.size(); ++p)
      for (size_t q = 0; q < e.before.paths.size(); ++q)
        if (on_track[p] && !on_track[q] &&
            e.before.paths[q].points.front().position == e.before.paths[p].points.back().position &&
            e.before.paths[q].points.front().t == e.before.paths[p].points.back().t)
          on_track[q] = grew = true;
  }
  const auto gone = static_cast<size_t>(std::count(on_track.begin(), on_track.end(), 1));
  EXPECT_GE(gone, 2u);
  EXPECT_EQ(e.after.paths.size() + gone, e.before.paths.size());
  for (const Bifurcation& b : e.before.bifurcations) {
    const bool is_removed = &b == removed;
    EXPECT_EQ(match(e.after.bifurcations, b, e.cell, e.dt) == nullptr, is_removed)
        << to_string(b.kind) << " at t = " << b.t;
  }
}

TEST(EditExamples, BifurcationMoveMovesItToTheCorner) {
  BeforeAfter e("11_bifurcation_move");
  const std::vector<Edit>& edits = e.scene.edits;
  ASSERT_EQ(edits.size(), 1u);
  const auto& move = std::get<MoveBifurcationEdit>(edits[0]);
  ASSERT_EQ(e.before.bifurcations.size(), 1u);
  ASSERT_EQ(e.after.bifurcations.size(), 1u);
  const Bifurcation& b = e.after.bifurcations[0];
  EXPECT_EQ(b.kind, BifurcationKind::creation);
  EXPECT_LT((b.position - move.to.position).norm(), 2 * e.cell);
  EXPECT_LT(std::abs(b.t - move.to.t), 2 * e.dt);
  EXPECT_EQ(e.after.paths.size(), e.before.paths.size());
  // Outside the window the singularities are where they were.
  const int last = static_cast<int>(std::lround((move.to.t + move.window) / e.dt)) + 1;
  for (int j : {0, 20, last, last + 10, e.scene.time.frames - 1}) {
    const auto& a = e.before.singularities[static_cast<size_t>(j)];
    const auto& c = e.after.singularities[static_cast<size_t>(j)];
    ASSERT_EQ(a.size(), c.size()) << "frame " << j;
    for (size_t k = 0; k < a.size(); ++k) EXPECT_LT((a[k].position - c[k].position).norm(), e.cell) << j;
  }
}

TEST(EditExamples, BifurcationMoveOnTheSphereMovesItAQuarterTurnRoundThePole) {
  BeforeAfter e("20_sphere_bifurcation_move");
  const std::vector<Edit>& edits = e.scene.edits;
  ASSERT_EQ(edits.size(), 1u);
  const auto& move = std::get<MoveBifurcationEdit>(edits[0]);
  const Vec3 to = surface_position(e.space->mesh(), e.space->locate(move.to.position));
  // The designed creation, before; the same creation at the new place and time, after,
  // and none left at the old place.
  auto creations_near = [&](const Topology& topo, const Vec3& x, double t) {
    std::vector<const Bifurcation*> out;
    for (const auto& b : topo.bifurcations)
      if (b.kind == BifurcationKind::creation && (b.position - x).norm() < 2 * e.cell && std::abs(b.t - t) < 2 * e.dt)
        out.push_back(&b);
    return out;
  };
  const auto original = creations_near(e.before, move.at.position.normalized(), move.at.t);
  ASSERT_EQ(original.size(), 1u);
  EXPECT_EQ(creations_near(e.after, to, move.to.t).size(), 1u);
  for (const auto& b : e.after.bifurcations)
    EXPECT_GT((b.position - original[0]->position).norm(), 3 * e.cell) << b.position.transpose() << " t = " << b.t;
  // Every other bifurcation stays where it was.
  for (const Bifurcation& b : e.before.bifurcations) {
    if (&b == original[0]) continue;
    EXPECT_NE(match(e.after.bifurcations, b, e.cell, e.dt), nullptr) << b.t;
  }
  EXPECT_EQ(e.after.bifurcations.size(), e.before.bifurcations.size());
  // Outside the window every singularity is where it was (within an edge length).
  const int last = static_cast<int>(std::lround((move.to.t + move.window) / e.dt)) + 1;
  for (int j : {0, 20, last, last + 10, e.scene.time.frames - 1}) {
    const auto& a = e.before.singularities[static_cast<size_t>(j)];
    const auto& c = e.after.singularities[static_cast<size_t>(j)];
    ASSERT_EQ(a.size(), c.size()) << "frame " << j;
    for (size_t k = 0; k < a.size(); ++k) EXPECT_LT((a[k].position - c[k].position).norm(), e.cell) << j;
  }
}

}  // namespace
}  // namespace tvf
