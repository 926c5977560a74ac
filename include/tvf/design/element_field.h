#pragma once
// Design elements as fields (paper §5.1–5.2, DESIGN §4). An element at time t is a point
// p(t) and a basis field in its local planar frame: the local coordinate w of a point is
// x − p(t) on planar domains and the log map log_p(x) on surfaces; the vector it gives is
// expressed in the same frame (carried back to each vertex by the log map's transport).
// The falloff exp(−d‖w‖²) is applied by the generator, not here.
#include "tvf/design/hermite_path.h"
#include "tvf/scene/scene.h"

#include <string>

namespace tvf {

// An element's basis field at one time, without falloff: w (local coordinate, world
// units) ↦ vector in the element's frame.
struct LocalField {
  enum class Kind { linear, regular, bifurcation };
  Kind kind = Kind::linear;
  Mat2 matrix = Mat2::Zero();   // linear: v = M(t)ᵀ J M(t) w
  cplx velocity{0, 0};          // regular: V(t) = dP/dt in the element's frame
  double attach = 0.0;          // regular: attachment strength c
  BifurcationType bifurcation = BifurcationType::saddle_sink_creation;
  double scale = 1.0;           // bifurcation: space scale s; v = s·R V_b(Rᵀw/s; t′)
  double local_time = 0.0;      // bifurcation: (t − t0)/τ
  cplx axis{1, 0};              // bifurcation: e^{iθ}

  cplx operator()(cplx w) const;
};

// The element at one time.
struct ElementState {
  bool active = false;
  Vec3 position = Vec3::Zero();  // p(t), world (before snapping to a surface)
  Vec3 velocity = Vec3::Zero();  // dP/dt, world (regular elements; for the generator to
                                 // express in the local frame on surfaces)
  LocalField field;
};

// An element prepared for evaluation at many times (splines built once).
class CompiledElement {
public:
  explicit CompiledElement(const Element& element);
  // State at time t. On planar domains the regular velocity is already the (x, y) of
  // dP/dt; on surfaces the generator projects `velocity` into the local frame.
  ElementState at(double t) const;
  // +1 or −1 for singular elements (sign of det J), 0 otherwise.
  int index() const { return index_; }
  // Time span in which the element is present: path span for singular and regular
  // elements (a one-point path: always), always for bifurcations.
  bool active(double t) const;
  const Element& element() const { return element_; }

private:
  Element element_;
  HermitePath path_;
  int index_ = 0;
};

// The bifurcation normal form V_b(x, y; t) of DESIGN §4 (eq. 1, eq. 2 and their time
// reverses) and §12 (the Hopf normal forms, μ = t), in template coordinates. With the
// template's v = s·R V_b(Rᵀw/s; t′) a Hopf cycle has world radius s·√|t′| and, since the
// normal form turns at angular velocity 1 in template and world coordinates alike, period
// 2π in the streamline parameter (the generators' falloff exp(−d‖w‖²) scales the vector,
// not its direction: the cycle keeps its place and its period becomes 2π·exp(d·s²|t′|)).
Vec2 bifurcation_normal_form(BifurcationType type, double x, double y, double t);

}  // namespace tvf
