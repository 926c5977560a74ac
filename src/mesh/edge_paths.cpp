#include "tvf/mesh/edge_paths.h"

#include <limits>
#include <queue>
#include <utility>

namespace tvf {

std::vector<double> edge_path_distances(const Mesh& mesh, std::span<const EdgePathSeed> seeds, double radius,
                                        const std::function<bool(int, double)>& settle) {
  std::vector<double> dist(static_cast<size_t>(mesh.num_vertices()), std::numeric_limits<double>::infinity());
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  for (const EdgePathSeed& s : seeds) {
    double& d = dist[static_cast<size_t>(s.vertex)];
    if (s.distance < d) d = s.distance, queue.emplace(s.distance, s.vertex);
  }
  while (!queue.empty()) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > dist[static_cast<size_t>(v)]) continue;  // a stale entry
    if (settle && !settle(v, d)) break;
    if (d > radius) continue;
    // The one ring: each outgoing halfedge's head, and the tail of the halfedge before it
    // (on the boundary, the one neighbour no outgoing halfedge points to).
    for (const int h : mesh.outgoing(v))
      for (const int w : {mesh.head(h), mesh.tail(Mesh::prev(h))}) {
        const double nd = d + (mesh.position(w) - mesh.position(v)).norm();
        if (nd <= radius && nd < dist[static_cast<size_t>(w)]) {
          dist[static_cast<size_t>(w)] = nd;
          queue.emplace(nd, w);
        }
      }
  }
  return dist;
}

}  // namespace tvf
