#include "support/test_fields.h"

#include <cmath>

namespace tvf::test {

Field field_from(const TangentBundle& bundle, TimeSampling time, const std::function<Vec3(const Vec3&, double)>& v) {
  const Mesh& mesh = bundle.mesh();
  Field field(time, mesh.num_vertices());
  for (int j = 0; j < time.frames; ++j)
    for (int i = 0; i < mesh.num_vertices(); ++i) field.at(j, i) = bundle.world_to_vertex(i, v(mesh.position(i), time.time(j)));
  return field;
}

Vec3 double_gyre(const Vec3& x, double t) {
  constexpr double kA = 0.1, kEps = 0.25, kPiD = 3.14159265358979323846;
  const double omega = 2 * kPiD / 10;
  const double a = kEps * std::sin(omega * t);
  const double b = 1 - 2 * a;
  const double f = a * x.x() * x.x() + b * x.x();
  const double df = 2 * a * x.x() + b;
  return {-kPiD * kA * std::sin(kPiD * f) * std::cos(kPiD * x.y()),
          kPiD * kA * std::cos(kPiD * f) * std::sin(kPiD * x.y()) * df, 0.0};
}

}  // namespace tvf::test
