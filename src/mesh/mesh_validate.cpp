#include "tvf/mesh/mesh_validate.h"

#include "tvf/core/error.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>

namespace tvf {

namespace {

// Items (faces or halfedges) grouped by their smallest vertex with a counting sort, then
// sorted inside each group: O(n + Σ d log d) for vertex degrees d, so meshes with
// millions of faces stay fast. Every index must be in [0, nv).
struct Buckets {
  std::vector<int> offset;  // nv + 1
  std::vector<int> items;
};

template <typename MinVertex>
Buckets bucket_by_vertex(size_t nv, size_t n, MinVertex&& min_vertex) {
  Buckets b;
  b.offset.assign(nv + 1, 0);
  for (size_t i = 0; i < n; ++i) ++b.offset[static_cast<size_t>(min_vertex(i)) + 1];
  for (size_t v = 0; v < nv; ++v) b.offset[v + 1] += b.offset[v];
  b.items.assign(n, 0);
  std::vector<int> fill(b.offset.begin(), b.offset.end() - 1);
  for (size_t i = 0; i < n; ++i)
    b.items[static_cast<size_t>(fill[static_cast<size_t>(min_vertex(i))]++)] = static_cast<int>(i);
  return b;
}

Face sorted(const Face& f) {
  Face s = f;
  std::sort(s.begin(), s.end());
  return s;
}

// Faces in groups of equal vertex sets, each group in increasing face order. Calls
// `on_duplicate(first, other)` for every face `other` whose vertex set equals that of
// the earlier face `first`.
template <typename OnDuplicate>
void for_each_duplicate_face(const std::vector<Face>& faces, size_t nv,
                             OnDuplicate&& on_duplicate) {
  std::vector<Face> keys(faces.size());
  for (size_t f = 0; f < faces.size(); ++f) keys[f] = sorted(faces[f]);
  Buckets b = bucket_by_vertex(nv, faces.size(), [&](size_t f) { return keys[f][0]; });
  for (size_t v = 0; v < nv; ++v) {
    const auto first = b.items.begin() + b.offset[v];
    const auto last = b.items.begin() + b.offset[v + 1];
    if (last - first < 2) continue;
    std::sort(first, last, [&](int x, int y) {
      const Face& kx = keys[static_cast<size_t>(x)];
      const Face& ky = keys[static_cast<size_t>(y)];
      if (kx[1] != ky[1]) return kx[1] < ky[1];
      if (kx[2] != ky[2]) return kx[2] < ky[2];
      return x < y;
    });
    for (auto g = first; g != last;) {
      const Face& key = keys[static_cast<size_t>(*g)];
      auto e = g + 1;
      for (; e != last && keys[static_cast<size_t>(*e)] == key; ++e) on_duplicate(*g, *e);
      g = e;
    }
  }
}

bool indices_in_range(const std::vector<Face>& faces, size_t nv) {
  for (const Face& f : faces)
    for (int v : f)
      if (v < 0 || static_cast<size_t>(v) >= nv) return false;
  return true;
}

std::string format_point(const Vec3& p) { return fmt::format("({}, {}, {})", p.x(), p.y(), p.z()); }

}  // namespace

void validate_triangle_soup(const std::vector<Vec3>& positions, const std::vector<Face>& faces,
                            const std::string& source) {
  auto fail = [&](const std::string& message) { throw_input_error(source, "", message); };
  const size_t nv = positions.size();
  const size_t nf = faces.size();
  if (nv == 0) fail("the mesh has no vertices");
  if (nf == 0) fail("the mesh has no faces");
  if (nv > static_cast<size_t>(std::numeric_limits<int>::max()))
    fail(fmt::format("the mesh has {} vertices, more than the supported {}", nv,
                     std::numeric_limits<int>::max()));
  if (nf > static_cast<size_t>(std::numeric_limits<int>::max() / 3))
    fail(fmt::format("the mesh has {} faces, more than the supported {}", nf,
                     std::numeric_limits<int>::max() / 3));

  // Coordinates.
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = -lo;
  for (size_t v = 0; v < nv; ++v) {
    const Vec3& p = positions[v];
    if (!p.allFinite())
      fail(fmt::format("vertex {} has a non-finite coordinate {}", v, format_point(p)));
    if (p.cwiseAbs().maxCoeff() > kMaxCoordinate)
      fail(fmt::format("vertex {} at {} has a coordinate of magnitude above {:g} (larger ones overflow the "
                       "squared distances and areas tvf computes; scale the mesh down)",
                       v, format_point(p), kMaxCoordinate));
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  // An extent too small for the coordinates' magnitude: the vertices' differences lose all
  // precision (a mesh a unit wide 1e15 from the origin has vertices 0.125 apart at best).
  const double magnitude = std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff());
  if ((hi - lo).maxCoeff() < kMinRelativeExtent * magnitude)
    fail(fmt::format("the mesh spans only {:g} but lies {:g} from the origin: it must span at least {:g} of its "
                     "largest coordinate, or its vertices lose their precision (move it nearer the origin)",
                     (hi - lo).maxCoeff(), magnitude, kMinRelativeExtent));

  // Faces on their own: indices, repeated vertices, area.
  for (size_t f = 0; f < nf; ++f) {
    const Face& t = faces[f];
    for (int v : t)
      if (v < 0 || static_cast<size_t>(v) >= nv)
        fail(fmt::format("face {} uses vertex {}, but the vertices are numbered 0 to {}", f, v,
                         nv - 1));
    for (int k = 0; k < 3; ++k)
      if (t[static_cast<size_t>(k)] == t[static_cast<size_t>((k + 1) % 3)])
        fail(fmt::format("face {} uses vertex {} twice (degenerate face)", f,
                         t[static_cast<size_t>(k)]));
  }
  // Zero area: exactly, or below 1e-14 of the squared bounding-box diagonal (divided
  // rather than squared, so that huge coordinates cannot overflow the threshold).
  const double diag = (hi - lo).norm();
  for (size_t f = 0; f < nf; ++f) {
    const Face& t = faces[f];
    const Vec3& a = positions[static_cast<size_t>(t[0])];
    const Vec3 c =
        (positions[static_cast<size_t>(t[1])] - a).cross(positions[static_cast<size_t>(t[2])] - a);
    const double area = 0.5 * c.norm();
    if (!(area > 0) || area / diag / diag < 1e-14)
      fail(fmt::format("face {} (vertices {}, {}, {}) has zero area (degenerate face)", f, t[0],
                       t[1], t[2]));
  }

  // Vertices used by no face.
  {
    std::vector<std::uint8_t> used(nv, 0);
    for (const Face& t : faces)
      for (int v : t) used[static_cast<size_t>(v)] = 1;
    for (size_t v = 0; v < nv; ++v)
      if (!used[v]) fail(fmt::format("vertex {} is used by no face (unreferenced vertex)", v));
  }

  // Duplicate faces.
  for_each_duplicate_face(faces, nv, [&](int first, int other) {
    fail(fmt::format("faces {} and {} use the same three vertices (duplicate face)", first, other));
  });

  // Edges: halfedges grouped by their undirected edge. h = 3·f + c runs from
  // faces[f][c] to faces[f][(c + 1) % 3].
  const size_t nh = 3 * nf;
  auto tail = [&](size_t h) { return faces[h / 3][h % 3]; };
  auto head = [&](size_t h) { return faces[h / 3][(h % 3 + 1) % 3]; };
  Buckets edges = bucket_by_vertex(nv, nh, [&](size_t h) { return std::min(tail(h), head(h)); });
  std::vector<int> twin(nh, -1);
  for (size_t v = 0; v < nv; ++v) {
    const auto first = edges.items.begin() + edges.offset[v];
    const auto last = edges.items.begin() + edges.offset[v + 1];
    auto other_end = [&](int h) {
      return std::max(tail(static_cast<size_t>(h)), head(static_cast<size_t>(h)));
    };
    std::sort(first, last, [&](int x, int y) {
      const int ox = other_end(x), oy = other_end(y);
      return ox != oy ? ox < oy : x < y;
    });
    for (auto g = first; g != last;) {
      auto e = g + 1;
      while (e != last && other_end(*e) == other_end(*g)) ++e;
      const auto count = e - g;
      const int a = static_cast<int>(v), b = other_end(*g);
      if (count > 2)
        fail(fmt::format("edge {}–{} is shared by {} faces (non-manifold edge)", a, b, count));
      if (count == 2) {
        const auto h0 = static_cast<size_t>(g[0]);
        const auto h1 = static_cast<size_t>(g[1]);
        if (tail(h0) == tail(h1))
          fail(
              fmt::format("faces {} and {} both run along edge {}→{} in the same direction "
                          "(inconsistent orientation)",
                          h0 / 3, h1 / 3, tail(h0), head(h0)));
        twin[h0] = static_cast<int>(h1);
        twin[h1] = static_cast<int>(h0);
      }
      g = e;
    }
  }

  // Vertices: the faces around each must form a single fan. Rotating around v maps an
  // outgoing halfedge h to next(twin(h)) (clockwise) or twin(prev(h)) (counter-clockwise);
  // both are injective, so a walk either ends on the boundary or returns to its start.
  auto next = [](size_t h) { return 3 * (h / 3) + (h % 3 + 1) % 3; };
  auto prev = [](size_t h) { return 3 * (h / 3) + (h % 3 + 2) % 3; };
  std::vector<int> corners(nv, 0);
  std::vector<int> any_out(nv, -1);
  for (size_t h = 0; h < nh; ++h) {
    const auto v = static_cast<size_t>(tail(h));
    ++corners[v];
    any_out[v] = static_cast<int>(h);
  }
  for (size_t v = 0; v < nv; ++v) {
    const auto start = static_cast<size_t>(any_out[v]);
    // Clockwise to the boundary (or all the way round).
    size_t h = start;
    for (;;) {
      const int t = twin[h];
      if (t < 0) break;
      h = next(static_cast<size_t>(t));
      if (h == start) break;
    }
    // Counter-clockwise, counting the corners of this fan.
    const size_t fan_start = h;
    int count = 0;
    for (;;) {
      ++count;
      const int t = twin[prev(h)];
      if (t < 0 || static_cast<size_t>(t) == fan_start) break;
      h = static_cast<size_t>(t);
    }
    if (count != corners[v])
      fail(
          fmt::format("vertex {} joins faces that form more than one fan around it "
                      "(non-manifold vertex)",
                      v));
  }

  // A planar mesh (every z = 0) must not fold over itself: where it does (an interior
  // vertex moved outside the ring of its neighbours), the faces on either side of an edge
  // turn opposite ways and the plane's own directions are no longer the mesh's.
  const bool planar = std::all_of(positions.begin(), positions.end(), [](const Vec3& p) { return p.z() == 0.0; });
  if (planar) {
    auto signed_area = [&](size_t f) {
      const Face& t = faces[f];
      const Vec3& a = positions[static_cast<size_t>(t[0])];
      const Vec3 u = positions[static_cast<size_t>(t[1])] - a, w = positions[static_cast<size_t>(t[2])] - a;
      return u.x() * w.y() - u.y() * w.x();
    };
    std::vector<double> area(nf);
    double total = 0;
    for (size_t f = 0; f < nf; ++f) total += area[f] = signed_area(f);
    size_t fold = nh;
    for (size_t h = 0; h < nh && fold == nh; ++h)
      if (twin[h] >= 0 && (area[h / 3] > 0) != (area[static_cast<size_t>(twin[h]) / 3] > 0)) fold = h;
    if (fold != nh) {
      // Name the vertex the fold is around: an interior vertex whose faces do not wind
      // once around it (their signed corner angles sum to 0 instead of ±2π).
      std::vector<double> winding(nv, 0.0);
      std::vector<std::uint8_t> boundary(nv, 0);
      for (size_t h = 0; h < nh; ++h) {
        const auto v = static_cast<size_t>(tail(h));
        if (twin[h] < 0) boundary[v] = boundary[static_cast<size_t>(head(h))] = 1;
        const Vec3 a = positions[static_cast<size_t>(head(h))] - positions[v];
        const Vec3 b = positions[static_cast<size_t>(head(next(h)))] - positions[v];
        winding[v] += std::atan2(a.x() * b.y() - a.y() * b.x(), a.x() * b.x() + a.y() * b.y());
      }
      const double turn = total > 0 ? 2 * std::numbers::pi : -2 * std::numbers::pi;
      size_t vertex = static_cast<size_t>(tail(fold));
      for (size_t v = 0; v < nv; ++v)
        if (!boundary[v] && std::abs(winding[v] - turn) > 1e-6) {
          vertex = v;
          break;
        }
      fail(fmt::format("the planar mesh folds over itself at vertex {} {}: faces {} and {} on either side of edge "
                       "{}–{} turn opposite ways (a vertex outside the ring of its neighbours)",
                       vertex, format_point(positions[vertex]), fold / 3, static_cast<size_t>(twin[fold]) / 3,
                       tail(fold), head(fold)));
    }
  }
}

MeshRepairReport repair_triangle_soup(std::vector<Vec3>& positions, std::vector<Face>& faces) {
  MeshRepairReport report;
  const size_t nv = positions.size();
  // Out-of-range indices make both repairs meaningless; validation reports them.
  if (nv == 0 || faces.empty() || !indices_in_range(faces, nv)) return report;

  std::vector<std::uint8_t> keep(faces.size(), 1);
  for_each_duplicate_face(faces, nv, [&](int, int other) { keep[static_cast<size_t>(other)] = 0; });
  size_t out = 0;
  for (size_t f = 0; f < faces.size(); ++f)
    if (keep[f]) faces[out++] = faces[f];
  report.duplicate_faces_removed = static_cast<int>(faces.size() - out);
  faces.resize(out);

  std::vector<int> remap(nv, -1);
  for (const Face& t : faces)
    for (int v : t) remap[static_cast<size_t>(v)] = 0;
  int next_index = 0;
  for (size_t v = 0; v < nv; ++v) {
    if (remap[v] < 0) continue;
    remap[v] = next_index;
    positions[static_cast<size_t>(next_index)] = positions[v];
    ++next_index;
  }
  report.unreferenced_vertices_removed = static_cast<int>(nv) - next_index;
  positions.resize(static_cast<size_t>(next_index));
  if (report.unreferenced_vertices_removed > 0)
    for (Face& t : faces)
      for (int& v : t) v = remap[static_cast<size_t>(v)];
  return report;
}

}  // namespace tvf
