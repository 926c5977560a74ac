#include "tvf/analysis/singularities.h"

#include "support/test_meshes.h"
#include "tvf/core/error.h"
#include "tvf/mesh/grid.h"

#include <gtest/gtest.h>

#include <Eigen/LU>

#include <cmath>
#include <numeric>
#include <random>
#include <string>
#include <vector>

namespace tvf {
namespace {

struct LinearCase {
  std::string name;
  Mat2 J;
  SingularityType type;
};

Mat2 mat(double a, double b, double c, double d) {
  Mat2 m;
  m << a, b, c, d;
  return m;
}

// The seven kinds of linear singularity, each with a generic (non-symmetric) Jacobian.
std::vector<LinearCase> linear_cases() {
  return {
      {"source", mat(1.3, 0.2, 0.1, 0.9), SingularityType::source},
      {"sink", mat(-1.3, 0.2, 0.1, -0.9), SingularityType::sink},
      {"saddle", mat(1.0, 0.3, 0.2, -0.8), SingularityType::saddle},
      {"ccw_center", mat(0.0, -0.7, 1.1, 0.0), SingularityType::center},
      {"cw_center", mat(0.0, 0.9, -0.6, 0.0), SingularityType::center},
      {"repelling_focus", mat(0.5, -1.0, 1.2, 0.4), SingularityType::repelling_focus},
      {"attracting_focus", mat(-0.5, -1.0, 1.2, -0.4), SingularityType::attracting_focus},
  };
}

// Vertex values of the linear field z = J·(x − p) on a planar mesh.
std::vector<cplx> linear_field(const TangentBundle& bundle, const Mat2& J, const Vec2& p) {
  const Mesh& mesh = bundle.mesh();
  std::vector<cplx> z(static_cast<size_t>(mesh.num_vertices()));
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Vec2 d = mesh.position(v).head<2>() - p;
    const Vec2 w = J * d;
    z[static_cast<size_t>(v)] = bundle.world_to_vertex(v, Vec3(w.x(), w.y(), 0.0));
  }
  return z;
}

int index_sum(const std::vector<Singularity>& s) {
  int sum = 0;
  for (const auto& x : s) sum += x.index;
  return sum;
}

int expected_index(const Mat2& J) { return J.determinant() > 0 ? 1 : -1; }

void expect_inside_face(const Singularity& s) {
  EXPECT_GE(s.where.bary.minCoeff(), 0.0);
  EXPECT_LE(s.where.bary.maxCoeff(), 1.0);
  EXPECT_NEAR(s.where.bary.sum(), 1.0, 1e-12);
}

// A dyadic grid: every vertex coordinate and every edge midpoint is exact in binary.
const Mesh& dyadic_grid() {
  static const Mesh m = make_grid(GridSpec{17, 17, {-1.0, -1.0}, {1.0, 1.0}});
  return m;
}

TEST(SingularityTypes, NamesAreExact) {
  EXPECT_STREQ(to_string(SingularityType::source), "source");
  EXPECT_STREQ(to_string(SingularityType::sink), "sink");
  EXPECT_STREQ(to_string(SingularityType::saddle), "saddle");
  EXPECT_STREQ(to_string(SingularityType::center), "center");
  EXPECT_STREQ(to_string(SingularityType::repelling_focus), "repelling_focus");
  EXPECT_STREQ(to_string(SingularityType::attracting_focus), "attracting_focus");
}

TEST(SingularityClassify, LinearCasesAndThresholds) {
  for (const auto& c : linear_cases()) EXPECT_EQ(classify_jacobian(c.J), c.type) << c.name;
  // Center: |Re λ| ≤ 0.1·|Im λ|.
  EXPECT_EQ(classify_jacobian(mat(0.09, -1, 1, 0.09)), SingularityType::center);
  EXPECT_EQ(classify_jacobian(mat(-0.09, -1, 1, -0.09)), SingularityType::center);
  EXPECT_EQ(classify_jacobian(mat(0.11, -1, 1, 0.11)), SingularityType::repelling_focus);
  EXPECT_EQ(classify_jacobian(mat(-0.11, -1, 1, -0.11)), SingularityType::attracting_focus);
  // Nearly real eigenvalues: |Im λ| ≤ 0.1·|Re λ| counts as real.
  EXPECT_EQ(classify_jacobian(mat(1, -0.09, 0.09, 1)), SingularityType::source);
  EXPECT_EQ(classify_jacobian(mat(-1, -0.09, 0.09, -1)), SingularityType::sink);
  EXPECT_EQ(classify_jacobian(mat(1, -0.11, 0.11, 1)), SingularityType::repelling_focus);
  // Repeated real eigenvalues, a shear, and a saddle with tiny determinant.
  EXPECT_EQ(classify_jacobian(mat(2, 1, 0, 2)), SingularityType::source);
  EXPECT_EQ(classify_jacobian(mat(-2, 1, 0, -2)), SingularityType::sink);
  EXPECT_EQ(classify_jacobian(mat(1e-9, 0, 0, -1e-9)), SingularityType::saddle);
}

TEST(SingularityLinear, OneSingularityAtTheZeroWithItsJacobian) {
  for (const GridSpec& spec : {GridSpec{17, 17, {-1.0, -1.0}, {1.0, 1.0}},
                               GridSpec{13, 9, {-0.7, -0.4}, {1.3, 0.9}},
                               GridSpec{21, 15, {-300.0, -100.0}, {500.0, 400.0}}}) {
    const Mesh grid = make_grid(spec);
    const TangentBundle bundle(grid);
    ASSERT_TRUE(bundle.is_flat());
    const Vec2 lo = spec.min, hi = spec.max;
    for (const Vec2& rel : {Vec2(0.4123, 0.5871), Vec2(0.1337, 0.8219), Vec2(0.7771, 0.2903)}) {
      const Vec2 p = lo + rel.cwiseProduct(hi - lo);
      const double scale = (hi - lo).norm();
      for (const auto& c : linear_cases()) {
        SCOPED_TRACE(c.name + " at " + std::to_string(p.x()) + ", " + std::to_string(p.y()));
        const auto s = find_singularities(bundle, linear_field(bundle, c.J, p));
        ASSERT_EQ(s.size(), 1u);
        EXPECT_EQ(s[0].index, expected_index(c.J));
        EXPECT_EQ(s[0].type, c.type);
        EXPECT_NEAR(s[0].position.x(), p.x(), 1e-12 * scale);
        EXPECT_NEAR(s[0].position.y(), p.y(), 1e-12 * scale);
        EXPECT_EQ(s[0].position.z(), 0.0);
        EXPECT_LT((s[0].jacobian - c.J).cwiseAbs().maxCoeff(), 1e-9);
        expect_inside_face(s[0]);
        EXPECT_EQ(s[0].frame, 0);
      }
    }
  }
}

TEST(SingularityDegenerate, ZeroOnEveryVertexIsFoundOnce) {
  const Mesh& grid = dyadic_grid();
  const TangentBundle bundle(grid);
  auto cases = linear_cases();
  // The perturbation δ·(1, 0) moves the zero along −J⁻¹(1, 0): for this sink exactly along
  // the grid diagonal, for the identity exactly along a horizontal edge; the second-order
  // term i·δ' must decide.
  cases.push_back({"diagonal_sink", mat(-2, 1, 1, -1), SingularityType::sink});  // J·(1,1) = −(1,0)
  cases.push_back({"identity_source", Mat2::Identity(), SingularityType::source});
  cases.push_back({"rotation_center", mat(0, -1, 1, 0), SingularityType::center});
  int boundary_found = 0;
  for (int v = 0; v < grid.num_vertices(); ++v) {
    const Vec2 p = grid.position(v).head<2>();
    for (const auto& c : cases) {
      SCOPED_TRACE(c.name + " at vertex " + std::to_string(v));
      const auto values = linear_field(bundle, c.J, p);
      ASSERT_EQ(values[static_cast<size_t>(v)], cplx(0, 0));
      const auto s = find_singularities(bundle, values);
      if (grid.is_boundary_vertex(v)) {
        // On the boundary the perturbation may move the zero out of the domain.
        ASSERT_LE(s.size(), 1u);
        boundary_found += static_cast<int>(s.size());
        continue;
      }
      ASSERT_EQ(s.size(), 1u);
      EXPECT_EQ(s[0].index, expected_index(c.J));
      EXPECT_EQ(s[0].type, c.type);
      EXPECT_LT((s[0].position - grid.position(v)).norm(), 1e-12);
      EXPECT_LT((s[0].jacobian - c.J).cwiseAbs().maxCoeff(), 1e-9);
      expect_inside_face(s[0]);
      const Face& f = grid.face(s[0].where.face);
      EXPECT_TRUE(f[0] == v || f[1] == v || f[2] == v);
    }
  }
  EXPECT_GT(boundary_found, 0);
}

TEST(SingularityDegenerate, ZeroOnEveryEdgeIsFoundOnce) {
  const Mesh& grid = dyadic_grid();
  const TangentBundle bundle(grid);
  int kinds[3] = {0, 0, 0};  // horizontal, vertical, diagonal interior edges seen
  for (int e = 0; e < grid.num_edges(); ++e) {
    const auto [a, b] = grid.edge(e);
    const Vec2 xa = grid.position(a).head<2>();
    const Vec2 xb = grid.position(b).head<2>();
    const Vec2 p = 0.5 * (xa + xb);
    ASSERT_EQ(xa - p, p - xb);  // exact midpoint
    const bool boundary = std::abs(p.x()) == 1.0 || std::abs(p.y()) == 1.0;
    if (!boundary) ++kinds[xa.y() == xb.y() ? 0 : xa.x() == xb.x() ? 1 : 2];
    for (const auto& c : linear_cases()) {
      SCOPED_TRACE(c.name + " on edge " + std::to_string(a) + "-" + std::to_string(b));
      const auto s = find_singularities(bundle, linear_field(bundle, c.J, p));
      if (boundary) {
        ASSERT_LE(s.size(), 1u);
        continue;
      }
      ASSERT_EQ(s.size(), 1u);
      EXPECT_EQ(s[0].index, expected_index(c.J));
      EXPECT_EQ(s[0].type, c.type);
      EXPECT_LT((s[0].position.head<2>() - p).norm(), 1e-12);
      EXPECT_LT((s[0].jacobian - c.J).cwiseAbs().maxCoeff(), 1e-9);
      expect_inside_face(s[0]);
      const Face& f = grid.face(s[0].where.face);
      const auto has = [&](int v) { return f[0] == v || f[1] == v || f[2] == v; };
      EXPECT_TRUE(has(a) && has(b));
    }
  }
  EXPECT_GT(kinds[0], 100);
  EXPECT_GT(kinds[1], 100);
  EXPECT_GT(kinds[2], 100);
}

// Grid vertex indices of the boundary loop, counter-clockwise (grid.h: v = iy·nx + ix).
std::vector<int> grid_boundary_loop(int nx, int ny) {
  std::vector<int> loop;
  for (int ix = 0; ix < nx - 1; ++ix) loop.push_back(ix);
  for (int iy = 0; iy < ny - 1; ++iy) loop.push_back(iy * nx + nx - 1);
  for (int ix = nx - 1; ix > 0; --ix) loop.push_back((ny - 1) * nx + ix);
  for (int iy = ny - 1; iy > 0; --iy) loop.push_back(iy * nx);
  return loop;
}

// Interior values drawn from a small set of Gaussian integers, so exact zeros, exactly
// opposite neighbours and collinear triples are everywhere; the boundary carries a smooth
// field of known winding. The index sum must equal the boundary's winding number, which is
// computed here independently from consecutive boundary angles.
TEST(SingularityDegenerate, IntegerFieldsKeepTheBoundaryWinding) {
  const int nx = 11, ny = 9;
  const Mesh grid = make_grid(GridSpec{nx, ny, {-1.0, -1.0}, {1.0, 1.0}});
  const TangentBundle bundle(grid);
  const std::vector<int> loop = grid_boundary_loop(nx, ny);
  const cplx choices[] = {0, 0, 0, 1, -1, {0, 1}, {0, -1}, {1, 1}, {-1, -1}, {1, -1}, 2, -2};
  const cplx p(0.1234, -0.0567);
  const std::vector<std::pair<std::string, cplx (*)(cplx)>> boundary_fields = {
      {"z", [](cplx z) { return z; }},
      {"conj z", [](cplx z) { return std::conj(z); }},
      {"z^2", [](cplx z) { return z * z; }},
      {"conj z^3", [](cplx z) { return std::conj(z * z * z); }},
      {"1", [](cplx) { return cplx(1, 0.5); }},
  };
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(std::size(choices)) - 1);
  for (const auto& [name, g] : boundary_fields) {
    std::vector<cplx> z(static_cast<size_t>(grid.num_vertices()));
    for (int v : loop) {
      const Vec3& x = grid.position(v);
      z[static_cast<size_t>(v)] = g(cplx(x.x(), x.y()) - p);
    }
    double turn = 0;
    for (size_t k = 0; k < loop.size(); ++k) {
      const cplx a = z[static_cast<size_t>(loop[k])];
      const cplx b = z[static_cast<size_t>(loop[(k + 1) % loop.size()])];
      ASSERT_NE(a, cplx(0, 0));
      const double step = std::arg(b / a);
      ASSERT_LT(std::abs(step), 3.0);  // well away from the branch cut
      turn += step;
    }
    const int winding = static_cast<int>(std::lround(turn / (2 * kPi)));
    for (int trial = 0; trial < 40; ++trial) {
      SCOPED_TRACE(name + ", trial " + std::to_string(trial));
      for (int v = 0; v < grid.num_vertices(); ++v)
        if (!grid.is_boundary_vertex(v)) z[static_cast<size_t>(v)] = choices[pick(rng)];
      const auto s = find_singularities(bundle, z);
      EXPECT_EQ(index_sum(s), winding);
      const auto idx = face_indices(bundle, z);
      EXPECT_EQ(std::accumulate(idx.begin(), idx.end(), 0), winding);
      for (const auto& x : s) {
        expect_inside_face(x);
        EXPECT_TRUE(x.index == 1 || x.index == -1);
        EXPECT_TRUE(std::isfinite(x.position.x()) && std::isfinite(x.position.y()));
      }
    }
  }
}

