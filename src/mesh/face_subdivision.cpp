#include "tvf/mesh/face_subdivision.h"

#include "tvf/core/error.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace tvf {

long subdivision_vertex_count(const Mesh& mesh, int n) {
  const long m = n;
  return static_cast<long>(mesh.num_vertices()) + static_cast<long>(mesh.num_edges()) * (m - 1) +
         static_cast<long>(mesh.num_faces()) * (m - 1) * (m - 2) / 2;
}

FaceSubdivision subdivide_faces(const Mesh& mesh, int n) {
  if (n < 1 || n > 64) throw Error(fmt::format("face subdivision {}: must be in [1, 64]", n));
  FaceSubdivision out;
  out.n = n;
  const size_t count = static_cast<size_t>(subdivision_vertex_count(mesh, n));
  std::vector<Vec3> positions(count);
  out.face.assign(count, -1);
  out.bary.assign(count, Vec3::Zero());
  const long nv = mesh.num_vertices();
  const long edge_base = nv, face_base = nv + static_cast<long>(mesh.num_edges()) * (n - 1);
  const int per_face = (n + 1) * (n + 2) / 2;
  out.grid.assign(static_cast<size_t>(mesh.num_faces()) * static_cast<size_t>(per_face), -1);
  std::vector<Face> triangles;
  triangles.reserve(static_cast<size_t>(mesh.num_faces()) * static_cast<size_t>(n) * static_cast<size_t>(n));
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Face& c = mesh.face(f);
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i + j <= n; ++i) {
        long id;
        if (i == 0 && j == 0) {
          id = c[0];
        } else if (i == n) {
          id = c[1];
        } else if (j == n) {
          id = c[2];
        } else if (j == 0 || i + j == n || i == 0) {
          // On an edge: halfedge k of the face runs from corner k to corner k + 1; the
          // edge's points are numbered from its first vertex.
          int k;
          int steps;  // from corner k
          if (j == 0) k = 0, steps = i;
          else if (i + j == n) k = 1, steps = j;
          else k = 2, steps = n - j;
          const int h = 3 * f + k;
          const auto& e = mesh.edge(mesh.edge_of(h));
          const long q = mesh.tail(h) == e[0] ? steps : n - steps;
          id = edge_base + static_cast<long>(mesh.edge_of(h)) * (n - 1) + (q - 1);
        } else {
          id = face_base + static_cast<long>(f) * (n - 1) * (n - 2) / 2 + (j - 1) * (n - 2) - (j - 1) * (j - 2) / 2 + (i - 1);
        }
        const auto s = static_cast<size_t>(id);
        out.grid[static_cast<size_t>(f) * static_cast<size_t>(per_face) +
                 static_cast<size_t>(FaceSubdivision::local_index(n, i, j))] = static_cast<int>(id);
        if (out.face[s] < 0) {
          const Vec3 b(static_cast<double>(n - i - j) / n, static_cast<double>(i) / n, static_cast<double>(j) / n);
          out.face[s] = f;
          out.bary[s] = b;
          positions[s] = b[0] * mesh.position(c[0]) + b[1] * mesh.position(c[1]) + b[2] * mesh.position(c[2]);
        }
      }
    auto at = [&](int i, int j) { return out.vertex(f, i, j); };
    for (int j = 0; j < n; ++j)
      for (int i = 0; i + j < n; ++i) {
        triangles.push_back({at(i, j), at(i + 1, j), at(i, j + 1)});
        if (i + j < n - 1) triangles.push_back({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
      }
  }
  TVF_CHECK(std::all_of(out.face.begin(), out.face.end(), [](int f) { return f >= 0; }), "a subdivision vertex was not placed");
  out.mesh = Mesh(std::move(positions), std::move(triangles), mesh.source());
  return out;
}

}  // namespace tvf
