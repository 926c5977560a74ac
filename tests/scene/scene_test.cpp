#include "tvf/scene/scene.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <filesystem>

namespace tvf {
namespace {

const SingularType kAllSingular[] = {SingularType::source,          SingularType::sink,
                                     SingularType::saddle,          SingularType::ccw_center,
                                     SingularType::cw_center,       SingularType::repelling_focus,
                                     SingularType::attracting_focus};

TEST(SceneNames, AreTheExactStringsOfTheFormat) {
  EXPECT_STREQ(to_string(SingularType::source), "source");
  EXPECT_STREQ(to_string(SingularType::sink), "sink");
  EXPECT_STREQ(to_string(SingularType::saddle), "saddle");
  EXPECT_STREQ(to_string(SingularType::ccw_center), "ccw_center");
  EXPECT_STREQ(to_string(SingularType::cw_center), "cw_center");
  EXPECT_STREQ(to_string(SingularType::repelling_focus), "repelling_focus");
  EXPECT_STREQ(to_string(SingularType::attracting_focus), "attracting_focus");
  EXPECT_STREQ(to_string(BifurcationType::saddle_source_cancellation), "saddle_source_cancellation");
  EXPECT_STREQ(to_string(BifurcationType::saddle_sink_creation), "saddle_sink_creation");
  EXPECT_STREQ(to_string(BifurcationType::saddle_source_creation), "saddle_source_creation");
  EXPECT_STREQ(to_string(BifurcationType::saddle_sink_cancellation), "saddle_sink_cancellation");
  EXPECT_STREQ(to_string(BifurcationType::hopf_supercritical), "hopf_supercritical");
  EXPECT_STREQ(to_string(BifurcationType::hopf_subcritical), "hopf_subcritical");
  EXPECT_STREQ(to_string(Generator::basis), "basis");
  EXPECT_STREQ(to_string(Generator::constrained), "constrained");
  EXPECT_STREQ(to_string(Generator::spacetime), "spacetime");
  EXPECT_STREQ(to_string(Generator::deform), "deform");
  EXPECT_STREQ(to_string(Weights::cotan), "cotan");
  EXPECT_STREQ(to_string(Weights::uniform), "uniform");
  EXPECT_STREQ(to_string(Weights::mean_value), "mean_value");
}

TEST(SceneNames, FromStringInvertsToString) {
  for (SingularType t : kAllSingular) EXPECT_EQ(singular_type_from_string(to_string(t)), t);
  for (BifurcationType t :
       {BifurcationType::saddle_source_cancellation, BifurcationType::saddle_sink_creation,
        BifurcationType::saddle_source_creation, BifurcationType::saddle_sink_cancellation,
        BifurcationType::hopf_supercritical, BifurcationType::hopf_subcritical})
    EXPECT_EQ(bifurcation_type_from_string(to_string(t)), t);
  for (Generator g : {Generator::basis, Generator::constrained, Generator::spacetime, Generator::deform})
    EXPECT_EQ(generator_from_string(to_string(g)), g);
  for (Weights w : {Weights::cotan, Weights::uniform, Weights::mean_value})
    EXPECT_EQ(weights_from_string(to_string(w)), w);
}

TEST(SceneNames, UnknownOrMisspelledNamesAreRejected) {
  // Exact matching: no case folding, no trimming, no "center" for the analysis type.
  EXPECT_EQ(singular_type_from_string("Source"), std::nullopt);
  EXPECT_EQ(singular_type_from_string("center"), std::nullopt);
  EXPECT_EQ(singular_type_from_string(" sink"), std::nullopt);
  EXPECT_EQ(singular_type_from_string(""), std::nullopt);
  EXPECT_EQ(bifurcation_type_from_string("saddle_sink"), std::nullopt);
  EXPECT_EQ(generator_from_string("Basis"), std::nullopt);
  EXPECT_EQ(weights_from_string("mean-value"), std::nullopt);
}

Mat2 m(double a, double b, double c, double d) {
  Mat2 r;
  r << a, b, c, d;
  return r;
}

TEST(JacobianOf, IsTheTableOfTheFormat) {
  EXPECT_EQ(jacobian_of(SingularType::source), m(1, 0, 0, 1));
  EXPECT_EQ(jacobian_of(SingularType::sink), m(-1, 0, 0, -1));
  EXPECT_EQ(jacobian_of(SingularType::saddle), m(1, 0, 0, -1));
  EXPECT_EQ(jacobian_of(SingularType::ccw_center), m(0, -1, 1, 0));
  EXPECT_EQ(jacobian_of(SingularType::cw_center), m(0, 1, -1, 0));
  EXPECT_EQ(jacobian_of(SingularType::repelling_focus), m(1, -1, 1, 1));
  EXPECT_EQ(jacobian_of(SingularType::attracting_focus), m(-1, -1, 1, -1));
}

TEST(JacobianOf, EigenvaluesClassifyEachType) {
  // The linear field J x has the named singularity at 0: the classification of DESIGN §6.
  for (SingularType t : kAllSingular) {
    const Eigen::Vector2cd ev = jacobian_of(t).eigenvalues();
    const double det = jacobian_of(t).determinant();
    const double tr = jacobian_of(t).trace();
    SCOPED_TRACE(to_string(t));
    switch (t) {
      case SingularType::source: EXPECT_TRUE(det > 0 && tr > 0 && ev.imag().isZero()); break;
      case SingularType::sink: EXPECT_TRUE(det > 0 && tr < 0 && ev.imag().isZero()); break;
      case SingularType::saddle: EXPECT_LT(det, 0); break;
      case SingularType::ccw_center:
      case SingularType::cw_center: EXPECT_TRUE(det > 0 && tr == 0); break;
      case SingularType::repelling_focus: EXPECT_TRUE(tr > 0 && ev.imag().cwiseAbs().minCoeff() > 0); break;
      case SingularType::attracting_focus: EXPECT_TRUE(tr < 0 && ev.imag().cwiseAbs().minCoeff() > 0); break;
    }
  }
  // Orientation: ccw turns (1, 0) to (0, 1), cw to (0, −1); both foci turn counter-clockwise
  // with equal radial and angular rates.
  EXPECT_EQ(jacobian_of(SingularType::ccw_center) * Vec2(1, 0), Vec2(0, 1));
  EXPECT_EQ(jacobian_of(SingularType::cw_center) * Vec2(1, 0), Vec2(0, -1));
  EXPECT_EQ(jacobian_of(SingularType::repelling_focus) * Vec2(1, 0), Vec2(1, 1));
  EXPECT_EQ(jacobian_of(SingularType::attracting_focus) * Vec2(1, 0), Vec2(-1, 1));
}

TEST(SceneResolvePath, IsRelativeToTheSceneFilesFolder) {
  Scene s;
  s.domain.mesh = "meshes/bunny.obj";
  s.source_path = "/data/scenes/bunny.json";
  EXPECT_EQ(s.resolved_mesh_path(), "/data/scenes/meshes/bunny.obj");
  s.source_path = "scenes/bunny.json";
  EXPECT_EQ(s.resolved_mesh_path(), "scenes/meshes/bunny.obj");
  s.domain.mesh = "../bunny.obj";
  EXPECT_EQ(s.resolved_mesh_path(), "scenes/../bunny.obj");
  EXPECT_EQ(s.resolve_path("fields/key.tvff"), "scenes/fields/key.tvff");
}

TEST(SceneResolvePath, AbsolutePathsAndCodeScenesAreUnchanged) {
  Scene s;
  s.domain.mesh = "/abs/bunny.obj";
  s.source_path = "/data/scenes/bunny.json";
  EXPECT_EQ(s.resolved_mesh_path(), "/abs/bunny.obj");
  s.domain.mesh = "bunny.obj";
  s.source_path = "scene.json";  // a scene in the working folder
  EXPECT_EQ(s.resolved_mesh_path(), "bunny.obj");
  s.source_path.clear();  // built in code
  EXPECT_EQ(s.resolved_mesh_path(), "bunny.obj");
  EXPECT_EQ(s.label(), "scene");
  s.domain.mesh.clear();
  s.source_path = "/data/scenes/x.json";
  EXPECT_EQ(s.resolved_mesh_path(), "");
  EXPECT_EQ(s.label(), "/data/scenes/x.json");
}

}  // namespace
}  // namespace tvf

#include "tvf/core/error.h"
#include "tvf/scene/design_space.h"

#include <string>

namespace tvf {
namespace {

// domain.mesh with a name the file system refuses: an input error naming the key (it was
// an internal error, exit 2, from std::filesystem::exists).
TEST(DesignSpace, AMeshNameTooLongForTheFileSystemIsAnInputError) {
  Scene scene;
  scene.domain.mesh = std::string(300, 'm') + ".off";
  try {
    make_design_space(scene);
    FAIL() << "no error thrown";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("scene: domain.mesh: the mesh file '"), std::string::npos) << what;
    EXPECT_NE(what.find("' cannot be used: File name too long"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace tvf
