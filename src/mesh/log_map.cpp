#include "tvf/mesh/log_map.h"
#include "tvf/mesh/heat_distance.h"

#include "tvf/core/error.h"
#include "tvf/mesh/edge_paths.h"
#include "tvf/mesh/intrinsic_triangulation.h"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <array>
#include <cmath>
#include <limits>
#include <utility>

namespace tvf {

namespace {
using SpMat = Eigen::SparseMatrix<double>;
using SpCMat = Eigen::SparseMatrix<cplx>;

// compute_local's patch: the vertices within this edge-path distance of p, for a chart
// needed within `radius` (h the mean edge length). Measured (docs/benchmarks.md, issue 15,
// the local log map): with it the coordinates within `radius` are the whole mesh's to
// 0.4–1.3 % of the radius on the sphere, a torus and the bunny, the frames to 1e-7;
// 16h instead of 8h halves that and costs 30 % more.
double patch_radius(double radius, double h) { return 1.5 * radius + 8 * h; }

}  // namespace

// The scalar heat method's systems (shared by LogMap and HeatDistance).
struct HeatSolvers {
  Eigen::VectorXd mass;                              // lumped (barycentric) areas
  // The heat flows, the heat method's gradient and divergence and the Poisson solve run on
  // the intrinsic Delaunay triangulation (non-negative cotan weights on any mesh): its
  // faces' corners (the input's positions and normals where it is the input, else each
  // face laid out in the plane), and per intrinsic halfedge the cot of the opposite angle.
  std::vector<Face> faces;
  std::vector<std::array<Vec3, 3>> corners;
  std::vector<Vec3> normals;
  std::vector<double> cot;
  Eigen::SimplicialLDLT<SpMat> scalar_heat;          // M + t L
  Eigen::SimplicialLDLT<SpMat> poisson;              // L with vertex 0 pinned
  double h = 0;                                      // mean edge length
  std::vector<int> component;                        // per vertex: its connected component
  int num_components = 0;
  double far = 0;  // the distance given to vertices of other components than p's
};


// For LogMap::compute_local's patches: per intrinsic halfedge its twin (−1 on the
// boundary), its edge's (clamped) cotan weight and the transport T_tail → T_head.
struct LogMapPatchData {
  std::vector<int> twin;
  std::vector<double> weight;
  std::vector<cplx> transport;
  double t = 0;  // the diffusion time
};

struct LogMap::Solvers : HeatSolvers, LogMapPatchData {
  Eigen::SimplicialLDLT<SpCMat> vector_heat;         // M + t L∇
};

LogMap::~LogMap() = default;

namespace {

// Assembles and factors the scalar systems on the intrinsic Delaunay triangulation (and
// the vector heat system's triplets when ct is given); t = time_factor · h².
void build_heat(const TangentBundle& bundle, double time_factor, HeatSolvers* s,
                std::vector<Eigen::Triplet<cplx>>* ct, LogMapPatchData* ls = nullptr) {
  const Mesh& mesh = bundle.mesh();
  const int nv = mesh.num_vertices();
  s->h = mesh.mean_edge_length();
  const double t = time_factor * s->h * s->h;

  s->mass = Eigen::VectorXd::Zero(nv);
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int v : mesh.face(f)) s->mass[v] += mesh.face_area(f) / 3.0;

