#include "tvf/analysis/topology.h"

#include "analysis/index_predicates.h"

#include "tvf/analysis/coherence.h"
#include "tvf/core/error.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <utility>

namespace tvf {

using namespace detail;

namespace {

// Below this |Ω_f| (< π/4), a prism whose twelve edges all turn by less than π/4 cannot
// hold a crossing: every triangle's |Σ a + Ω| stays below π.
constexpr double kSmallCurvature = 0.7;



// True when the turn from z_lo to z_hi (against r) is certainly below π/4 in magnitude:
// then the simulation of simplicity plays no part (the leading coefficient is non-zero
// with a positive real part).
bool small_turn(cplx zi, cplx zj, cplx r) {
  // q = z_hi · conj(r·z_lo), written out (std::complex's product checks for inf/NaN).
  const double pr = r.real() * zi.real() - r.imag() * zi.imag();
  const double pi = r.real() * zi.imag() + r.imag() * zi.real();
  const double qr = zj.real() * pr + zj.imag() * pi;
  const double qi = zj.imag() * pr - zj.real() * pi;
  return qr > std::abs(qi);
}

// The per-frame scale of singularities.cpp: values × 2^-exponent with the largest
// component in [0.5, 1), magnitudes below 2^-460 of it flushed to zero. Throws tvf::Error
// naming the frame and vertex of a value that is not finite.
int frame_exponent(const Mesh& mesh, std::span<const cplx> values, int frame) {
  double largest = 0;
  for (size_t v = 0; v < values.size(); ++v) {
    const cplx z = values[v];
    if (!std::isfinite(z.real()) || !std::isfinite(z.imag()))
      throw_input_error(mesh.source(), "",
                        fmt::format("topology: the field value at frame {}, vertex {} is not finite "
                                    "({} + {}i)",
                                    frame, v, z.real(), z.imag()));
    largest = std::max({largest, std::abs(z.real()), std::abs(z.imag())});
  }
  int e = 0;
  if (largest > 0) std::frexp(largest, &e);
  return e;
}
// One value scaled as above. Multiplying by the power of two rounds exactly as ldexp does
// (one correctly rounded result), and is much cheaper.
struct FrameScale {
  explicit FrameScale(int exponent)
      : factor(exponent > -1000 && exponent < 1000 ? std::ldexp(1.0, -exponent) : 0.0), e(exponent) {}
  cplx operator()(cplx z) const {
    const cplx x = factor != 0 ? cplx(z.real() * factor, z.imag() * factor)
                               : cplx(std::ldexp(z.real(), -e), std::ldexp(z.imag(), -e));
    constexpr double tiny = 0x1p-460;
    return std::abs(x.real()) < tiny && std::abs(x.imag()) < tiny ? cplx(0, 0) : x;
  }
  double factor;
  int e;
};
void normalize_frame(std::span<const cplx> values, int exponent, std::vector<cplx>& out) {
  const FrameScale scale(exponent);
  out.resize(values.size());
  for (size_t v = 0; v < values.size(); ++v) out[v] = scale(values[v]);
}


// ---- Space-time complex -------------------------------------------------------------
//
// Prism of face f between frames j and j+1, with the face's vertices sorted a < b < c.
// Local vertex L = 0..5 is (a, j), (b, j), (c, j), (a, j+1), (b, j+1), (c, j+1): the global
// order. Its ten triangles (vertices in increasing order, the canonical orientation):
enum TriKind : std::uint64_t { kFrameTri = 0, kSideTri = 1, kInteriorTri = 2 };
struct PrismTriangle {
  std::array<int, 3> v;  // local vertices, increasing
  TriKind kind;
  int which;  // frame: 0 bottom, 1 top; side: pair (0 ab, 1 bc, 2 ac); interior: 0 or 1
  int upper;  // side: 0 the triangle with two vertices at frame j, 1 with two at j+1
};
constexpr std::array<PrismTriangle, 10> kTriangles = {{
    {{0, 1, 2}, kFrameTri, 0, 0},     // 0: bottom face (frame j)
    {{3, 4, 5}, kFrameTri, 1, 0},     // 1: top face (frame j+1)
    {{0, 1, 4}, kSideTri, 0, 0},      // 2: side ab, lower
    {{0, 3, 4}, kSideTri, 0, 1},      // 3: side ab, upper
    {{1, 2, 5}, kSideTri, 1, 0},      // 4: side bc, lower
    {{1, 4, 5}, kSideTri, 1, 1},      // 5: side bc, upper
    {{0, 2, 5}, kSideTri, 2, 0},      // 6: side ac, lower
    {{0, 3, 5}, kSideTri, 2, 1},      // 7: side ac, upper
    {{0, 1, 5}, kInteriorTri, 0, 0},  // 8: interior
    {{0, 4, 5}, kInteriorTri, 1, 0},  // 9: interior
}};
// The three tetrahedra (a_j b_j c_j c_j+1), (a_j b_j b_j+1 c_j+1), (a_j a_j+1 b_j+1 c_j+1);
// their boundary Σ_k (−1)^k [face opposite vertex k] as (triangle, sign).
constexpr std::array<std::array<std::pair<int, int>, 4>, 3> kTets = {{
    {{{4, +1}, {6, -1}, {8, +1}, {0, -1}}},
    {{{5, +1}, {9, -1}, {8, +1}, {2, -1}}},
    {{{1, +1}, {9, -1}, {7, +1}, {3, -1}}},
}};
// The twelve edges of the prism (local vertex pairs, increasing).
constexpr std::array<std::array<int, 2>, 12> kPrismEdges = {{
    {0, 1}, {1, 2}, {0, 2}, {3, 4}, {4, 5}, {3, 5}, {0, 3}, {1, 4}, {2, 5}, {0, 4}, {1, 5}, {0, 5},
}};

// Triangle keys: (layer << 35) | (kind << 33) | local, with layer the frame (frame
// triangles) or the slab (others) and local f, 2e + upper, or 2f + which.
std::uint64_t tri_key(std::uint64_t layer, TriKind kind, std::uint64_t local) {
  return (layer << 35) | (static_cast<std::uint64_t>(kind) << 33) | local;
}
int key_layer(std::uint64_t key) { return static_cast<int>(key >> 35); }
TriKind key_kind(std::uint64_t key) { return static_cast<TriKind>((key >> 33) & 3); }
std::uint64_t key_local(std::uint64_t key) { return key & ((std::uint64_t{1} << 33) - 1); }

// Per-face data of the prisms.
struct FaceInfo {
  std::array<int, 3> v;          // sorted vertices a < b < c
  std::array<int, 3> corner;     // corner (0..2 in the face) of a, b, c
  std::array<int, 3> edge;       // mesh edges ab, bc, ac
  int parity;                    // +1 when (a, b, c) is counter-clockwise in the face
  double omega;                  // Ω_f (face_curvature)
};

struct Crossing {
  std::uint64_t key;
  int slot;       // 0..|index|−1
  int index;      // in the canonical orientation
  Vec3 x = Vec3::Zero();
  double t = 0;
};
struct Link {
  std::uint64_t a;
  int sa;
  std::uint64_t b;
  int sb;
};

struct SlabResult {
  std::vector<Crossing> crossings;
  std::vector<Link> links;
};

class Tracker {
public:
  Tracker(const TangentBundle& bundle, const Field& field) : bundle_(bundle), mesh_(bundle.mesh()), field_(field) {
    const int ne = mesh_.num_edges();
    edge_r_.assign(static_cast<size_t>(ne), cplx(1, 0));
    edge_boundary_.assign(static_cast<size_t>(ne), 0);
    for (int h = 0; h < mesh_.num_halfedges(); ++h) {
      const auto e = static_cast<size_t>(mesh_.edge_of(h));
      if (mesh_.twin(h) < 0) edge_boundary_[e] = 1;
      if (mesh_.tail(h) < mesh_.head(h))
        edge_r_[e] = bundle_.transport(h);
      else if (mesh_.twin(h) < 0)
        edge_r_[e] = std::conj(bundle_.transport(h));
    }
    faces_.resize(static_cast<size_t>(mesh_.num_faces()));
    for (int f = 0; f < mesh_.num_faces(); ++f) {
      FaceInfo& fi = faces_[static_cast<size_t>(f)];
      const Face& t = mesh_.face(f);
      std::array<int, 3> order{0, 1, 2};
      std::sort(order.begin(), order.end(),
                [&](int x, int y) { return t[static_cast<size_t>(x)] < t[static_cast<size_t>(y)]; });
      for (size_t k = 0; k < 3; ++k) {
        fi.corner[k] = order[k];
        fi.v[k] = t[static_cast<size_t>(order[k])];
      }
      // (a, b, c) is a cyclic rotation of the face's order exactly when the corners are.
      fi.parity = (order[1] - order[0] + 3) % 3 == 1 ? 1 : -1;
      auto edge_between = [&](int x, int y) {
        for (int c = 0; c < 3; ++c) {
          const int h = 3 * f + c;
          if ((mesh_.tail(h) == x && mesh_.head(h) == y) || (mesh_.tail(h) == y && mesh_.head(h) == x))
            return mesh_.edge_of(h);
        }
        TVF_CHECK(false, "face {} has no edge {}–{}", f, x, y);
        return -1;
      };
      fi.edge = {edge_between(fi.v[0], fi.v[1]), edge_between(fi.v[1], fi.v[2]),
                 edge_between(fi.v[0], fi.v[2])};
      fi.omega = face_curvature(bundle_, f);
    }
    exponent_.resize(static_cast<size_t>(field_.frames()));
  }