// --- Closed meshes: Poincaré–Hopf -------------------------------------------------------

std::vector<cplx> random_values(const Mesh& mesh, std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<cplx> z(static_cast<size_t>(mesh.num_vertices()));
  for (auto& x : z) x = {n(rng), n(rng)};
  return z;
}

// A smooth field: a constant plus a few Gaussian-weighted sources, sinks, vortices and
// spirals around random points, projected onto the tangent planes.
std::vector<cplx> smooth_values(const TangentBundle& bundle, std::mt19937& rng) {
  const Mesh& mesh = bundle.mesh();
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Vec3 constant = 0.3 * Vec3(n(rng), n(rng), n(rng));
  struct Element {
    Vec3 c;
    double angle, radius, strength;
  };
  std::vector<Element> elements;
  const int count = 1 + static_cast<int>(u(rng) * 5);
  for (int k = 0; k < count; ++k) {
    const Vec3 c = mesh.position(static_cast<int>(u(rng) * mesh.num_vertices()));
    elements.push_back({c, 2 * kPi * u(rng), 0.3 + 0.7 * u(rng), 0.5 + u(rng)});
  }
  std::vector<cplx> z(static_cast<size_t>(mesh.num_vertices()));
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Vec3& x = mesh.position(v);
    const Vec3& nv = bundle.vertex_normal(v);
    Vec3 w = constant;
    for (const auto& e : elements) {
      const Vec3 d = x - e.c;
      const double g = e.strength * std::exp(-d.squaredNorm() / (e.radius * e.radius));
      w += g * (std::cos(e.angle) * d + std::sin(e.angle) * nv.cross(d));
    }
    z[static_cast<size_t>(v)] = bundle.world_to_vertex(v, w);
  }
  return z;
}