  const IntrinsicTriangulation idt(bundle);
  const int nf = idt.num_faces();
  s->faces.resize(static_cast<size_t>(nf));
  s->corners.resize(static_cast<size_t>(nf));
  s->normals.resize(static_cast<size_t>(nf));
  for (int f = 0; f < nf; ++f) {
    const Face& face = idt.face(f);
    s->faces[static_cast<size_t>(f)] = face;
    if (idt.is_input()) {
      for (int c = 0; c < 3; ++c)
        s->corners[static_cast<size_t>(f)][static_cast<size_t>(c)] = mesh.position(face[static_cast<size_t>(c)]);
      s->normals[static_cast<size_t>(f)] = bundle.face_normal(f);
    } else {
      s->corners[static_cast<size_t>(f)] = idt.layout(f);
      s->normals[static_cast<size_t>(f)] = Vec3::UnitZ();
    }
  }
  s->cot.resize(static_cast<size_t>(idt.num_halfedges()));
  for (int h = 0; h < idt.num_halfedges(); ++h) s->cot[static_cast<size_t>(h)] = idt.cot_opposite(h);
  if (ls) {
    ls->t = t;
    const auto nh = static_cast<size_t>(idt.num_halfedges());
    ls->twin.resize(nh);
    ls->weight.resize(nh);
    ls->transport.resize(nh);
    for (int h = 0; h < idt.num_halfedges(); ++h) {
      ls->twin[static_cast<size_t>(h)] = idt.twin(h);
      ls->weight[static_cast<size_t>(h)] = idt.edge_weight(h);
      ls->transport[static_cast<size_t>(h)] = idt.transport(h);
    }
  }

  std::vector<Eigen::Triplet<double>> rt, ht;
  if (ct) ct->reserve(static_cast<size_t>(nv + 4 * mesh.num_edges()));
  rt.reserve(static_cast<size_t>(nv + 4 * mesh.num_edges()));
  for (int v = 0; v < nv; ++v) {
    if (ct) ct->emplace_back(v, v, s->mass[v]);
    ht.emplace_back(v, v, s->mass[v]);
  }
  for (int h = 0; h < idt.num_halfedges(); ++h) {
    const int tw = idt.twin(h);
    if (tw >= 0 && tw < h) continue;  // each edge once
    const double w = idt.edge_weight(h);
    const int i = idt.tail(h), j = idt.head(h);
    const cplx rij = idt.transport(h);  // T_i → T_j
    // (L∇ z)_j ∋ −w·r_ij·z_i and (L∇ z)_i ∋ −w·conj(r_ij)·z_j: Hermitian.
    if (ct) {
      ct->emplace_back(i, i, t * w);
      ct->emplace_back(j, j, t * w);
      ct->emplace_back(j, i, -t * w * rij);
      ct->emplace_back(i, j, -t * w * std::conj(rij));
    }
    ht.emplace_back(i, i, t * w);
    ht.emplace_back(j, j, t * w);
    ht.emplace_back(i, j, -t * w);
    ht.emplace_back(j, i, -t * w);
    rt.emplace_back(i, i, w);
    rt.emplace_back(j, j, w);
    rt.emplace_back(i, j, -w);
    rt.emplace_back(j, i, -w);
  }
  // Pin one vertex per connected component so that the Neumann Laplacian becomes
  // definite; with a compatible right-hand side the solution is the one with φ = 0 there.
  s->component.assign(static_cast<size_t>(nv), -1);
  {
    std::vector<int> stack;
    for (int v0 = 0; v0 < nv; ++v0) {
      if (s->component[static_cast<size_t>(v0)] >= 0) continue;
      const int id = s->num_components++;
      s->component[static_cast<size_t>(v0)] = id;
      rt.emplace_back(v0, v0, 1.0);
      stack.assign(1, v0);
      while (!stack.empty()) {
        const int v = stack.back();
        stack.pop_back();
        for (int h : mesh.outgoing(v)) {
          for (int w : {mesh.head(h), mesh.tail(Mesh::prev(h))}) {
            if (s->component[static_cast<size_t>(w)] >= 0) continue;
            s->component[static_cast<size_t>(w)] = id;
            stack.push_back(w);
          }
        }
      }
    }
  }
  s->far = 1e3 * mesh.diameter();