  void compute_exponents(bool parallel, const std::atomic<bool>* cancel) {
    auto body = [&](int j) {
      check_analysis_cancel(cancel);
      exponent_[static_cast<size_t>(j)] = frame_exponent(mesh_, field_.frame(j), j);
    };
    if (parallel)
      tbb::parallel_for(0, field_.frames(), body);
    else
      for (int j = 0; j < field_.frames(); ++j) body(j);
  }

  // Crossings and tetrahedron links of the slabs j0..j1−1 (slab j: frames j and j+1), in
  // order, so that each frame is scaled and its edges tested once.
  void slabs(int j0, int j1, std::vector<SlabResult>& results, const std::atomic<bool>* cancel) const {
    const int ne = mesh_.num_edges();
    const int nv = mesh_.num_vertices();
    std::vector<cplx> z0, z1;
    // Edges that may turn by π/4 or more: in frame j, in frame j+1, and then any of those
    // or the diagonal (u, j)–(w, j+1); vertices whose value may turn so in time.
    std::vector<std::uint8_t> large0(static_cast<size_t>(ne)), large1(static_cast<size_t>(ne));
    std::vector<std::uint8_t> edge_large(static_cast<size_t>(ne)), time_large(static_cast<size_t>(nv));
    auto frame_flags = [&](const std::vector<cplx>& z, std::vector<std::uint8_t>& large) {
      for (int e = 0; e < ne; ++e) {
        const auto& uv = mesh_.edge(e);
        large[static_cast<size_t>(e)] =
            !small_turn(z[static_cast<size_t>(uv[0])], z[static_cast<size_t>(uv[1])], edge_r_[static_cast<size_t>(e)]);
      }
    };
    normalize_frame(field_.frame(j0), exponent_[static_cast<size_t>(j0)], z0);
    frame_flags(z0, large0);
    for (int j = j0; j < j1; ++j) {
      check_analysis_cancel(cancel);
      normalize_frame(field_.frame(j + 1), exponent_[static_cast<size_t>(j + 1)], z1);
      frame_flags(z1, large1);
      for (int e = 0; e < ne; ++e) {
        const auto& uv = mesh_.edge(e);
        const auto k = static_cast<size_t>(e);
        edge_large[k] = large0[k] | large1[k] |
                        static_cast<std::uint8_t>(!small_turn(z0[static_cast<size_t>(uv[0])],
                                                              z1[static_cast<size_t>(uv[1])], edge_r_[k]));
      }
      for (int v = 0; v < nv; ++v)
        time_large[static_cast<size_t>(v)] = !small_turn(z0[static_cast<size_t>(v)], z1[static_cast<size_t>(v)], 1.0);

      // Frame weights back to a common scale for positions: frame j's values are
      // z·2^-e_j, frame j+1's z·2^-e_{j+1}.
      const int e0 = exponent_[static_cast<size_t>(j)];
      const int e1 = exponent_[static_cast<size_t>(j + 1)];
      const int emax = std::max(e0, e1);
      const std::array<double, 2> layer_scale = {std::ldexp(1.0, e0 - emax), std::ldexp(1.0, e1 - emax)};
      const std::array<double, 2> layer_t = {field_.time().time(j), field_.time().time(j + 1)};
      SlabResult& out = results[static_cast<size_t>(j)];
      for (int f = 0; f < mesh_.num_faces(); ++f) {
        const FaceInfo& fi = faces_[static_cast<size_t>(f)];
        const bool suspicious =
            std::abs(fi.omega) >= kSmallCurvature || edge_large[static_cast<size_t>(fi.edge[0])] ||
            edge_large[static_cast<size_t>(fi.edge[1])] || edge_large[static_cast<size_t>(fi.edge[2])] ||
            time_large[static_cast<size_t>(fi.v[0])] || time_large[static_cast<size_t>(fi.v[1])] ||
            time_large[static_cast<size_t>(fi.v[2])];
        if (suspicious) prism(f, j, z0, z1, layer_scale, layer_t, out);
      }
      std::swap(z0, z1);
      std::swap(large0, large1);
    }
  }