TEST(SingularityPoincareHopf, FaceCurvatureSumsToTwoPiChi) {
  for (const auto& [name, mesh] : test::all_meshes()) {
    const TangentBundle bundle(*mesh);
    double sum = 0;
    for (int f = 0; f < mesh->num_faces(); ++f) {
      const double omega = face_curvature(bundle, f);
      sum += omega;
      // Ω_f is the holonomy of the stored transports around f (mod 2π) ...
      cplx hol(1, 0);
      for (int c = 0; c < 3; ++c) hol *= bundle.transport(3 * f + c);
      EXPECT_NEAR(std::remainder(std::arg(hol) - omega, 2 * kPi), 0.0, 1e-12) << name << " " << f;
      // ... and equals the rescaled angle excess Σ s_v·α − π.
      double excess = -kPi;
      for (int c = 0; c < 3; ++c) {
        const int v = mesh->face(f)[static_cast<size_t>(c)];
        const double s = mesh->is_boundary_vertex(v) ? 1.0 : 2 * kPi / bundle.angle_sum(v);
        excess += s * mesh->corner_angle(3 * f + c);
      }
      EXPECT_NEAR(omega, excess, 1e-12) << name << " " << f;
    }
    if (mesh->is_closed()) {
      EXPECT_NEAR(sum, 2 * kPi * mesh->euler_characteristic(), 1e-9) << name;
    }
    if (bundle.is_flat()) {
      for (int f = 0; f < mesh->num_faces(); ++f)
        EXPECT_NEAR(face_curvature(bundle, f), 0.0, 1e-14) << name;
    }
  }
}

