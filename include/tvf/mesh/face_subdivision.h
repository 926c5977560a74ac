#pragma once
// Regular subdivision of a triangle mesh's faces: every face split into n² small triangles
// by the points of barycentric coordinates (n − i − j, i, j)/n, the points on an edge
// shared by its two faces and the corners shared by all faces round a vertex, so that the
// result is a mesh of the same surface (flat on each original face). Each new vertex knows
// where it lies on the original mesh (face and barycentric coordinates), so that values
// defined on the original (fields, colours) can be sampled there.
#include "tvf/mesh/mesh.h"

#include <vector>

namespace tvf {

struct FaceSubdivision {
  int n = 1;                    // small triangles per original edge
  Mesh mesh;                    // the subdivided mesh; vertices 0 … |V|−1 are the original ones
  std::vector<int> face;        // per new vertex: a face of the original mesh holding it
  std::vector<Vec3> bary;       // and its barycentric coordinates there (corners 0, 1, 2)
  // Per original face, the new vertices at barycentric (n − i − j, i, j)/n, row j by row
  // (i = 0 … n − j): (n + 1)(n + 2)/2 ids a face, for lookups by a face's lattice point.
  std::vector<int> grid;

  static int local_index(int n, int i, int j) { return j * (n + 1) - j * (j - 1) / 2 + i; }
  int vertex(int f, int i, int j) const {
    return grid[static_cast<size_t>(f) * static_cast<size_t>((n + 1) * (n + 2) / 2) +
                static_cast<size_t>(local_index(n, i, j))];
  }
};

// Vertices of the subdivision with n per edge: |V| + |E|·(n − 1) + |F|·(n − 1)(n − 2)/2.
long subdivision_vertex_count(const Mesh& mesh, int n);

// Throws tvf::Error when n is outside [1, 64].
FaceSubdivision subdivide_faces(const Mesh& mesh, int n);

}  // namespace tvf