  // The singularity of frame j in face f (index in the face's counter-clockwise order),
  // computed exactly as find_singularities does: zero of the face's linear interpolant
  // (clamped to the face), Jacobian in the face frame, type from it and the index.
  Singularity singularity(int j, int f, int index) const {
    const std::span<const cplx> values = field_.frame(j);
    const FrameScale scale(exponent_[static_cast<size_t>(j)]);
    const Face& t = mesh_.face(f);
    std::array<cplx, 3> w;
    for (int c = 0; c < 3; ++c)
      w[static_cast<size_t>(c)] = bundle_.corner_to_face(3 * f + c) * scale(values[static_cast<size_t>(t[static_cast<size_t>(c)])]);
    Singularity s;
    s.frame = j;
    s.t = field_.time().time(j);
    s.index = index;
    s.where.face = f;
    s.where.bary = zero_barycentric(w);
    s.position = Vec3::Zero();
    for (int c = 0; c < 3; ++c) s.position += s.where.bary[c] * mesh_.position(t[static_cast<size_t>(c)]);
    const Mat2 J = face_linear_jacobian(bundle_, f, w);
    if (index < 0) {
      s.type = SingularityType::saddle;
    } else {
      s.type = classify_jacobian(J);
      // Index +1 with det J < 0: trust the index (as find_singularities does).
      if (s.type == SingularityType::saddle)
        s.type = J.trace() >= 0 ? SingularityType::source : SingularityType::sink;
    }
    s.jacobian = J.unaryExpr([e = exponent_[static_cast<size_t>(j)]](double x) { return std::ldexp(x, e); });
    return s;
  }