TEST(SingularityPoincareHopf, RandomFieldsOnClosedMeshes) {
  for (const auto& [name, mesh] : test::closed_meshes()) {
    const TangentBundle bundle(*mesh);
    const int chi = mesh->euler_characteristic();
    std::mt19937 rng(12345);
    for (int trial = 0; trial < 20; ++trial) {
      SCOPED_TRACE(name + ", trial " + std::to_string(trial));
      const auto s = find_singularities(bundle, random_values(*mesh, rng));
      EXPECT_EQ(index_sum(s), chi);
      EXPECT_GT(s.size(), 100u);  // i.i.d. values: many singularities, many near-opposite edges
      for (const auto& x : s) {
        expect_inside_face(x);
        EXPECT_TRUE(x.index == 1 || x.index == -1);
        EXPECT_EQ(x.type == SingularityType::saddle, x.index < 0);
      }
    }
  }
}

// The faces' curvature given once (face_curvatures, for a caller that checks many fields
// on one mesh): every face's Ω_f as face_curvature has it, and the same singularities to
// the bit; a list of another length is refused.
TEST(SingularityPoincareHopf, GivenCurvatureGivesTheSameSingularities) {
  for (const auto& [name, mesh] : test::closed_meshes()) {
    const TangentBundle bundle(*mesh);
    const std::vector<double> curvature = face_curvatures(bundle);
    ASSERT_EQ(curvature.size(), static_cast<size_t>(mesh->num_faces())) << name;
    for (int f = 0; f < mesh->num_faces(); ++f)
      EXPECT_EQ(curvature[static_cast<size_t>(f)], face_curvature(bundle, f)) << name << " " << f;
    std::mt19937 rng(4242);
    const auto values = random_values(*mesh, rng);
    const auto a = find_singularities(bundle, values);
    const auto b = find_singularities(bundle, values, curvature);
    ASSERT_EQ(a.size(), b.size()) << name;
    for (size_t k = 0; k < a.size(); ++k) {
      EXPECT_EQ(a[k].where.face, b[k].where.face) << name;
      EXPECT_EQ(a[k].index, b[k].index) << name;
      EXPECT_EQ(a[k].position, b[k].position) << name;
      EXPECT_EQ(a[k].jacobian, b[k].jacobian) << name;
    }
    const std::vector<double> short_list(curvature.begin(), curvature.end() - 1);
    EXPECT_THROW(find_singularities(bundle, values, short_list), InternalError) << name;
  }
}

