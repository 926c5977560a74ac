#include "grid_flow.h"

#include <algorithm>
#include <cmath>

namespace tvf::detail {

std::optional<GridLayout> detect_grid(const TangentBundle& bundle) {
  const Mesh& mesh = bundle.mesh();
  const int nv = mesh.num_vertices();
  if (nv < 4) return std::nullopt;
  const auto& pos = mesh.positions();
  // nx: the first row runs along x at constant y.
  int nx = 1;
  while (nx < nv && pos[static_cast<size_t>(nx)].y() == pos[0].y()) ++nx;
  if (nx < 2 || nv % nx != 0) return std::nullopt;
  const int ny = nv / nx;
  if (ny < 2) return std::nullopt;
  GridLayout g;
  g.nx = nx;
  g.ny = ny;
  g.x0 = pos[0].x();
  g.y0 = pos[0].y();
  g.hx = (pos[static_cast<size_t>(nx - 1)].x() - g.x0) / (nx - 1);
  g.hy = (pos[static_cast<size_t>(nv - 1)].y() - g.y0) / (ny - 1);
  if (!(g.hx > 0) || !(g.hy > 0)) return std::nullopt;
  const double tx = 1e-9 * g.hx, ty = 1e-9 * g.hy;
  for (int iy = 0; iy < ny; ++iy)
    for (int ix = 0; ix < nx; ++ix) {
      const Vec3& p = pos[static_cast<size_t>(iy * nx + ix)];
      if (std::abs(p.x() - (g.x0 + g.hx * ix)) > tx || std::abs(p.y() - (g.y0 + g.hy * iy)) > ty ||
          p.z() != 0.0)
        return std::nullopt;
    }
  if (mesh.num_faces() != 2 * (nx - 1) * (ny - 1)) return std::nullopt;
  for (int iy = 0; iy + 1 < ny; ++iy)
    for (int ix = 0; ix + 1 < nx; ++ix) {
      const int v00 = iy * nx + ix, v10 = v00 + 1, v01 = v00 + nx, v11 = v01 + 1;
      const int f = 2 * (iy * (nx - 1) + ix);
      if (mesh.face(f) != Face{v00, v10, v11} || mesh.face(f + 1) != Face{v00, v11, v01}) return std::nullopt;
    }
  // Frames: the vertex and face bases must be world x, y (then every corner's transport is 1).
  constexpr double kTol = 1e-12;
  const Vec3 ex = Vec3::UnitX(), ey = Vec3::UnitY();
  for (int v = 0; v < nv; ++v)
    if ((bundle.vertex_e1(v) - ex).norm() > kTol || (bundle.vertex_e2(v) - ey).norm() > kTol) return std::nullopt;
  for (int f = 0; f < mesh.num_faces(); ++f)
    if ((bundle.face_e1(f) - ex).norm() > kTol || (bundle.face_e2(f) - ey).norm() > kTol) return std::nullopt;
  return g;
}

void GridFlow::locate(const Vec2& p, int& ix, int& iy, double& fx, double& fy) const {
  const double u = (p.x() - g_.x0) * inv_hx_, v = (p.y() - g_.y0) * inv_hy_;
  ix = std::clamp(static_cast<int>(std::floor(u)), 0, g_.nx - 2);
  iy = std::clamp(static_cast<int>(std::floor(v)), 0, g_.ny - 2);
  fx = std::clamp(u - ix, 0.0, 1.0);
  fy = std::clamp(v - iy, 0.0, 1.0);
}

SurfacePoint GridFlow::to_surface(const Vec2& p) const {
  int ix = 0, iy = 0;
  double fx = 0.0, fy = 0.0;
  locate(p, ix, iy, fx, fy);
  SurfacePoint s;
  const int f = 2 * (iy * (g_.nx - 1) + ix);
  if (fx >= fy) {  // (v00, v10, v11)
    s.face = f;
    s.bary = Vec3(1.0 - fx, fx - fy, fy);
  } else {  // (v00, v11, v01)
    s.face = f + 1;
    s.bary = Vec3(1.0 - fy, fx, fy - fx);
  }
  return s;
}

void GridFlow::corners(const Vec2& p, std::array<int, 3>& v, Vec3& w) const {
  const SurfacePoint s = to_surface(p);
  const int iy = (s.face / 2) / (g_.nx - 1), ix = (s.face / 2) % (g_.nx - 1);
  const int v00 = iy * g_.nx + ix;
  v = s.face % 2 == 0 ? std::array<int, 3>{v00, v00 + 1, v00 + g_.nx + 1}
                      : std::array<int, 3>{v00, v00 + g_.nx + 1, v00 + g_.nx};
  w = s.bary;
}

Vec2 GridFlow::velocity(const Vec2& p, int j, double w) const {
  int ix = 0, iy = 0;
  double fx = 0.0, fy = 0.0;
  locate(p, ix, iy, fx, fy);
  const int v00 = iy * g_.nx + ix, v11 = v00 + g_.nx + 1;
  const int v2 = fx >= fy ? v00 + 1 : v00 + g_.nx;
  const double b0 = fx >= fy ? 1.0 - fx : 1.0 - fy;
  const double b1 = fx >= fy ? fy : fx;              // weight of v11
  const double b2 = fx >= fy ? fx - fy : fy - fx;    // weight of v10 or v01
  auto at = [&](int v) {
    const cplx z = field_.at(j, v);
    if (w == 0.0) return z;
    return w == 1.0 ? field_.at(j + 1, v) : (1.0 - w) * z + w * field_.at(j + 1, v);
  };
  const cplx s = b0 * at(v00) + b1 * at(v11) + b2 * at(v2);
  return {s.real(), s.imag()};
}

GridFlow::Move GridFlow::move(const Vec2& p, const Vec2& d) const {
  // Most moves stay inside the box.
  const Vec2 e = p + d;
  if (e.x() >= g_.x0 && e.x() <= g_.x1() && e.y() >= g_.y0 && e.y() <= g_.y1()) return {e};
  Move m{p};
  Vec2 rem = d;
  const double tol = 1e-6 * d.norm();
  const double lo[2] = {g_.x0, g_.y0}, hi[2] = {g_.x1(), g_.y1()};
  for (int pass = 0; pass < 8 && rem.squaredNorm() > 0.0; ++pass) {
    double s = 1.0;
    int wall = -1;  // axis of the wall met first
    double at = 0.0;
    for (int a = 0; a < 2; ++a) {
      if (rem[a] == 0.0) continue;
      const double bound = rem[a] > 0 ? hi[a] : lo[a];
      const double sa = (bound - m.end[a]) / rem[a];
      if (sa < s) {
        s = std::max(sa, 0.0);
        wall = a;
        at = bound;
      }
    }
    if (wall < 0) {
      m.end += rem;
      return m;
    }
    m.end += s * rem;
    m.end[wall] = at;
    rem *= 1.0 - s;
    // The outward part of what is left: rounding slides along the wall, more leaves.
    if (std::abs(rem[wall]) > tol) {
      m.left = true;
      return m;
    }
    rem[wall] = 0.0;
  }
  return m;
}

bool GridFlow::advect(Vec2& p, const std::vector<double>& knots, double dt, double& t_left) const {
  const TimeSampling& time = field_.time();
  t_left = knots.back();
  // As the walk keeps particles strictly inside their faces (1e-10 of the face towards its
  // centroid, flow_map.cpp), particles are kept off the walls by the same hair: a particle
  // on a wall whose field points out by rounding (the double gyre's corners) stays.
  const double mx = 1e-10 * g_.hx / 3, my = 1e-10 * g_.hy / 3;
  auto inside = [&](Vec2& q) {
    q.x() = std::clamp(q.x(), g_.x0 + mx, g_.x1() - mx);
    q.y() = std::clamp(q.y(), g_.y0 + my, g_.y1() - my);
  };
  inside(p);
  for (size_t s = 0; s + 1 < knots.size(); ++s) {
    const double a = knots[s], b = knots[s + 1];
    const long n = std::max(1L, static_cast<long>(std::ceil(std::abs(b - a) / dt - 1e-9)));
    const double h = (b - a) / static_cast<double>(n);
    for (long k = 0; k < n; ++k) {
      const double t = a + h * static_cast<double>(k);
      int j0 = 0, jm = 0, j1 = 0;
      double w0 = 0.0, wm = 0.0, w1 = 0.0;
      time.locate(t, j0, w0);
      time.locate(t + 0.5 * h, jm, wm);
      time.locate(t + h, j1, w1);
      const Vec2 k1 = velocity(p, j0, w0);
      const Vec2 k2 = velocity(move(p, 0.5 * h * k1).end, jm, wm);
      const Vec2 k3 = velocity(move(p, 0.5 * h * k2).end, jm, wm);
      const Vec2 k4 = velocity(move(p, h * k3).end, j1, w1);
      const Move m = move(p, h * (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0);
      p = m.end;
      inside(p);
      if (m.left) {
        t_left = t;
        return true;
      }
    }
  }
  return false;
}

}  // namespace tvf::detail
