#include "tvf/design/element_field.h"

#include <gtest/gtest.h>

#include <cmath>

namespace tvf {
namespace {

// Zeros and Jacobians of the normal forms (DESIGN §4).
struct NormalFormCase {
  BifurcationType type;
  double t;          // template time at which the two zeros exist
  double source_or_sink_x;  // x of the node
  double saddle_x;
  double node_trace_sign;   // +1 source, −1 sink
};

Mat2 numeric_jacobian(BifurcationType type, double x, double y, double t) {
  const double h = 1e-6;
  Mat2 j;
  j.col(0) = (bifurcation_normal_form(type, x + h, y, t) - bifurcation_normal_form(type, x - h, y, t)) / (2 * h);
  j.col(1) = (bifurcation_normal_form(type, x, y + h, t) - bifurcation_normal_form(type, x, y - h, t)) / (2 * h);
  return j;
}

TEST(BifurcationNormalForms, ZerosAtPlusMinusSqrtWithTheRightTypes) {
  const double a = 0.36, r = std::sqrt(a);
  const NormalFormCase cases[] = {
      {BifurcationType::saddle_source_cancellation, -a, +r, -r, +1},
      {BifurcationType::saddle_sink_creation, +a, +r, -r, -1},
      {BifurcationType::saddle_source_creation, +a, +r, -r, +1},
      {BifurcationType::saddle_sink_cancellation, -a, +r, -r, -1},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(to_string(c.type));
    EXPECT_LT(bifurcation_normal_form(c.type, c.source_or_sink_x, 0, c.t).norm(), 1e-15);
    EXPECT_LT(bifurcation_normal_form(c.type, c.saddle_x, 0, c.t).norm(), 1e-15);
    const Mat2 jn = numeric_jacobian(c.type, c.source_or_sink_x, 0, c.t);
    EXPECT_GT(jn.determinant(), 0);
    EXPECT_GT(c.node_trace_sign * jn.trace(), 0);
    EXPECT_LT(numeric_jacobian(c.type, c.saddle_x, 0, c.t).determinant(), 0);
    // On the other side of t = 0 there is no zero at all: |V| ≥ |t| > 0 on y = 0.
    for (double x = -2; x <= 2; x += 0.01)
      EXPECT_GT(bifurcation_normal_form(c.type, x, 0, -c.t).norm(), 0.99 * a);
  }
}

TEST(BifurcationNormalForms, HopfCycleOfRadiusSqrtMuAroundAFocusOfTraceTwoMu) {
  // On the circle r = √|μ| the Hopf forms are tangent to it at speed r (angular velocity 1):
  // the cycle; the focus at 0 has the Jacobian [[μ, −1], [1, μ]].
  for (const auto& [type, mu] : {std::pair{BifurcationType::hopf_supercritical, 0.49},
                                 std::pair{BifurcationType::hopf_subcritical, -0.49}}) {
    SCOPED_TRACE(to_string(type));
    const double r = std::sqrt(std::abs(mu));
    for (double a = 0; a < 6.28; a += 0.1) {
      const Vec2 x(r * std::cos(a), r * std::sin(a));
      const Vec2 v = bifurcation_normal_form(type, x.x(), x.y(), mu);
      EXPECT_NEAR(v.dot(x), 0.0, 1e-15);
      EXPECT_NEAR(x.x() * v.y() - x.y() * v.x(), r * r, 1e-15);  // counter-clockwise, |v| = r
    }
    EXPECT_LT(bifurcation_normal_form(type, 0, 0, mu).norm(), 1e-300);
    Mat2 expected;
    expected << mu, -1, 1, mu;
    EXPECT_LT((numeric_jacobian(type, 0, 0, mu) - expected).norm(), 1e-8);
    // Inside the cycle the flow moves toward it (supercritical: outward, from the repelling
    // focus) or away from it (subcritical: inward, to the attracting focus).
    const double sigma = type == BifurcationType::hopf_supercritical ? 1.0 : -1.0;
    EXPECT_GT(sigma * bifurcation_normal_form(type, 0.5 * r, 0, mu).x(), 0);
    EXPECT_LT(sigma * bifurcation_normal_form(type, 1.5 * r, 0, mu).x(), 0);
  }
}

TEST(BifurcationElement, HopfCycleRadiusIsScaleTimesSqrtMu) {
  BifurcationElement b;
  b.type = BifurcationType::hopf_supercritical;
  b.at = {Vec3(0.3, -0.2, 0), 0.6};
  b.scale = 0.2;
  b.time_scale = 0.5;
  b.angle = 0.9;
  const ElementState st = CompiledElement{Element{b}}.at(1.1);  // μ = 1
  for (double a = 0; a < 6.28; a += 0.3) {
    const cplx w = 0.2 * std::polar(1.0, a);
    EXPECT_NEAR((st.field(w) * std::conj(w)).real(), 0.0, 1e-15);  // tangent to the circle
    EXPECT_NEAR(std::abs(st.field(w)), 0.2, 1e-15);                // angular velocity 1
  }
}

TEST(BifurcationElement, RotatedAndScaledTemplateMovesAlongItsAxis) {
  // Element at p, scale s, time scale τ, axis θ: zeros at p ± s·√(−t′)·(cos θ, sin θ)
  // with t′ = (t − t0)/τ for a saddle–source cancellation.
  BifurcationElement b;
  b.type = BifurcationType::saddle_source_cancellation;
  b.at = {Vec3(0.3, -0.2, 0), 0.6};
  b.scale = 0.2;
  b.time_scale = 0.5;
  b.angle = 0.9;
  const CompiledElement el{Element{b}};
  for (double t : {0.0, 0.2, 0.4, 0.55}) {
    const ElementState st = el.at(t);
    ASSERT_TRUE(st.active);
    const double tp = (t - b.at.t) / b.time_scale;
    const cplx axis = std::polar(1.0, b.angle);
    const cplx node = b.scale * std::sqrt(-tp) * axis;  // relative to p
    const cplx saddle = -node;
    EXPECT_LT(std::abs(st.field(node)), 1e-14) << t;
    EXPECT_LT(std::abs(st.field(saddle)), 1e-14) << t;
    EXPECT_EQ(st.position, b.at.position);
  }
  // After t0 the pair is gone: no zero along the axis.
  const ElementState after = el.at(0.8);
  for (double s = -1; s <= 1; s += 0.01)
    EXPECT_GT(std::abs(after.field(s * std::polar(1.0, b.angle))), 0.0);
}

TEST(SingularElement, LinearFieldIsTransformedJacobian) {
  SingularElement s;
  s.type = SingularType::saddle;
  s.jacobian = jacobian_of(SingularType::saddle);
  s.path = {{Vec3(-0.5, 0, 0), 0.0}, {Vec3(0.5, 0, 0), 1.0}};
  s.transform = {{0.0, 1, 1, 0}, {1.0, 2, 0.5, kPi / 2}};
  const CompiledElement el{Element{s}};
  EXPECT_EQ(el.index(), -1);
  const ElementState st = el.at(0.5);
  EXPECT_LT((st.position - Vec3(0, 0, 0)).norm(), 1e-15);
  const Mat2 m = transform_matrix(interpolate_transform(s.transform, 0.5));
  const Mat2 expected = m.transpose() * s.jacobian * m;
  EXPECT_LT((st.field.matrix - expected).norm(), 1e-15);
  const cplx w(0.3, -0.7);
  EXPECT_LT(std::abs(st.field(w) - to_complex(expected * to_vec2(w))), 1e-15);
  EXPECT_FALSE(el.active(1.2));
}

TEST(SingularElement, NamedTypesHaveTheirIndices) {
  for (auto [type, index] : {std::pair{SingularType::source, 1}, {SingularType::sink, 1},
                             {SingularType::saddle, -1}, {SingularType::ccw_center, 1},
                             {SingularType::cw_center, 1}, {SingularType::repelling_focus, 1},
                             {SingularType::attracting_focus, 1}}) {
    SingularElement s;
    s.type = type;
    s.jacobian = jacobian_of(type);
    s.path = {{Vec3::Zero(), 0.0}};
    EXPECT_EQ(CompiledElement(Element{s}).index(), index) << to_string(type);
  }
}

TEST(RegularElement, VelocityIsPathDerivativeAndAttachmentPullsTowardsThePath) {
  RegularElement r;
  r.pathline = {{Vec3(-1, 0, 0), 0.0}, {Vec3(1, 0, 0), 1.0}};
  r.attach = 3.0;
  const CompiledElement el{Element{r}};
  const ElementState st = el.at(0.5);
  EXPECT_LT(std::abs(st.field.velocity - cplx(2, 0)), 1e-14);
  // On the path: the velocity itself.
  EXPECT_LT(std::abs(st.field(cplx(0.4, 0)) - cplx(2, 0)), 1e-14);
  // Above the path (y′ = 0.1): pulled down by c·|V|·y′ = 0.6.
  EXPECT_LT(std::abs(st.field(cplx(0, 0.1)) - cplx(2, -0.6)), 1e-14);
  EXPECT_LT(std::abs(st.field(cplx(0, -0.1)) - cplx(2, 0.6)), 1e-14);
  EXPECT_FALSE(el.active(-0.1));
}

}  // namespace
}  // namespace tvf