TEST(SingularityPoincareHopf, SmoothFieldsOnClosedMeshes) {
  for (const auto& [name, mesh] : test::closed_meshes()) {
    const TangentBundle bundle(*mesh);
    const int chi = mesh->euler_characteristic();
    std::mt19937 rng(777);
    for (int trial = 0; trial < 20; ++trial) {
      SCOPED_TRACE(name + ", trial " + std::to_string(trial));
      const auto s = find_singularities(bundle, smooth_values(bundle, rng));
      EXPECT_EQ(index_sum(s), chi);
      for (const auto& x : s) {
        expect_inside_face(x);
        // World position lies on its face's plane.
        const Face& f = mesh->face(x.where.face);
        EXPECT_NEAR((x.position - mesh->position(f[0])).dot(bundle.face_normal(x.where.face)), 0.0,
                    1e-12);
      }
    }
  }
}

TEST(SingularityPoincareHopf, ExactZerosAndOppositeValuesOnClosedMeshes) {
  for (const auto& [name, mesh] : test::closed_meshes()) {
    const TangentBundle bundle(*mesh);
    const int chi = mesh->euler_characteristic();
    std::mt19937 rng(99);
    std::uniform_int_distribution<int> vertex(0, mesh->num_vertices() - 1);
    std::uniform_int_distribution<int> halfedge(0, mesh->num_halfedges() - 1);
    for (int trial = 0; trial < 20; ++trial) {
      SCOPED_TRACE(name + ", trial " + std::to_string(trial));
      auto z = trial % 2 ? random_values(*mesh, rng) : smooth_values(bundle, rng);
      // Exact zeros at random vertices ...
      for (int k = 0; k < mesh->num_vertices() / 10; ++k) z[static_cast<size_t>(vertex(rng))] = 0;
      // ... on a whole vertex star (every face around it has three zero corners) ...
      const int c = vertex(rng);
      z[static_cast<size_t>(c)] = 0;
      for (int h : mesh->outgoing(c)) z[static_cast<size_t>(mesh->head(h))] = 0;
      // ... and edges whose transported values are exactly opposite.
      for (int k = 0; k < 50; ++k) {
        const int h = halfedge(rng);
        z[static_cast<size_t>(mesh->head(h))] =
            -(bundle.transport(h) * z[static_cast<size_t>(mesh->tail(h))]);
      }
      const auto s = find_singularities(bundle, z);
      EXPECT_EQ(index_sum(s), chi);
      const auto idx = face_indices(bundle, z);
      EXPECT_EQ(std::accumulate(idx.begin(), idx.end(), 0), chi);
      for (const auto& x : s) expect_inside_face(x);
    }
    // The zero field: every face fully degenerate, decided by the perturbation alone.
    const std::vector<cplx> zero(static_cast<size_t>(mesh->num_vertices()), cplx(0, 0));
    EXPECT_EQ(index_sum(find_singularities(bundle, zero)), chi) << name;
  }
}