  SpMat hs(nv, nv);
  hs.setFromTriplets(ht.begin(), ht.end());
  s->scalar_heat.compute(hs);
  TVF_CHECK(s->scalar_heat.info() == Eigen::Success, "scalar heat factorization failed");
  SpMat l(nv, nv);
  l.setFromTriplets(rt.begin(), rt.end());
  s->poisson.compute(l);
  TVF_CHECK(s->poisson.info() == Eigen::Success, "Poisson factorization failed");
}

}  // namespace

LogMap::LogMap(const TangentBundle& bundle, LogMapOptions options)
    : bundle_(bundle), options_(options) {
  if (bundle.is_flat()) return;
  const int nv = bundle.mesh().num_vertices();
  auto s = std::make_unique<Solvers>();
  std::vector<Eigen::Triplet<cplx>> ct;
  build_heat(bundle, options_.time_factor, s.get(), &ct, s.get());
  SpCMat a(nv, nv);
  a.setFromTriplets(ct.begin(), ct.end());
  s->vector_heat.compute(a);
  TVF_CHECK(s->vector_heat.info() == Eigen::Success, "vector heat factorization failed");
  solvers_ = std::move(s);
}

// The heat method's distance (Crane, Weischedel & Wardetzky 2013) from the heat u0 placed
// at the sources, up to a constant per component: heat flow, unit gradient field, Poisson.
namespace {
Eigen::VectorXd heat_distance(const HeatSolvers& s, const Eigen::VectorXd& u0) {
  const int nv = static_cast<int>(u0.size());
  // 2. Geodesic direction: the heat method's unit field X = −∇u/|∇u| per face, u the
  //    heat flowed from p (a delta with barycentric weights). Unlike a diffused ring of
  //    radial vectors, a point delta has no preferred direction, so X is unbiased.
  const Eigen::VectorXd u = s.scalar_heat.solve(u0);
  const int nf = static_cast<int>(s.faces.size());
  std::vector<Vec3> xf(static_cast<size_t>(nf));
  for (int f = 0; f < nf; ++f) {
    const Face& t = s.faces[static_cast<size_t>(f)];
    const auto& q = s.corners[static_cast<size_t>(f)];
    Vec3 grad = Vec3::Zero();
    for (int c = 0; c < 3; ++c)
      grad += u[t[static_cast<size_t>(c)]] *
              s.normals[static_cast<size_t>(f)].cross(q[static_cast<size_t>((c + 2) % 3)] - q[static_cast<size_t>((c + 1) % 3)]);
    const double g = grad.norm();
    xf[static_cast<size_t>(f)] = g > 0 ? Vec3(-grad / g) : Vec3::Zero();
  }

  // 3. Distance: L φ = −div X (φ grows away from p), as in the heat method.
  Eigen::VectorXd div = Eigen::VectorXd::Zero(nv);
  for (int f = 0; f < nf; ++f) {
    const Vec3& xw = xf[static_cast<size_t>(f)];
    const Face& t = s.faces[static_cast<size_t>(f)];
    const auto& q = s.corners[static_cast<size_t>(f)];
    for (int c = 0; c < 3; ++c) {
      const int h = 3 * f + c;                 // i → j
      const int hp = IntrinsicTriangulation::prev(h);  // k → i
      const int i = t[static_cast<size_t>(c)];
      const Vec3 e1 = q[static_cast<size_t>((c + 1) % 3)] - q[static_cast<size_t>(c)];
      const Vec3 e2 = q[static_cast<size_t>((c + 2) % 3)] - q[static_cast<size_t>(c)];
      // cot of the angle opposite e1 (at k) and opposite e2 (at j).
      div[i] += 0.5 * (s.cot[static_cast<size_t>(h)] * e1.dot(xw) +
                       s.cot[static_cast<size_t>(hp)] * e2.dot(xw));
    }
  }
  // Make the right-hand side compatible with the Neumann Laplacian (zero sum), spreading
  // the boundary flux by area.
  // (per component: each has its own Neumann problem).
  {
    std::vector<double> sum(static_cast<size_t>(s.num_components), 0.0), area(sum.size(), 0.0);
    for (int v = 0; v < nv; ++v) {
      sum[static_cast<size_t>(s.component[static_cast<size_t>(v)])] += div[v];
      area[static_cast<size_t>(s.component[static_cast<size_t>(v)])] += s.mass[v];
    }
    for (int v = 0; v < nv; ++v) {
      const auto c = static_cast<size_t>(s.component[static_cast<size_t>(v)]);
      div[v] -= sum[c] / area[c] * s.mass[v];
    }
  }
  return s.poisson.solve(-div);
}
}  // namespace

