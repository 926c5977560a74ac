#pragma once
// Distances along a mesh's edges (Dijkstra over the edge graph): the bounded walks that
// gather a patch round a point (the local log map's), the curvature within a radius (a
// template's), and a tube round a path measured on the surface (the key-frame guide's).
// Edge paths are longer than geodesics (1.0–1.2 times on reasonable meshes), which these
// callers allow for; where the exact geodesic distance matters, HeatDistance.
#include "tvf/mesh/mesh.h"

#include <functional>
#include <span>
#include <vector>

namespace tvf {

struct EdgePathSeed {
  int vertex = -1;
  double distance = 0;  // where the walk starts it (a point's chord to it, say)
};

// The distance of every vertex from the seeds along the mesh's edges (every edge both ways,
// boundary edges too); +∞ where no path of at most `radius` reaches (a seed has its own
// distance whatever it is, and is walked on from only if that is within `radius`). A
// vertex seeded twice keeps the smaller distance. `settle(v, d)`, if given, is called once
// for each vertex reached, in order of distance (ties by vertex number), when its distance
// is final; the walk stops where it returns false (the distances of vertices not settled
// by then are upper bounds).
std::vector<double> edge_path_distances(const Mesh& mesh, std::span<const EdgePathSeed> seeds, double radius,
                                        const std::function<bool(int, double)>& settle = {});

}  // namespace tvf