// Where the winding of the three corner vectors transported into the face frame is well
// defined (no edge with nearly opposite vectors), the index is that winding.
TEST(SingularityPoincareHopf, IndexIsTheFaceFrameWinding) {
  for (const auto& [name, mesh] : test::all_meshes()) {
    const TangentBundle bundle(*mesh);
    std::mt19937 rng(2024);
    int compared = 0, singular = 0;
    for (int trial = 0; trial < 5; ++trial) {
      const auto z = random_values(*mesh, rng);
      const auto idx = face_indices(bundle, z);
      for (int f = 0; f < mesh->num_faces(); ++f) {
        cplx w[3];
        for (int c = 0; c < 3; ++c)
          w[c] = bundle.corner_to_face(3 * f + c) *
                 z[static_cast<size_t>(mesh->face(f)[static_cast<size_t>(c)])];
        double turn = 0;
        bool clear = true;
        for (int c = 0; c < 3; ++c) {
          const double a = std::arg(w[(c + 1) % 3] / w[c]);
          clear = clear && std::abs(a) < kPi - 0.05;
          turn += a;
        }
        if (!clear) continue;
        ++compared;
        const int winding = static_cast<int>(std::lround(turn / (2 * kPi)));
        EXPECT_EQ(idx[static_cast<size_t>(f)], winding) << name << " face " << f;
        singular += winding != 0;
      }
    }
    EXPECT_GT(compared, 4 * mesh->num_faces()) << name;
    EXPECT_GT(singular, 50) << name;
  }
}