HeatDistance::HeatDistance(const TangentBundle& bundle, double time_factor) : bundle_(bundle) {
  if (bundle.is_flat()) return;
  auto s = std::make_unique<HeatSolvers>();
  build_heat(bundle, time_factor, s.get(), nullptr);
  solvers_ = std::move(s);
}

HeatDistance::~HeatDistance() = default;

std::vector<double> HeatDistance::distance(std::span<const SurfacePoint> sources) const {
  const Mesh& mesh = bundle_.mesh();
  const int nv = mesh.num_vertices();
  TVF_CHECK(!sources.empty(), "geodesic distance from no source");
  std::vector<double> out(static_cast<size_t>(nv), 0.0);
  auto point_of = [&](const SurfacePoint& p) {
    const Face& f = mesh.face(p.face);
    return Vec3(p.bary[0] * mesh.position(f[0]) + p.bary[1] * mesh.position(f[1]) + p.bary[2] * mesh.position(f[2]));
  };
  if (!solvers_) {
    for (int v = 0; v < nv; ++v) {
      double d = std::numeric_limits<double>::infinity();
      for (const SurfacePoint& p : sources) d = std::min(d, (mesh.position(v) - point_of(p)).norm());
      out[static_cast<size_t>(v)] = d;
    }
    return out;
  }
  const HeatSolvers& s = *solvers_;
  Eigen::VectorXd u0 = Eigen::VectorXd::Zero(nv);
  for (const SurfacePoint& p : sources) {
    const Face& f = mesh.face(p.face);
    for (int c = 0; c < 3; ++c) u0[f[static_cast<size_t>(c)]] += p.bary[c];
  }
  const Eigen::VectorXd phi = heat_distance(s, u0);
  // The constant of each component: fitted, as in compute(), on the vertices around its
  // sources, where the distance to the nearest source is the chord to O(h³).
  std::vector<double> offset(static_cast<size_t>(s.num_components), 0.0);
  std::vector<int> count(offset.size(), 0);
  for (const SurfacePoint& p : sources) {
    const Vec3 x = point_of(p);
    auto fit = [&](int v) {
      double chord = std::numeric_limits<double>::infinity();
      for (const SurfacePoint& q : sources) chord = std::min(chord, (mesh.position(v) - point_of(q)).norm());
      if (chord > 2 * (mesh.position(v) - x).norm() + 1e-300) return;  // nearer another source's tip
      const auto c = static_cast<size_t>(s.component[static_cast<size_t>(v)]);
      offset[c] += phi[v] - chord;
      ++count[c];
    };
    for (int c : mesh.face(p.face)) {
      fit(c);
      for (int h : mesh.outgoing(c)) fit(mesh.head(h));
    }
  }
  for (int v = 0; v < nv; ++v) {
    const auto c = static_cast<size_t>(s.component[static_cast<size_t>(v)]);
    out[static_cast<size_t>(v)] =
        count[c] > 0 ? std::max(0.0, phi[v] - offset[c] / count[c]) : std::numeric_limits<double>::infinity();
  }
  return out;
}

