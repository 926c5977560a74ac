#include "tvf/integrate/streamline.h"

#include "tvf/core/error.h"

#include <algorithm>
#include <cmath>
#include <optional>

namespace tvf {

namespace {

// Barycentric coordinates of x in planar face f (z ignored).
Vec3 bary_in(const Mesh& mesh, int f, const Vec3& x) {
  const Face& t = mesh.face(f);
  const Vec2 a = mesh.position(t[0]).head<2>(), b = mesh.position(t[1]).head<2>(),
             c = mesh.position(t[2]).head<2>();
  const Vec2 p = x.head<2>();
  const double det = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
  const double l1 = ((p - a).x() * (c - a).y() - (p - a).y() * (c - a).x()) / det;
  const double l2 = ((b - a).x() * (p - a).y() - (b - a).y() * (p - a).x()) / det;
  return {1 - l1 - l2, l1, l2};
}

class PlanarWalker {
public:
  PlanarWalker(const TangentBundle& bundle, std::span<const cplx> values)
      : bundle_(bundle), mesh_(bundle.mesh()), values_(values) {}

  // The field at x (in the plane's frame), or nothing outside the domain. Looks in the
  // last face and its neighbours first, then everywhere.
  std::optional<cplx> at(const Vec3& x) {
    constexpr double eps = -1e-12;
    auto inside = [&](int f, Vec3& b) {
      b = bary_in(mesh_, f, x);
      return b.minCoeff() >= eps;
    };
    Vec3 b;
    int found = -1;
    if (face_ >= 0) {
      if (inside(face_, b)) found = face_;
      for (int c = 0; c < 3 && found < 0; ++c) {
        const int t = mesh_.twin(3 * face_ + c);
        if (t >= 0 && inside(Mesh::face_of(t), b)) found = Mesh::face_of(t);
      }
    }
    if (found < 0) {
      const SurfacePoint p = closest_point(mesh_, x);
      if (!inside(p.face, b)) return std::nullopt;
      found = p.face;
    }
    face_ = found;
    cplx z(0, 0);
    for (int c = 0; c < 3; ++c)
      z += b[c] * bundle_.corner_to_face(3 * found + c) * values_[static_cast<size_t>(mesh_.face(found)[static_cast<size_t>(c)])];
    return z;
  }

private:
  const TangentBundle& bundle_;
  const Mesh& mesh_;
  std::span<const cplx> values_;
  int face_ = -1;
};

}  // namespace

Streamline trace_streamline(const TangentBundle& bundle, std::span<const cplx> values,
                            const Vec3& seed, const StreamlineOptions& options) {
  const Mesh& mesh = bundle.mesh();
  if (!bundle.is_flat())
    throw_input_error(mesh.source(), "", "streamlines are traced on planar domains only in this version");
  double vmax = 0;
  for (const cplx& z : values) vmax = std::max(vmax, std::abs(z));
  const double h = options.step > 0 ? options.step : 0.5 * mesh.mean_edge_length();
  const double max_len = options.max_length > 0 ? options.max_length : mesh.diameter();
  const double stop = options.stop_speed * vmax;

  PlanarWalker walker(bundle, values);
  const auto v0 = walker.at(seed);
  if (!v0) throw_input_error(mesh.source(), "", fmt::format("the streamline seed ({}, {}) is outside the domain", seed.x(), seed.y()));

  auto direction = [&](const Vec3& x, double sign) -> std::optional<Vec3> {
    const auto z = walker.at(x);
    if (!z || std::abs(*z) <= stop) return std::nullopt;
    const cplx u = sign * *z / std::abs(*z);
    return Vec3(u.real(), u.imag(), 0);
  };

  std::vector<Vec3> half[2];
  std::vector<double> speed[2];
  bool closed = false;
  for (int dir = 0; dir < 2 && !closed; ++dir) {
    const double sign = dir == 0 ? 1.0 : -1.0;
    Vec3 x = seed;
    for (double len = 0; len < max_len; len += h) {
      const auto k1 = direction(x, sign);
      if (!k1) break;
      const auto k2 = direction(x + 0.5 * h * *k1, sign);
      if (!k2) break;
      const auto k3 = direction(x + 0.5 * h * *k2, sign);
      if (!k3) break;
      const auto k4 = direction(x + h * *k3, sign);
      if (!k4) break;
      const Vec3 next = x + h / 6 * (*k1 + 2 * *k2 + 2 * *k3 + *k4);
      const auto z = walker.at(next);
      if (!z) break;
      x = next;
      half[dir].push_back(x);
      speed[dir].push_back(std::abs(*z));
      // Closed orbit: back next to the seed after going some way round.
      if (len > 4 * h && (x - seed).norm() < 0.5 * h) {
        closed = true;  // the backward half would retrace the same orbit
        break;
      }
    }
  }
  Streamline s;
  for (size_t k = half[1].size(); k-- > 0;) {
    s.points.push_back(half[1][k]);
    s.speeds.push_back(speed[1][k]);
  }
  s.seed = s.points.size();
  s.points.push_back(seed);
  s.speeds.push_back(std::abs(*v0));
  s.points.insert(s.points.end(), half[0].begin(), half[0].end());
  s.speeds.insert(s.speeds.end(), speed[0].begin(), speed[0].end());
  return s;
}

}  // namespace tvf