TEST(SingularityField, FrameAndTimeAreFilled) {
  const Mesh& grid = test::grid_mesh();
  const TangentBundle bundle(grid);
  Field field(TimeSampling{0.0, 2.0, 5}, grid.num_vertices());
  const auto cases = linear_cases();
  for (int j = 0; j < field.frames(); ++j) {
    const auto z =
        linear_field(bundle, cases[static_cast<size_t>(j)].J, Vec2(0.31 + 0.1 * j, 0.23));
    std::copy(z.begin(), z.end(), field.frame(j).begin());
  }
  for (int j = 0; j < field.frames(); ++j) {
    const auto s = find_singularities(bundle, field, j);
    ASSERT_EQ(s.size(), 1u);
    EXPECT_EQ(s[0].frame, j);
    EXPECT_DOUBLE_EQ(s[0].t, 0.5 * j);
    EXPECT_EQ(s[0].type, cases[static_cast<size_t>(j)].type);
    const auto direct = find_singularities(bundle, field.frame(j));
    EXPECT_EQ(direct[0].where.face, s[0].where.face);
    EXPECT_EQ(direct[0].position, s[0].position);
  }
}

TEST(SingularityRobustness, MagnitudeDoesNotMatter) {
  for (const auto& [name, mesh] : test::all_meshes()) {
    const TangentBundle bundle(*mesh);
    std::mt19937 rng(5);
    const auto z = smooth_values(bundle, rng);
    const auto ref = find_singularities(bundle, z);
    for (double k : {1e-280, 1e-150, 1e150, 1e300}) {
      std::vector<cplx> y(z);
      for (auto& x : y) x *= k;
      const auto s = find_singularities(bundle, y);
      ASSERT_EQ(s.size(), ref.size()) << name << " × " << k;
      for (size_t i = 0; i < s.size(); ++i) {
        EXPECT_EQ(s[i].where.face, ref[i].where.face);
        EXPECT_EQ(s[i].index, ref[i].index);
        EXPECT_EQ(s[i].type, ref[i].type);
        EXPECT_LT((s[i].position - ref[i].position).norm(), 1e-9);
      }
    }
  }
}

TEST(SingularityRobustness, RejectsNonFiniteValues) {
  const Mesh& grid = test::grid_mesh();
  const TangentBundle bundle(grid);
  std::vector<cplx> z(static_cast<size_t>(grid.num_vertices()), cplx(1, 0));
  z[17] = cplx(std::nan(""), 0);
  EXPECT_THROW(find_singularities(bundle, z), Error);
  z[17] = cplx(0, INFINITY);
  EXPECT_THROW(find_singularities(bundle, z), Error);
  z.pop_back();
  EXPECT_THROW(find_singularities(bundle, z), InternalError);
}

}  // namespace
}  // namespace tvf