namespace {

// Steps 4–5 of the log map, shared by compute (the whole mesh) and compute_local (a
// patch): from the distance φ and the transported frame y on the vertices `verts` (their
// local indices; local[v] the index of mesh vertex v, −1 where it is not among them), the
// chart's coordinates and frames there. in_faces: the input faces with all three corners
// among them; reached: per local index, whether it is in p's connected component; far:
// the distance given to the others.
void finish_chart(const TangentBundle& bundle, const SurfacePoint& p, const Vec3& x, double h,
                  const std::vector<int>& verts, const std::vector<int>& local, const std::vector<int>& in_faces,
                  const std::vector<char>& reached, double far, const Eigen::VectorXd& phi,
                  const Eigen::VectorXcd& y, LocalChart& chart) {
  const Mesh& mesh = bundle.mesh();
  const int n = static_cast<int>(verts.size());
  const Face& pf = mesh.face(p.face);
  auto at = [&](int v) { return local[static_cast<size_t>(v)]; };
  // Geodesic direction at the vertices: ∇φ (the gradient field closest to X, smoother
  // than X itself), area-weighted over the faces around each vertex and carried into T_v.
  Eigen::VectorXcd radial = Eigen::VectorXcd::Zero(n);
  for (int f : in_faces) {
    const Face& t = mesh.face(f);
    const Vec3& nf = bundle.face_normal(f);
    Vec3 grad = Vec3::Zero();
    for (int c = 0; c < 3; ++c) {
      const Vec3 e = mesh.position(t[static_cast<size_t>((c + 2) % 3)]) -
                     mesh.position(t[static_cast<size_t>((c + 1) % 3)]);
      grad += phi[at(t[static_cast<size_t>(c)])] * nf.cross(e);
    }
    const cplx g = normalized(bundle.world_to_face(f, grad)) * mesh.face_area(f);
    for (int c = 0; c < 3; ++c)
      radial[at(t[static_cast<size_t>(c)])] += std::conj(bundle.corner_to_face(3 * f + c)) * g;
  }

  // φ is known up to a constant. Its value at p itself is too high (the heat method
  // rounds the distance cone's tip over about an edge length), so the constant is fitted
  // instead on the vertices around p, where the geodesic distance is the chord to O(h³).
  double offset = 0;
  int count = 0;
  auto fit = [&](int v) {
    offset += phi[at(v)] - (mesh.position(v) - x).norm();
    ++count;
  };
  for (int c : pf) {
    fit(c);
    for (int hh : mesh.outgoing(c)) fit(mesh.head(hh));
  }
  offset /= count;

  for (int i = 0; i < n; ++i) {
    const auto v = static_cast<size_t>(verts[static_cast<size_t>(i)]);
    const cplx fr = normalized(y[i]);
    const cplx dir = normalized(radial[i] * std::conj(fr));
    // Another component is out of reach: far beyond any element's falloff.
    const double dist = reached[static_cast<size_t>(i)] ? std::max(0.0, phi[i] - offset) : far;
    chart.coords[v] = dist * dir;
    chart.frame[v] = fr;
  }
  // Near p the heat gradient's direction error is O(h / r), while the projection onto p's
  // tangent plane agrees with the log map to second order in r. Use the projection within
  // 3h and blend to the heat-method coordinates by 6h (they agree there to ~1 %, so the
  // blend leaves no seam).
  const double r_in = 3 * h, r_out = 6 * h;
  for (int i = 0; i < n; ++i) {
    const auto v = static_cast<size_t>(verts[static_cast<size_t>(i)]);
    const cplx heat = chart.coords[v];
    const double dist = std::abs(heat);
    if (dist >= r_out) continue;
    const cplx chord = bundle.world_to_face(p.face, mesh.position(static_cast<int>(v)) - x);
    const double w = dist <= r_in ? 0.0 : (dist - r_in) / (r_out - r_in);
    const double blend = w * w * (3 - 2 * w);  // smoothstep
    chart.coords[v] = (1 - blend) * chord + blend * heat;
  }
}

}  // namespace

