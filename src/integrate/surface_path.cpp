#include "tvf/integrate/surface_path.h"

#include "tvf/integrate/surface_walk.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <optional>
#include <queue>
#include <utility>

namespace tvf {

SurfacePaths::SurfacePaths(const TangentBundle& bundle, const PointLocator& locator)
    : bundle_(bundle), locator_(locator) {}

namespace {

// v's barycentric place in `face`, one of its corners.
SurfacePoint corner_of(const Mesh& mesh, int face, int v) {
  const Face& f = mesh.face(face);
  return {face, Vec3(f[0] == v ? 1.0 : 0.0, f[1] == v ? 1.0 : 0.0, f[2] == v ? 1.0 : 0.0)};
}

// A face that holds both vertices u and v of an edge, and u's barycentric place in it.
SurfacePoint corner_in_face_with(const Mesh& mesh, int u, int v) {
  for (const int e : mesh.outgoing(u))
    if (mesh.head(e) == v || mesh.tail(Mesh::prev(e)) == v) return corner_of(mesh, e / 3, u);
  return {-1, Vec3::Zero()};
}

}  // namespace

// The shortest path along the mesh's edges from p (on sp.face) to q (on sq.face): the
// vertices between them, Dijkstra from sp.face's corners to sq.face's; empty when both
// lie in one face; nullopt when no edge path joins them.
std::optional<std::vector<int>> SurfacePaths::edge_route(const SurfacePoint& sp, const Vec3& p, const SurfacePoint& sq,
                                                         const Vec3& q) const {
  const Mesh& mesh = bundle_.mesh();
  if (sp.face == sq.face) return std::vector<int>{};
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
  if (end < 0) return std::nullopt;
  std::vector<int> vertices;
  for (int v = end; v >= 0; v = from[static_cast<size_t>(v)]) vertices.push_back(v);
  std::reverse(vertices.begin(), vertices.end());
  return vertices;
}

std::vector<Vec3> SurfacePaths::between(const Vec3& p, const Vec3& q, int max_segments) const {
  const Mesh& mesh = bundle_.mesh();
  const double h = mesh.mean_edge_length();
  const SurfacePoint sp = locator_.closest(p), sq = locator_.closest(q);
  // The edge path: p, the vertices, q.
  const std::optional<std::vector<int>> vertices = edge_route(sp, p, sq, q);
  if (!vertices) return {};
  std::vector<Vec3> line{p};
  for (const int v : *vertices) line.push_back(mesh.position(v));
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

// The step in from.face's frame whose walk ends at `to` (within `tol`): the chord in the
// face's plane, corrected by each walk's miss (its part in the end face's plane, carried
// back by the walk's transport: exact where the walk and the target lie in one unfolded
// strip of faces). nullopt when no walk reaches it, as from one side of a thin part to
// the other, where the miss is along the end face's normal.
std::optional<cplx> SurfacePaths::shoot(const SurfacePoint& from, const Vec3& to, double tol) const {
  const Mesh& mesh = bundle_.mesh();
  cplx step = bundle_.world_to_face(from.face, to - surface_position(mesh, from));
  for (int round = 0; round < 12; ++round) {
    const SurfaceWalk walk = walk_surface(bundle_, from, step);
    const Vec3 miss = to - surface_position(mesh, walk.end);
    if (miss.norm() <= tol) return step;
    const cplx tangential = bundle_.world_to_face(walk.end.face, miss);
    // Most of the miss off the end face's plane: the target is across a fold or a thin
    // part from where the walk can go.
    if (std::abs(tangential) < 0.5 * miss.norm()) return std::nullopt;
    step += tangential / walk.transport;
  }
  return std::nullopt;
}

// Straightened intrinsically: each inner point moves towards the middle of its two
// neighbours as seen from it, the mean of the steps whose walks reach them (shoot), not of
// the chords, which on a thin part run through it (the straightened chords of `between`
// draw a path over a slab's rim through the slab). A move is kept only where both its
// segments are still walks, so the route starts and stays one: it starts as the edge path,
// every piece of which lies in one face. Its fixed points are geodesic polygons: at every
// point the two steps to the neighbours are opposite.
SurfacePaths::Route SurfacePaths::route(const Vec3& p, const Vec3& q, int max_segments) const {
  const Mesh& mesh = bundle_.mesh();
  const double h = mesh.mean_edge_length(), tol = 1e-6 * h;
  const SurfacePoint sp = locator_.closest(p), sq = locator_.closest(q);
  const std::optional<std::vector<int>> vertices = edge_route(sp, p, sq, q);
  if (!vertices) return {};
  // The edge path: p, the vertices, q, each piece walked in a face that holds it.
  Route r;
  r.points.push_back(p);
  r.starts.push_back(sp);
  for (size_t i = 0; i < vertices->size(); ++i) {
    const int v = (*vertices)[i];
    r.points.push_back(mesh.position(v));
    r.starts.push_back(i + 1 < vertices->size() ? corner_in_face_with(mesh, v, (*vertices)[i + 1])
                                                : corner_of(mesh, sq.face, v));
  }
  r.points.push_back(q);
  for (size_t k = 0; k + 1 < r.points.size(); ++k)
    r.steps.push_back(bundle_.world_to_face(r.starts[k].face, r.points[k + 1] - r.points[k]));
  // About max_segments pieces: consecutive pieces are joined, in one pass, while together
  // they are no longer than the path over max_segments and a walk joins their ends.
  double total = 0;
  for (const cplx& step : r.steps) total += std::abs(step);
  if (static_cast<int>(r.steps.size()) > std::max(1, max_segments)) {
    const double longest = total / std::max(1, max_segments);
    Route joined;
    joined.points.push_back(r.points.front());
    joined.starts.push_back(r.starts.front());
    joined.steps.push_back(r.steps.front());
    double run = std::abs(r.steps.front());
    for (size_t i = 1; i < r.steps.size(); ++i) {
      const std::optional<cplx> step =
          run + std::abs(r.steps[i]) <= longest ? shoot(joined.starts.back(), r.points[i + 1], tol) : std::nullopt;
      if (step) {
        joined.steps.back() = *step;
        run += std::abs(r.steps[i]);
        continue;
      }
      joined.points.push_back(r.points[i]);
      joined.starts.push_back(r.starts[i]);
      joined.steps.push_back(r.steps[i]);
      run = std::abs(r.steps[i]);
    }
    joined.points.push_back(r.points.back());
    r = std::move(joined);
  }
  const size_t n = r.steps.size();
  if (n < 2) return r;
  const double omega = std::min(1.9, 2 / (1 + std::sin(std::numbers::pi / static_cast<double>(n))));
  for (size_t sweep = 0; sweep < 20 * n + 200; ++sweep) {
    double moved = 0;
    for (size_t i = 1; i < n; ++i) {
      const SurfacePoint& here = r.starts[i];
      const std::optional<cplx> back = shoot(here, r.points[i - 1], tol);
      if (!back) continue;
      // Over-relaxed, or plainly to the middle, or half way there: the first that shortens
      // the two segments (the sum of their squared lengths), which the over-relaxed move does
      // not beside a vertex of high curvature, where the steps to the neighbours flip sides
      // (the point would swing across it for ever).
      const double before = std::norm(*back) + std::norm(r.steps[i]);
      for (const double w : {omega, 1.0, 0.5}) {
        const cplx move = 0.5 * w * (*back + r.steps[i]);
        if (std::abs(move) < 1e-3 * tol) break;
        const SurfacePoint there = walk_surface(bundle_, here, move).end;
        const Vec3 x = surface_position(mesh, there);
        const std::optional<cplx> in = shoot(r.starts[i - 1], x, tol);
        const std::optional<cplx> out = in ? shoot(there, r.points[i + 1], tol) : std::nullopt;
        // A segment that would no longer be a walk, or no shorter: the point stays.
        if (!out || !(std::norm(*in) + std::norm(*out) < before)) continue;
        r.points[i] = x, r.starts[i] = there, r.steps[i - 1] = *in, r.steps[i] = *out;
        moved = std::max(moved, std::abs(move));
        break;
      }
    }
    if (moved < tol) break;
  }
  return r;
}

}  // namespace tvf
