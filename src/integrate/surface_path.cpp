#include "tvf/integrate/surface_path.h"

#include "tvf/integrate/surface_walk.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <queue>
#include <utility>

namespace tvf {

SurfacePaths::SurfacePaths(const TangentBundle& bundle, const PointLocator& locator)
    : bundle_(bundle), locator_(locator) {}

std::vector<Vec3> SurfacePaths::between(const Vec3& p, const Vec3& q, int max_segments) const {
  const Mesh& mesh = bundle_.mesh();
  const double h = mesh.mean_edge_length();
  const SurfacePoint sp = locator_.closest(p), sq = locator_.closest(q);
  // The edge path: p, the vertices, q.
  std::vector<Vec3> line{p};
  if (sp.face != sq.face) {
    const auto nv = static_cast<size_t>(mesh.num_vertices());
    std::vector<double> dist(nv, std::numeric_limits<double>::infinity());
    std::vector<int> from(nv, -1);
    using Item = std::pair<double, int>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
    for (const int c : mesh.face(sp.face)) {
      dist[static_cast<size_t>(c)] = (mesh.position(c) - p).norm();
      queue.emplace(dist[static_cast<size_t>(c)], c);
    }
    auto is_goal = [&](int v) {
      const Face& f = mesh.face(sq.face);
      return v == f[0] || v == f[1] || v == f[2];
    };
    double best = std::numeric_limits<double>::infinity();
    int end = -1;
    while (!queue.empty()) {
      const auto [d, v] = queue.top();
      queue.pop();
      if (d > dist[static_cast<size_t>(v)]) continue;
      if (d >= best) break;
      if (is_goal(v) && d + (mesh.position(v) - q).norm() < best) best = d + (mesh.position(v) - q).norm(), end = v;
      // The one ring (as edge_paths.cpp walks it): each outgoing halfedge's head, and the
      // tail of the halfedge before it (on the boundary, the one no outgoing halfedge reaches).
      for (const int e : mesh.outgoing(v))
        for (const int w : {mesh.head(e), mesh.tail(Mesh::prev(e))}) {
          const double nd = d + (mesh.position(w) - mesh.position(v)).norm();
          if (nd < dist[static_cast<size_t>(w)]) {
            dist[static_cast<size_t>(w)] = nd;
            from[static_cast<size_t>(w)] = v;
            queue.emplace(nd, w);
          }
        }
    }
    if (end < 0) return {};
    std::vector<Vec3> vertices;
    for (int v = end; v >= 0; v = from[static_cast<size_t>(v)]) vertices.push_back(mesh.position(v));
    line.insert(line.end(), vertices.rbegin(), vertices.rend());
  }
  line.push_back(q);
  std::vector<double> cum(line.size(), 0.0);
  double total = 0;
  for (size_t k = 1; k < line.size(); ++k) cum[k] = total += (line[k] - line[k - 1]).norm();
  if (!(total > 0)) return {p, q};
  // Resampled evenly along the edge path (every point on the surface: on an edge, or in
  // p's or q's face).
  const int n = std::clamp(static_cast<int>(std::ceil(total / h)), 2, std::max(2, max_segments));
  std::vector<Vec3> x(static_cast<size_t>(n) + 1);
  std::vector<SurfacePoint> on(x.size());
  for (int i = 0, k = 0; i <= n; ++i) {
    const double a = total * i / n;
    while (k + 2 < static_cast<int>(line.size()) && cum[static_cast<size_t>(k) + 1] < a) ++k;
    const auto ku = static_cast<size_t>(k);
    const double w = cum[ku + 1] > cum[ku] ? std::clamp((a - cum[ku]) / (cum[ku + 1] - cum[ku]), 0.0, 1.0) : 0.0;
    x[static_cast<size_t>(i)] = i == 0 ? p : i == n ? q : Vec3(line[ku] + w * (line[ku + 1] - line[ku]));
    on[static_cast<size_t>(i)] = locator_.closest(x[static_cast<size_t>(i)]);
    x[static_cast<size_t>(i)] = i == 0 ? p : i == n ? q : surface_position(mesh, on[static_cast<size_t>(i)]);
  }
  // Straightened on the surface.
  const double omega = std::min(1.9, 2 / (1 + std::sin(std::numbers::pi / n)));
  for (int sweep = 0; sweep < 20 * n + 200; ++sweep) {
    double moved = 0;
    for (size_t i = 1; i + 1 < x.size(); ++i) {
      const Vec3 d = 0.5 * (x[i - 1] + x[i + 1]) - x[i];
      const cplx step = omega * bundle_.world_to_face(on[i].face, d);
      if (std::abs(step) == 0) continue;
      on[i] = walk_surface(bundle_, on[i], step).end;
      x[i] = surface_position(mesh, on[i]);
      moved = std::max(moved, std::abs(step));
    }
    if (moved < 1e-6 * h) break;
  }
  return x;
}

}  // namespace tvf
