#include "tvf/design/element_field.h"

#include "tvf/core/error.h"

#include <cmath>

namespace tvf {

Vec2 bifurcation_normal_form(BifurcationType type, double x, double y, double t) {
  switch (type) {
    case BifurcationType::saddle_source_cancellation: return {t + x * x, y};
    case BifurcationType::saddle_sink_creation: return {t - x * x, -y};
    case BifurcationType::saddle_source_creation: return {-t + x * x, y};
    case BifurcationType::saddle_sink_cancellation: return {-t - x * x, -y};
    case BifurcationType::hopf_supercritical:
    case BifurcationType::hopf_subcritical: {
      const double sigma = type == BifurcationType::hopf_supercritical ? 1.0 : -1.0;
      const double r2 = x * x + y * y;
      return {t * x - y - sigma * x * r2, x + t * y - sigma * y * r2};
    }
  }
  TVF_CHECK(false, "unknown bifurcation type");
}

cplx LocalField::operator()(cplx w) const {
  switch (kind) {
    case Kind::linear: return to_complex(matrix * to_vec2(w));
    case Kind::regular: {
      if (attach == 0.0 || velocity == cplx(0, 0)) return velocity;
      // The paper's (1, c(y − y0)) in the path's frame, scaled by the path's speed: y′ is
      // the signed offset across the path (left positive), n = i·V/|V| its unit normal.
      const double speed = std::abs(velocity);
      const cplx dir = velocity / speed;
      const double offset = (w * std::conj(dir)).imag();
      return velocity - attach * speed * offset * (cplx(0, 1) * dir);
    }
    case Kind::bifurcation: {
      // Rotate into the template frame, scale, evaluate, rotate back. The factor s keeps
      // the template in the units of the other elements: its Jacobian at the two zeros is
      // the normal form's (O(1), like a singular element's J) instead of 1/s times it, so
      // a small template does not overpower its neighbours (docs/architecture.md).
      const cplx q = w * std::conj(axis) / scale;
      return scale * to_complex(bifurcation_normal_form(bifurcation, q.real(), q.imag(), local_time)) * axis;
    }
  }
  TVF_CHECK(false, "unknown element kind");
}

CompiledElement::CompiledElement(const Element& element) : element_(element) {
  if (const auto* s = std::get_if<SingularElement>(&element_)) {
    path_ = HermitePath(s->path);
    index_ = s->jacobian.determinant() > 0 ? 1 : -1;
  } else if (const auto* r = std::get_if<RegularElement>(&element_)) {
    path_ = HermitePath(r->pathline);
  }
}

bool CompiledElement::active(double t) const {
  if (const auto* s = std::get_if<SingularElement>(&element_))
    return s->path.size() == 1 || path_.covers(t);
  if (std::holds_alternative<RegularElement>(element_)) return path_.covers(t);
  // A streakline has no basis field: it constrains the solve (streakline_design.h) and is
  // never placed as an element.
  if (std::holds_alternative<StreaklineElement>(element_)) return false;
  return true;
}

ElementState CompiledElement::at(double t) const {
  ElementState st;
  st.active = active(t);
  if (const auto* s = std::get_if<SingularElement>(&element_)) {
    st.position = path_.position(t);
    const Mat2 m = transform_matrix(interpolate_transform(s->transform, t));
    st.field.kind = LocalField::Kind::linear;
    st.field.matrix = m.transpose() * s->jacobian * m;
  } else if (const auto* r = std::get_if<RegularElement>(&element_)) {
    st.position = path_.position(t);
    st.velocity = path_.velocity(t);
    st.field.kind = LocalField::Kind::regular;
    st.field.velocity = cplx(st.velocity.x(), st.velocity.y());
    st.field.attach = r->attach;
  } else if (const auto* sl = std::get_if<StreaklineElement>(&element_)) {
    st.active = false;  // no basis field (active() is false at every t)
    st.position = sl->points.front();
  } else {
    const auto& b = std::get<BifurcationElement>(element_);
    st.position = b.at.position;
    st.field.kind = LocalField::Kind::bifurcation;
    st.field.bifurcation = b.type;
    st.field.scale = b.scale;
    st.field.local_time = (t - b.at.t) / b.time_scale;
    st.field.axis = std::polar(1.0, b.angle);
  }
  return st;
}

}  // namespace tvf