void LogMap::compute(const SurfacePoint& p, LocalChart& chart) const {
  const Mesh& mesh = bundle_.mesh();
  const int nv = mesh.num_vertices();
  chart.coords.resize(static_cast<size_t>(nv));
  chart.frame.resize(static_cast<size_t>(nv));
  const Face& pf = mesh.face(p.face);
  const Vec3 x = p.bary[0] * mesh.position(pf[0]) + p.bary[1] * mesh.position(pf[1]) +
                 p.bary[2] * mesh.position(pf[2]);

  if (!solvers_) {
    // Flat: the plane's own coordinates; the frame at p is the global frame.
    for (int v = 0; v < nv; ++v) {
      const Vec3 d = mesh.position(v) - x;
      chart.coords[static_cast<size_t>(v)] = cplx(d.x(), d.y());
      chart.frame[static_cast<size_t>(v)] = cplx(1, 0);
    }
    return;
  }
  const Solvers& s = *solvers_;

  // 1. Parallel transport of p's frame: heat-flow the face frame's e1, placed on the
  //    face's corners with barycentric weights.
  Eigen::VectorXcd y0 = Eigen::VectorXcd::Zero(nv);
  for (int c = 0; c < 3; ++c) {
    const int h = 3 * p.face + c;
    y0[pf[static_cast<size_t>(c)]] += p.bary[c] * std::conj(bundle_.corner_to_face(h));
  }
  const Eigen::VectorXcd y = s.vector_heat.solve(y0);

  // 2–3. Geodesic direction and distance by the heat method from a point delta at p
  //      (barycentric weights): unlike a diffused ring of radial vectors, a point delta
  //      has no preferred direction, so the direction field is unbiased.
  Eigen::VectorXd u0 = Eigen::VectorXd::Zero(nv);
  for (int c = 0; c < 3; ++c) u0[pf[static_cast<size_t>(c)]] += p.bary[c];
  const Eigen::VectorXd phi = heat_distance(s, u0);

  std::vector<int> all(static_cast<size_t>(nv));
  for (int v = 0; v < nv; ++v) all[static_cast<size_t>(v)] = v;
  std::vector<int> faces(static_cast<size_t>(mesh.num_faces()));
  for (int f = 0; f < mesh.num_faces(); ++f) faces[static_cast<size_t>(f)] = f;
  std::vector<char> reached(static_cast<size_t>(nv));
  for (int v = 0; v < nv; ++v)
    reached[static_cast<size_t>(v)] = s.component[static_cast<size_t>(v)] == s.component[static_cast<size_t>(pf[0])];
  finish_chart(bundle_, p, x, s.h, all, all, faces, reached, s.far, phi, y, chart);
}