  bool edge_is_boundary(int e) const { return edge_boundary_[static_cast<size_t>(e)] != 0; }
  const FaceInfo& face_info(int f) const { return faces_[static_cast<size_t>(f)]; }

private:
  void prism(int f, int j, const std::vector<cplx>& z0, const std::vector<cplx>& z1,
             const std::array<double, 2>& layer_scale, const std::array<double, 2>& layer_t,
             SlabResult& out) const {
    const FaceInfo& fi = faces_[static_cast<size_t>(f)];
    auto spatial = [&](int L) { return fi.v[static_cast<size_t>(L % 3)]; };
    auto value = [&](int L) {
      const auto v = static_cast<size_t>(spatial(L));
      return L < 3 ? z0[v] : z1[v];
    };
    // Transport from spatial slot x to slot y (x < y in vertex order): the edge's.
    auto transport = [&](int x, int y) -> cplx {
      if (x == y) return 1.0;
      const int pair = (x == 0 && y == 1) ? 0 : (x == 1 && y == 2) ? 1 : 2;
      return edge_r_[static_cast<size_t>(fi.edge[static_cast<size_t>(pair)])];
    };
    std::array<std::array<double, 6>, 6> angle{};
    for (const auto& pq : kPrismEdges) {
      const int P = pq[0], Q = pq[1];
      angle[static_cast<size_t>(P)][static_cast<size_t>(Q)] =
          edge_angle(value(P), value(Q), transport(P % 3, Q % 3));
    }
    auto a = [&](int P, int Q) { return angle[static_cast<size_t>(P)][static_cast<size_t>(Q)]; };

    std::array<int, 10> index{};
    bool any = false;
    for (size_t k = 0; k < kTriangles.size(); ++k) {
      const auto& v = kTriangles[k].v;
      double turn = a(v[0], v[1]) + a(v[1], v[2]) - a(v[0], v[2]);
      const int s0 = v[0] % 3, s1 = v[1] % 3, s2 = v[2] % 3;
      if (s0 != s1 && s1 != s2 && s0 != s2) {
        // Sign of the permutation (s0, s1, s2) of (0, 1, 2), times the face's parity.
        const int perm = ((s1 - s0 + 3) % 3 == 1) ? 1 : -1;
        turn += perm * fi.parity * fi.omega;
      }
      const double m = std::round(turn / kTwoPi);
      TVF_CHECK(std::abs(turn - kTwoPi * m) < 1e-6,
                "face {} slab {} triangle {}: space-time turns do not close (residual {})", f, j, k,
                turn - kTwoPi * m);
      index[k] = static_cast<int>(m);
      any = any || index[k] != 0;
    }
    if (!any) return;

    std::array<std::uint64_t, 10> key{};
    for (size_t k = 0; k < kTriangles.size(); ++k) {
      const PrismTriangle& T = kTriangles[k];
      switch (T.kind) {
        case kFrameTri:
          key[k] = tri_key(static_cast<std::uint64_t>(j + T.which), kFrameTri, static_cast<std::uint64_t>(f));
          break;
        case kSideTri:
          key[k] = tri_key(static_cast<std::uint64_t>(j), kSideTri,
                           2 * static_cast<std::uint64_t>(fi.edge[static_cast<size_t>(T.which)]) +
                               static_cast<std::uint64_t>(T.upper));
          break;
        case kInteriorTri:
          key[k] = tri_key(static_cast<std::uint64_t>(j), kInteriorTri,
                           2 * static_cast<std::uint64_t>(f) + static_cast<std::uint64_t>(T.which));
          break;
      }
      if (index[k] == 0) continue;
      Crossing c{key[k], 0, index[k]};
      if (T.kind != kFrameTri) {
        // Values in one frame: the lower vertex's for a side triangle (so both prisms of
        // the side compute the same point), the face's for an interior one.
        std::array<cplx, 3> w;
        for (size_t i = 0; i < 3; ++i) {
          const int L = T.v[i];
          cplx z = value(L) * layer_scale[static_cast<size_t>(L / 3)];
          if (T.kind == kSideTri) {
            const int lower = T.which == 1 ? 1 : 0;  // ab, ac: a; bc: b
            if (L % 3 != lower) z *= std::conj(transport(lower, L % 3));
          } else {
            z *= bundle_.corner_to_face(3 * f + fi.corner[static_cast<size_t>(L % 3)]);
          }
          w[i] = z;
        }
        const Vec3 b = zero_barycentric(w);
        for (size_t i = 0; i < 3; ++i) {
          const int L = T.v[i];
          c.x += b[static_cast<Eigen::Index>(i)] * mesh_.position(spatial(L));
          c.t += b[static_cast<Eigen::Index>(i)] * layer_t[static_cast<size_t>(L / 3)];
        }
      }
      for (int s = 0; s < std::abs(index[k]); ++s) {
        c.slot = s;
        out.crossings.push_back(c);
      }
    }

    // Pair the crossings of each tetrahedron: the boundary indices sum to zero, so every
    // curve that enters leaves.
    for (const auto& tet : kTets) {
      std::array<std::pair<std::uint64_t, int>, 8> in{}, outs{};
      int n_in = 0, n_out = 0, total = 0;
      for (const auto& [k, sign] : tet) {
        const int idx = sign * index[static_cast<size_t>(k)];
        total += idx;
        for (int s = 0; s < std::abs(idx); ++s) {
          auto& list = idx > 0 ? in : outs;
          int& n = idx > 0 ? n_in : n_out;
          TVF_CHECK(n < 8, "face {} slab {}: too many crossings in one tetrahedron", f, j);
          list[static_cast<size_t>(n++)] = {key[static_cast<size_t>(k)], s};
        }
      }
      TVF_CHECK(total == 0, "face {} slab {}: tetrahedron boundary index {} (not 0)", f, j, total);
      for (int m = 0; m < n_in; ++m)
        out.links.push_back({in[static_cast<size_t>(m)].first, in[static_cast<size_t>(m)].second,
                             outs[static_cast<size_t>(m)].first, outs[static_cast<size_t>(m)].second});
    }
  }

  const TangentBundle& bundle_;
  const Mesh& mesh_;
  const Field& field_;
  std::vector<cplx> edge_r_;  // transport from the lower to the higher vertex of each edge
  std::vector<std::uint8_t> edge_boundary_;
  std::vector<FaceInfo> faces_;
  std::vector<int> exponent_;
};

// ---- Curves, tracks and paths ---------------------------------------------------------

struct Node {
  std::uint64_t key = 0;
  int slot = 0;
  int index = 0;
  TriKind kind = kFrameTri;
  int layer = 0;    // frame (frame nodes) or slab
  int sing = -1;    // frame nodes: position in singularities[layer]
  Vec3 x = Vec3::Zero();
  double t = 0;
  std::array<int, 2> nb{-1, -1};
};

// What a change of type along a track is measured in. Without node_focus_changes a node
// and a focus of the same stability are one class: they are topologically equivalent
// (Hartman–Grobman; a linear sink is conjugate to a linear attracting focus) and the
// boundary between them, equal eigenvalues, is no bifurcation. What remains is the index
// (saddle) and, for index +1, the stability: attracting, repelling, or the non-hyperbolic
// center between them.
int type_class(SingularityType t, bool node_focus_changes) {
  if (node_focus_changes) return static_cast<int>(t);
  switch (t) {
    case SingularityType::source:
    case SingularityType::repelling_focus: return 0;
    case SingularityType::sink:
    case SingularityType::attracting_focus: return 1;
    case SingularityType::saddle: return 2;
    case SingularityType::center: return 3;
  }
  return 4;
}

// The class runs of a track and where it changes: returns the positions (in `types`) at
// which a new path starts, with the type of every path: the type held at most of the
// path's frames of the path's class (ties to the earlier enumerator: a node before a focus).
void split_types(const std::vector<SingularityType>& types, int min_run, bool node_focus_changes,
                 std::vector<int>& starts, std::vector<SingularityType>& path_types, int& suppressed) {
  starts.clear();
  path_types.clear();
  std::vector<int> cls(types.size());
  for (size_t i = 0; i < types.size(); ++i) cls[i] = type_class(types[i], node_focus_changes);
  struct Run {
    int start, length, cls;
  };
  std::vector<Run> runs;
  for (int i = 0; i < static_cast<int>(types.size()); ++i) {
    if (runs.empty() || runs.back().cls != cls[static_cast<size_t>(i)])
      runs.push_back({i, 1, cls[static_cast<size_t>(i)]});
    else
      ++runs.back().length;
  }
  // The starting class: the first that holds long enough; else the most frequent.
  const Run* first = nullptr;
  for (const Run& r : runs)
    if (r.length >= min_run) {
      first = &r;
      break;
    }
  int current;
  if (first) {
    current = first->cls;
  } else {
    std::array<int, 6> count{};
    for (const int c : cls) ++count[static_cast<size_t>(c)];
    current = cls.front();
    for (const int c : cls)
      if (count[static_cast<size_t>(c)] > count[static_cast<size_t>(current)]) current = c;
  }
  std::vector<int> path_cls;
  starts.push_back(0);
  path_cls.push_back(current);
  for (const Run& r : runs) {
    if (r.cls == current) continue;
    if (r.length >= min_run) {
      starts.push_back(r.start);
      path_cls.push_back(r.cls);
      current = r.cls;
    } else {
      ++suppressed;
    }
  }
  for (size_t p = 0; p < starts.size(); ++p) {
    const size_t from = static_cast<size_t>(starts[p]);
    const size_t to = p + 1 < starts.size() ? static_cast<size_t>(starts[p + 1]) : types.size();
    std::array<int, 6> count{};
    for (size_t i = from; i < to; ++i)
      if (cls[i] == path_cls[p]) ++count[static_cast<size_t>(types[i])];
    size_t best = 0;
    for (size_t k = 1; k < count.size(); ++k)
      if (count[k] > count[best]) best = k;
    path_types.push_back(static_cast<SingularityType>(best));
  }
}

}  // namespace

const char* to_string(BifurcationKind k) {
  switch (k) {
    case BifurcationKind::creation: return "creation";
    case BifurcationKind::cancellation: return "cancellation";
  }
  return "unknown";
}

Topology analyze_topology(const TangentBundle& bundle, const Field& field, const TopologyOptions& options) {
  const Mesh& mesh = bundle.mesh();
  TVF_CHECK(field.num_vertices() == mesh.num_vertices(), "field of {} vertices on a mesh of {}",
            field.num_vertices(), mesh.num_vertices());
  TVF_CHECK(options.type_change_samples >= 1, "type_change_samples = {}", options.type_change_samples);
  const int N = field.frames();
  Topology topo;
  topo.times = field.time().times();
  topo.singularities.resize(static_cast<size_t>(N));
  topo.singularity_path.resize(static_cast<size_t>(N));
  if (N == 0) return topo;
  Tracker tracker(bundle, field);
  tracker.compute_exponents(options.parallel, options.cancel);  // throws on non-finite values
  topo.coherence = coherence(field);

  // One frame: every singularity is a path of one point.
  if (N == 1) {
    topo.singularities[0] = find_singularities(bundle, field, 0);
    topo.singularity_path[0].assign(topo.singularities[0].size(), -1);
    for (size_t k = 0; k < topo.singularities[0].size(); ++k) {
      const Singularity& s = topo.singularities[0][k];
      SingularityPath p;
      p.id = static_cast<int>(topo.paths.size());
      p.type = s.type;
      p.index = s.index;
      p.birth = p.death = s.t;
      p.points.push_back({s.position, s.t});
      topo.singularity_path[0][k] = p.id;
      topo.paths.push_back(std::move(p));
    }
    return topo;
  }

  // Crossings and links, slab by slab.
  std::vector<SlabResult> slabs(static_cast<size_t>(N - 1));
  if (options.parallel) {
    // Runs of at least 4 slabs, so that each run scales and tests most frames once.
    tbb::parallel_for(tbb::blocked_range<int>(0, N - 1, 4),
                      [&](const tbb::blocked_range<int>& r) { tracker.slabs(r.begin(), r.end(), slabs, options.cancel); });
  } else {
    tracker.slabs(0, N - 1, slabs, options.cancel);
  }
  check_analysis_cancel(options.cancel);

  // Nodes: one per crossing slot (the prisms on both sides of a triangle report it).
  std::vector<Crossing> all;
  for (const SlabResult& s : slabs) all.insert(all.end(), s.crossings.begin(), s.crossings.end());
  std::sort(all.begin(), all.end(), [](const Crossing& a, const Crossing& b) {
    return a.key != b.key ? a.key < b.key : a.slot < b.slot;
  });
  all.erase(std::unique(all.begin(), all.end(),
                        [](const Crossing& a, const Crossing& b) { return a.key == b.key && a.slot == b.slot; }),
            all.end());
  std::vector<Node> nodes(all.size());
  for (size_t n = 0; n < all.size(); ++n) {
    Node& nd = nodes[n];
    nd.key = all[n].key;
    nd.slot = all[n].slot;
    nd.index = all[n].index;
    nd.kind = key_kind(nd.key);
    nd.layer = key_layer(nd.key);
    nd.x = all[n].x;
    nd.t = all[n].t;
  }
  topo.stats.crossings = static_cast<long long>(nodes.size());
  auto find_node = [&](std::uint64_t key, int slot) {
    const auto it = std::lower_bound(all.begin(), all.end(), std::make_pair(key, slot),
                                     [](const Crossing& c, const std::pair<std::uint64_t, int>& k) {
                                       return c.key != k.first ? c.key < k.first : c.slot < k.second;
                                     });
    TVF_CHECK(it != all.end() && it->key == key && it->slot == slot, "link to an unknown crossing");
    return static_cast<int>(it - all.begin());
  };
  for (const SlabResult& s : slabs) {
    for (const Link& l : s.links) {
      const int a = find_node(l.a, l.sa);
      const int b = find_node(l.b, l.sb);
      for (const auto& [x, y] : {std::pair{a, b}, std::pair{b, a}}) {
        auto& nb = nodes[static_cast<size_t>(x)].nb;
        TVF_CHECK(nb[1] < 0, "crossing {} has more than two neighbours", x);
        (nb[0] < 0 ? nb[0] : nb[1]) = y;
      }
    }
  }
  slabs.clear();

  // The crossed triangles of frame j are its singularities (the same predicates as
  // find_singularities, in the same order of vertices): build them from the frame nodes,
  // which come sorted by frame and face. A face of index ±2 gives two nodes, one
  // singularity.
  for (size_t n = 0; n < nodes.size(); ++n) {
    Node& nd = nodes[n];
    const int degree = (nd.nb[0] >= 0) + (nd.nb[1] >= 0);
    int expected = 2;
    if (nd.kind == kFrameTri) {
      auto& sings = topo.singularities[static_cast<size_t>(nd.layer)];
      const int f = static_cast<int>(key_local(nd.key));
      if (sings.empty() || sings.back().where.face != f)
        sings.push_back(tracker.singularity(nd.layer, f, tracker.face_info(f).parity * nd.index));
      nd.sing = static_cast<int>(sings.size()) - 1;
      nd.x = sings.back().position;
      nd.t = sings.back().t;
      if (nd.layer == 0 || nd.layer == N - 1) expected = 1;
    } else if (nd.kind == kSideTri) {
      if (tracker.edge_is_boundary(static_cast<int>(key_local(nd.key) / 2))) expected = 1;
    }
    TVF_CHECK(degree == expected, "crossing {} (kind {}, layer {}) has {} neighbours, expected {}", n,
              static_cast<int>(nd.kind), nd.layer, degree, expected);
  }
  for (int j = 0; j < N; ++j)
    topo.singularity_path[static_cast<size_t>(j)].assign(topo.singularities[static_cast<size_t>(j)].size(), -1);

  // Curves: chains from their ends, then loops.
  std::vector<std::uint8_t> seen(nodes.size(), 0);
  std::vector<std::pair<std::vector<int>, bool>> curves;  // nodes in order, closed
  auto walk = [&](int start) {
    std::vector<int> c;
    int prev = -1, cur = start;
    while (cur >= 0 && !seen[static_cast<size_t>(cur)]) {
      seen[static_cast<size_t>(cur)] = 1;
      c.push_back(cur);
      const auto& nb = nodes[static_cast<size_t>(cur)].nb;
      const int next = nb[0] == prev ? nb[1] : nb[0];
      prev = cur;
      cur = next;
    }
    return c;
  };
  for (size_t n = 0; n < nodes.size(); ++n)
    if (!seen[n] && nodes[n].nb[1] < 0) curves.emplace_back(walk(static_cast<int>(n)), false);
  for (size_t n = 0; n < nodes.size(); ++n)
    if (!seen[n]) curves.emplace_back(walk(static_cast<int>(n)), true);
  topo.stats.curves = static_cast<int>(curves.size());

  // Tracks: runs of frame nodes at consecutive frames, with the pieces of the curve that
  // lead to a bifurcation or the boundary at either end.
  struct Track {
    std::vector<int> nodes;  // curve order
    bool reversed = false;
  };
  struct PendingBifurcation {
    int node;
    BifurcationKind kind;
    int track_tail;  // the track whose curve-order tail meets it
    int track_head;  // the track whose curve-order head meets it
  };
  std::vector<Track> tracks;
  std::vector<PendingBifurcation> pending;
  auto is_frame = [&](int n) { return nodes[static_cast<size_t>(n)].kind == kFrameTri; };
  auto frame_of = [&](int n) { return nodes[static_cast<size_t>(n)].layer; };

  for (auto& curve : curves) {
    // Named references, not a structured binding: the lambdas below use c, and clang 14
    // (the fuzz preset's compiler) cannot capture structured bindings.
    std::vector<int>& c = curve.first;
    const bool closed = curve.second;
    std::vector<int> F;
    for (size_t k = 0; k < c.size(); ++k)
      if (is_frame(c[k])) F.push_back(static_cast<int>(k));
    if (F.empty()) {
      ++topo.stats.hidden_curves;
      continue;
    }
    const int m = static_cast<int>(F.size());
    if (closed) {
      // Start at a frame node that follows a turn, so that no track wraps around.
      int start = -1;
      for (int i = 0; i < m && start < 0; ++i) {
        const int prev = F[static_cast<size_t>((i + m - 1) % m)];
        if (frame_of(c[static_cast<size_t>(prev)]) == frame_of(c[static_cast<size_t>(F[static_cast<size_t>(i)])]))
          start = i;
      }
      TVF_CHECK(start >= 0, "a closed zero curve that never turns back in time");
      std::rotate(c.begin(), c.begin() + F[static_cast<size_t>(start)], c.end());
      c.push_back(c.front());
      F.clear();
      for (size_t k = 0; k + 1 < c.size(); ++k)
        if (is_frame(c[k])) F.push_back(static_cast<int>(k));
    }
    // Segment after frame node i (curve positions F[i]..end): ends at F[i+1], at the
    // curve's end (open), or at the closing copy of c[0] (closed).
    auto seg_end = [&](int i) {
      if (i + 1 < m) return F[static_cast<size_t>(i + 1)];
      return static_cast<int>(c.size()) - 1;
    };
    enum class Seg { none, monotone, turn, boundary };
    auto seg_kind = [&](int from, int to) {
      if (from == to) return Seg::none;
      const int a = c[static_cast<size_t>(from)], b = c[static_cast<size_t>(to)];
      if (!is_frame(a) || !is_frame(b)) return Seg::boundary;
      return frame_of(a) == frame_of(b) ? Seg::turn : Seg::monotone;
    };
    // Extreme node of a turn segment (positions from..to, frame nodes at both ends).
    auto extreme = [&](int from, int to, BifurcationKind& kind) {
      const int frame = frame_of(c[static_cast<size_t>(from)]);
      const int first_inner = c[static_cast<size_t>(from + 1)];
      const bool above = nodes[static_cast<size_t>(first_inner)].layer == frame;
      kind = above ? BifurcationKind::cancellation : BifurcationKind::creation;
      int best = from + 1;
      for (int k = from + 1; k < to; ++k) {
        const double t = nodes[static_cast<size_t>(c[static_cast<size_t>(k)])].t;
        const double tb = nodes[static_cast<size_t>(c[static_cast<size_t>(best)])].t;
        if (above ? t > tb : t < tb) best = k;
      }
      return best;
    };

    // Head of the curve before the first frame node (open curves only).
    const int head_end = closed ? 0 : F[0];
    const int first_track = static_cast<int>(tracks.size());
    int current = -1;
    for (int i = 0; i < m; ++i) {
      const int fi = F[static_cast<size_t>(i)];
      const int prev_start = i > 0 ? F[static_cast<size_t>(i - 1)] : 0;
      const Seg before = i > 0 ? seg_kind(prev_start, fi) : (closed ? Seg::turn : seg_kind(0, head_end));
      if (before != Seg::monotone) {
        current = static_cast<int>(tracks.size());
        tracks.emplace_back();
        Track& tr = tracks.back();
        if (before == Seg::boundary) {
          for (int k = 0; k < fi; ++k) tr.nodes.push_back(c[static_cast<size_t>(k)]);
        } else if (before == Seg::turn) {
          // The turn before this node: positions prev..fi (closed i = 0: the closing
          // segment, handled when it is reached at the end, which appends here).
          if (i > 0) {
            BifurcationKind kind;
            const int ex = extreme(prev_start, fi, kind);
            for (int k = ex; k < fi; ++k) tr.nodes.push_back(c[static_cast<size_t>(k)]);
            pending.push_back({c[static_cast<size_t>(ex)], kind, current - 1, current});
          }
        }
      }
      Track& tr = tracks[static_cast<size_t>(current)];
      tr.nodes.push_back(c[static_cast<size_t>(fi)]);
      const int end = seg_end(i);
      const Seg after = (i + 1 < m) ? seg_kind(fi, end) : (closed ? Seg::turn : seg_kind(fi, end));
      if (after == Seg::monotone) {
        for (int k = fi + 1; k < end; ++k) tr.nodes.push_back(c[static_cast<size_t>(k)]);
      } else if (after == Seg::boundary) {
        for (int k = fi + 1; k <= end; ++k) tr.nodes.push_back(c[static_cast<size_t>(k)]);
      } else if (after == Seg::turn) {
        BifurcationKind kind;
        const int ex = extreme(fi, end, kind);
        for (int k = fi + 1; k <= ex; ++k) tr.nodes.push_back(c[static_cast<size_t>(k)]);
        if (i + 1 == m && closed) {
          // The closing turn leads back to the first track of this curve.
          Track& head = tracks[static_cast<size_t>(first_track)];
          std::vector<int> prefix;
          for (int k = ex; k < end; ++k) prefix.push_back(c[static_cast<size_t>(k)]);
          head.nodes.insert(head.nodes.begin(), prefix.begin(), prefix.end());
          pending.push_back({c[static_cast<size_t>(ex)], kind, current, first_track});
        }
      }
    }
  }

  // Orient tracks in time, split them at type changes, and emit paths.
  std::vector<std::array<int, 2>> track_paths(tracks.size(), {-1, -1});  // curve-order head, tail
  for (size_t ti = 0; ti < tracks.size(); ++ti) {
    Track& tr = tracks[ti];
    std::vector<int> fnodes;
    for (const int n : tr.nodes)
      if (is_frame(n)) fnodes.push_back(n);
    const int f0 = frame_of(fnodes.front()), f1 = frame_of(fnodes.back());
    if (f0 != f1) {
      tr.reversed = f0 > f1;
    } else {
      // One frame node: the slab of the piece before it in curve order says which way
      // time runs (below: forward), else the piece after it (above: forward), else the
      // end of the time range it sits on. Comparing times would fail where both pieces
      // only touch the frame.
      const auto at = static_cast<size_t>(std::find(tr.nodes.begin(), tr.nodes.end(), fnodes.front()) - tr.nodes.begin());
      if (at > 0)
        tr.reversed = nodes[static_cast<size_t>(tr.nodes[at - 1])].layer != f0 - 1;
      else if (at + 1 < tr.nodes.size())
        tr.reversed = nodes[static_cast<size_t>(tr.nodes[at + 1])].layer != f0;
      else
        tr.reversed = false;
    }
    if (tr.reversed) {
      std::reverse(tr.nodes.begin(), tr.nodes.end());
      std::reverse(fnodes.begin(), fnodes.end());
    }
    std::vector<SingularityType> types;
    for (const int n : fnodes) {
      const Node& nd = nodes[static_cast<size_t>(n)];
      types.push_back(topo.singularities[static_cast<size_t>(nd.layer)][static_cast<size_t>(nd.sing)].type);
    }
    std::vector<int> starts;
    std::vector<SingularityType> path_types;
    split_types(types, options.type_change_samples, options.node_focus_changes, starts, path_types,
                topo.stats.suppressed_flickers);
    topo.stats.type_changes += static_cast<int>(starts.size()) - 1;
    // Positions in tr.nodes where each path starts and ends.
    std::vector<int> fpos;
    for (size_t k = 0; k < tr.nodes.size(); ++k)
      if (is_frame(tr.nodes[k])) fpos.push_back(static_cast<int>(k));
    const int first_path = static_cast<int>(topo.paths.size());
    for (size_t p = 0; p < starts.size(); ++p) {
      const int from = p == 0 ? 0 : fpos[static_cast<size_t>(starts[p])];
      const int to = p + 1 < starts.size() ? fpos[static_cast<size_t>(starts[p + 1])]
                                           : static_cast<int>(tr.nodes.size()) - 1;
      SingularityPath path;
      path.id = static_cast<int>(topo.paths.size());
      path.type = path_types[p];
      const Node& lead = nodes[static_cast<size_t>(fnodes[static_cast<size_t>(starts[p])])];
      path.index = topo.singularities[static_cast<size_t>(lead.layer)][static_cast<size_t>(lead.sing)].index;
      for (int k = from; k <= to; ++k) {
        const Node& nd = nodes[static_cast<size_t>(tr.nodes[static_cast<size_t>(k)])];
        // Keep t non-decreasing: a crossing between frames that steps back in time (the
        // piecewise-linear curve wiggling inside one slab) replaces the points it undercuts.
        while (!path.points.empty() && path.points.back().t > nd.t) path.points.pop_back();
        path.points.push_back({nd.x, nd.t});
        // The frame node at a type change belongs to the new path.
        if (nd.kind == kFrameTri && (k < to || p + 1 == starts.size()))
          topo.singularity_path[static_cast<size_t>(nd.layer)][static_cast<size_t>(nd.sing)] = path.id;
      }
      path.birth = path.points.front().t;
      path.death = path.points.back().t;
      topo.paths.push_back(std::move(path));
    }
    const int last_path = static_cast<int>(topo.paths.size()) - 1;
    track_paths[ti] = tr.reversed ? std::array<int, 2>{last_path, first_path}
                                  : std::array<int, 2>{first_path, last_path};
  }
  for (const PendingBifurcation& pb : pending) {
    Bifurcation b;
    const Node& nd = nodes[static_cast<size_t>(pb.node)];
    b.t = nd.t;
    b.position = nd.x;
    b.kind = pb.kind;
    const int pa = track_paths[static_cast<size_t>(pb.track_tail)][1];
    const int pc = track_paths[static_cast<size_t>(pb.track_head)][0];
    b.paths = {std::min(pa, pc), std::max(pa, pc)};
    topo.bifurcations.push_back(b);
  }

  // Paths by birth (then place), bifurcations by time; renumber.
  std::vector<int> order(topo.paths.size());
  std::iota(order.begin(), order.end(), 0);
  auto lex = [](const Vec3& a, const Vec3& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  };
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) {
    const SingularityPath& a = topo.paths[static_cast<size_t>(x)];
    const SingularityPath& b = topo.paths[static_cast<size_t>(y)];
    if (a.birth != b.birth) return a.birth < b.birth;
    return lex(a.points.front().position, b.points.front().position);
  });
  std::vector<int> new_id(order.size());
  std::vector<SingularityPath> sorted;
  sorted.reserve(order.size());
  for (size_t k = 0; k < order.size(); ++k) {
    new_id[static_cast<size_t>(order[k])] = static_cast<int>(k);
    sorted.push_back(std::move(topo.paths[static_cast<size_t>(order[k])]));
    sorted.back().id = static_cast<int>(k);
  }
  topo.paths = std::move(sorted);
  for (auto& frame : topo.singularity_path)
    for (int& id : frame)
      if (id >= 0) id = new_id[static_cast<size_t>(id)];
  for (Bifurcation& b : topo.bifurcations) {
    b.paths = {new_id[static_cast<size_t>(b.paths[0])], new_id[static_cast<size_t>(b.paths[1])]};
    if (b.paths[0] > b.paths[1]) std::swap(b.paths[0], b.paths[1]);
  }
  std::stable_sort(topo.bifurcations.begin(), topo.bifurcations.end(), [&](const Bifurcation& a, const Bifurcation& b) {
    if (a.t != b.t) return a.t < b.t;
    return lex(a.position, b.position);
  });
  return topo;
}