void LogMap::compute_local(const SurfacePoint& p, double radius, LocalChart& chart) const {
  if (!solvers_ || !(radius < std::numeric_limits<double>::infinity())) {
    compute(p, chart);
    return;
  }
  const Solvers& s = *solvers_;
  const Mesh& mesh = bundle_.mesh();
  const int nv = mesh.num_vertices();
  const Face& pf = mesh.face(p.face);
  const Vec3 x = p.bary[0] * mesh.position(pf[0]) + p.bary[1] * mesh.position(pf[1]) +
                 p.bary[2] * mesh.position(pf[2]);

  // The patch: the vertices within edge-path distance R of p (Dijkstra from p's corners).
  // Edge paths are longer than geodesics, so it holds every vertex geodesically within R
  // / (their ratio, 1.0–1.2 on reasonable meshes) of p.
  const double reach = patch_radius(radius, s.h);
  std::vector<int> in_ball;
  const std::array<EdgePathSeed, 3> seeds{{{pf[0], (mesh.position(pf[0]) - x).norm()},
                                           {pf[1], (mesh.position(pf[1]) - x).norm()},
                                           {pf[2], (mesh.position(pf[2]) - x).norm()}}};
  const size_t limit = static_cast<size_t>(nv) / 4;
  edge_path_distances(mesh, seeds, reach, [&](int v, double) {
    in_ball.push_back(v);
    return in_ball.size() <= limit;
  });
  if (in_ball.size() > limit) {
    // The patch would hold a good part of the mesh: the whole mesh's solves are cheaper.
    compute(p, chart);
    return;
  }
  std::vector<char> ball(static_cast<size_t>(nv), 0);
  for (int v : in_ball) ball[static_cast<size_t>(v)] = 1;

  // The intrinsic faces with all corners in the ball, and the vertices they use (local
  // indices in order of first use).
  std::vector<int> local(static_cast<size_t>(nv), -1), verts;
  std::vector<int> ifaces;
  HeatSolvers ls;
  const int nif = static_cast<int>(s.faces.size());
  std::vector<char> face_in(static_cast<size_t>(nif), 0);
  for (int f = 0; f < nif; ++f) {
    const Face& t = s.faces[static_cast<size_t>(f)];
    if (!ball[static_cast<size_t>(t[0])] || !ball[static_cast<size_t>(t[1])] || !ball[static_cast<size_t>(t[2])]) continue;
    face_in[static_cast<size_t>(f)] = 1;
    ifaces.push_back(f);
    Face lf;
    for (int c = 0; c < 3; ++c) {
      int& l = local[static_cast<size_t>(t[static_cast<size_t>(c)])];
      if (l < 0) {
        l = static_cast<int>(verts.size());
        verts.push_back(t[static_cast<size_t>(c)]);
      }
      lf[static_cast<size_t>(c)] = l;
    }
    ls.faces.push_back(lf);
    ls.corners.push_back(s.corners[static_cast<size_t>(f)]);
    ls.normals.push_back(s.normals[static_cast<size_t>(f)]);
    for (int c = 0; c < 3; ++c) ls.cot.push_back(s.cot[static_cast<size_t>(3 * f + c)]);
  }
  for (int c : pf)
    for (int h : mesh.outgoing(c))
      if (local[static_cast<size_t>(mesh.head(h))] < 0 || local[static_cast<size_t>(c)] < 0) {
        compute(p, chart);  // p's neighbourhood is not covered (a patch too small to matter)
        return;
      }
  const int n = static_cast<int>(verts.size());
  ls.h = s.h;
  ls.far = s.far;
  ls.mass.resize(n);
  for (int i = 0; i < n; ++i) ls.mass[i] = s.mass[verts[static_cast<size_t>(i)]];

  // The patch's systems, assembled from its own faces (Neumann boundary): an edge inside
  // has the whole mesh's weight and transport, an edge on the patch's boundary the half
  // of its one face here.
  const double t = s.t;
  std::vector<Eigen::Triplet<cplx>> ct;
  std::vector<Eigen::Triplet<double>> ht, rt;
  for (int i = 0; i < n; ++i) {
    ct.emplace_back(i, i, ls.mass[i]);
    ht.emplace_back(i, i, ls.mass[i]);
  }
  std::vector<int> parent(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) parent[static_cast<size_t>(i)] = i;
  auto root = [&](int a) {
    while (parent[static_cast<size_t>(a)] != a) a = parent[static_cast<size_t>(a)] = parent[static_cast<size_t>(parent[static_cast<size_t>(a)])];
    return a;
  };
  for (int f : ifaces) {
    for (int c = 0; c < 3; ++c) {
      const int h = 3 * f + c;
      const int tw = s.twin[static_cast<size_t>(h)];
      const bool inner = tw >= 0 && face_in[static_cast<size_t>(tw / 3)];
      if (inner && tw < h) continue;  // each edge once
      const double w = inner || tw < 0 ? s.weight[static_cast<size_t>(h)] : std::max(0.0, 0.5 * s.cot[static_cast<size_t>(h)]);
      const int i = local[static_cast<size_t>(s.faces[static_cast<size_t>(f)][static_cast<size_t>(c)])];
      const int j = local[static_cast<size_t>(s.faces[static_cast<size_t>(f)][static_cast<size_t>((c + 1) % 3)])];
      const cplx rij = s.transport[static_cast<size_t>(h)];
      ct.emplace_back(i, i, t * w);
      ct.emplace_back(j, j, t * w);
      ct.emplace_back(j, i, -t * w * rij);
      ct.emplace_back(i, j, -t * w * std::conj(rij));
      ht.emplace_back(i, i, t * w);
      ht.emplace_back(j, j, t * w);
      ht.emplace_back(i, j, -t * w);
      ht.emplace_back(j, i, -t * w);
      rt.emplace_back(i, i, w);
      rt.emplace_back(j, j, w);
      rt.emplace_back(i, j, -w);
      rt.emplace_back(j, i, -w);
      parent[static_cast<size_t>(root(i))] = root(j);
    }
  }
  // Connected components of the patch (through its faces), one pinned vertex each.
  ls.component.assign(static_cast<size_t>(n), -1);
  {
    std::vector<int> id_of(static_cast<size_t>(n), -1);
    for (int i = 0; i < n; ++i) {
      const int r = root(i);
      if (id_of[static_cast<size_t>(r)] < 0) {
        id_of[static_cast<size_t>(r)] = ls.num_components++;
        rt.emplace_back(i, i, 1.0);
      }
      ls.component[static_cast<size_t>(i)] = id_of[static_cast<size_t>(r)];
    }
  }
  SpCMat a(n, n);
  a.setFromTriplets(ct.begin(), ct.end());
  Eigen::SimplicialLDLT<SpCMat> vector_heat(a);
  TVF_CHECK(vector_heat.info() == Eigen::Success, "vector heat factorization failed");
  SpMat hs(n, n);
  hs.setFromTriplets(ht.begin(), ht.end());
  ls.scalar_heat.compute(hs);
  TVF_CHECK(ls.scalar_heat.info() == Eigen::Success, "scalar heat factorization failed");
  SpMat l(n, n);
  l.setFromTriplets(rt.begin(), rt.end());
  ls.poisson.compute(l);
  TVF_CHECK(ls.poisson.info() == Eigen::Success, "Poisson factorization failed");

  Eigen::VectorXcd y0 = Eigen::VectorXcd::Zero(n);
  Eigen::VectorXd u0 = Eigen::VectorXd::Zero(n);
  for (int c = 0; c < 3; ++c) {
    const int i = local[static_cast<size_t>(pf[static_cast<size_t>(c)])];
    y0[i] += p.bary[c] * std::conj(bundle_.corner_to_face(3 * p.face + c));
    u0[i] += p.bary[c];
  }
  const Eigen::VectorXcd y = vector_heat.solve(y0);
  const Eigen::VectorXd phi = heat_distance(ls, u0);

  std::vector<int> faces;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Face& tf = mesh.face(f);
    if (local[static_cast<size_t>(tf[0])] >= 0 && local[static_cast<size_t>(tf[1])] >= 0 && local[static_cast<size_t>(tf[2])] >= 0)
      faces.push_back(f);
  }
  std::vector<char> reached(static_cast<size_t>(n));
  const int pc = ls.component[static_cast<size_t>(local[static_cast<size_t>(pf[0])])];
  for (int i = 0; i < n; ++i) reached[static_cast<size_t>(i)] = ls.component[static_cast<size_t>(i)] == pc;
  chart.coords.assign(static_cast<size_t>(nv), cplx(std::numeric_limits<double>::infinity(), 0));
  chart.frame.assign(static_cast<size_t>(nv), cplx(1, 0));
  finish_chart(bundle_, p, x, s.h, verts, local, faces, reached, s.far, phi, y, chart);
}

}  // namespace tvf