nlohmann::json topology_to_json(const Topology& topology) {
  using nlohmann::json;
  auto vec3 = [](const Vec3& x) { return json::array({x.x(), x.y(), x.z()}); };
  json sings = json::array();
  for (const auto& frame : topology.singularities) {
    for (const Singularity& s : frame) {
      const Mat2& J = s.jacobian;
      sings.push_back({{"frame", s.frame},
                       {"t", s.t},
                       {"position", vec3(s.position)},
                       {"face", s.where.face},
                       {"index", s.index},
                       {"type", to_string(s.type)},
                       {"jacobian", json::array({json::array({J(0, 0), J(0, 1)}), json::array({J(1, 0), J(1, 1)})})}});
    }
  }
  json paths = json::array();
  for (const SingularityPath& p : topology.paths) {
    json points = json::array();
    for (const PathSample& s : p.points)
      points.push_back(json::array({s.position.x(), s.position.y(), s.position.z(), s.t}));
    paths.push_back({{"id", p.id},
                     {"type", to_string(p.type)},
                     {"birth", p.birth},
                     {"death", p.death},
                     {"points", std::move(points)}});
  }
  json bifs = json::array();
  for (const Bifurcation& b : topology.bifurcations)
    bifs.push_back({{"t", b.t},
                    {"position", vec3(b.position)},
                    {"kind", to_string(b.kind)},
                    {"paths", json::array({b.paths[0], b.paths[1]})}});
  return json{{"frames", static_cast<int>(topology.times.size())},
              {"times", topology.times},
              {"singularities", std::move(sings)},
              {"paths", std::move(paths)},
              {"bifurcations", std::move(bifs)},
              {"coherence", topology.coherence}};
}

}  // namespace tvf
