#pragma once
// The connection (vector) Laplacian of DESIGN §5:
//   (L z)_i = Σ_j w_ij (z_i − r_ji z_j),
// z_i a tangent vector at vertex i in its basis, r_ji the transport j → i.
// L is positive semidefinite where the weights are non-negative: zᴴLz = Σ_edges w_ij
// |z_i − r_ji z_j|². Cotan and uniform weights are symmetric (w_ij = w_ji), which makes L
// Hermitian, so sparse Cholesky and CG apply; mean-value weights (the paper's) are not,
// and need LU or BiCGStab.
//
// Cotan weights are taken on the intrinsic Delaunay triangulation of the mesh
// (intrinsic_triangulation.h), whose cotan weights are non-negative whatever the input's
// triangle quality, so L is positive semidefinite by construction (and definite once a
// vertex of every component is fixed, or where the connection has holonomy). Its edges j
// may be geodesics across input faces: r_ji comes from the edge's direction at both
// ends. On a mesh that is already Delaunay nothing is flipped and L is the input's cotan
// Laplacian with TangentBundle::transport, exactly as before. Uniform and mean-value
// weights stay on the input's edges.
#include "tvf/mesh/tangent_bundle.h"

#include <Eigen/SparseCore>

#include <memory>
#include <span>
#include <string>
#include <vector>

namespace tvf {

enum class LaplacianWeights {
  cotan,       // w_ij = ½ (cot α_ij + cot β_ij), the angles opposite edge ij
  uniform,     // w_ij = 1
  mean_value,  // w_ij = (tan(γ/2) + tan(δ/2)) / |x_j − x_i|, γ, δ the angles at i beside ij
};

struct ConnectionLaplacian {
  Eigen::SparseMatrix<cplx> matrix;  // |V| × |V|, column-major
  Eigen::VectorXd weight_sum;        // d_i = Σ_j w_ij (the diagonal)
  LaplacianWeights weights = LaplacianWeights::cotan;
  bool hermitian = true;
  // Cotan weights: what the intrinsic Delaunay triangulation did (0 when nothing).
  int intrinsic_flips = 0;        // edges flipped
  double mollification = 0.0;     // δ added to every edge length
  int clamped_edges = 0;          // edges still negative after the flips (boundary edges
                                  // with an obtuse opposite angle), weight set to 0
  double min_input_weight = 0.0;  // the smallest cotan weight of the input mesh (negative: not Delaunay)
};

ConnectionLaplacian connection_laplacian(const TangentBundle& bundle,
                                         LaplacianWeights weights = LaplacianWeights::cotan);

// The connected components of L's graph (its sparsity pattern): component[v] for every
// vertex, numbered from 0 in the order of their first vertex; returns their number. A
// component without any constraint gets zero in a Dirichlet solve.
int graph_components(const ConnectionLaplacian& laplacian, std::vector<int>& component);

// The result of a linear solve: what was done and how well (STYLE 5).
struct SolveReport {
  std::string method;      // e.g. "sparse Cholesky (LDLᵀ)", "sparse LU"
  int iterations = 0;      // 0 for direct methods
  double residual = 0.0;   // ‖A z − b‖ / ‖b‖ over the free vertices (0 when b = 0)
  bool success = false;
  std::string failure;     // when !success: one sentence naming the matrix and why it failed
};

// How DirichletSolver factors its matrix (measured: docs/benchmarks.md, "Sparse
// factorizations"; why: docs/architecture.md, "Constrained solves keep one pattern").
enum class DirichletFactorization {
  automatic,   // Hermitian weights: CHOLMOD from 8,000 vertices, simplicial below; mean-value: LU
  simplicial,  // Eigen's SimplicialLDLᴴ (Hermitian) or SparseLU (mean-value)
  cholmod,     // CHOLMOD's supernodal LLᴴ (its own AMD/METIS ordering); Hermitian weights only
};

// Solves the Dirichlet problem L z = 0 at free vertices with z fixed at constrained ones
// (DESIGN §5.2). Factor once, solve many (STYLE 4): the matrix keeps L's sparsity pattern
// for every constraint set (constrained rows and columns become identity), so the
// symbolic analysis is done once at construction and each solve() pays one numeric
// factorization. Not thread-safe; copy it for each thread (a copy keeps the
// factorization choice and redoes the symbolic analysis).
class DirichletSolver {
public:
  explicit DirichletSolver(const ConnectionLaplacian& laplacian,
                           DirichletFactorization factorization = DirichletFactorization::automatic);
  DirichletSolver(const DirichletSolver&);
  DirichletSolver& operator=(const DirichletSolver&) = delete;
  ~DirichletSolver();

  // constrained[v] != 0 marks fixed vertices, whose values are taken from `values`
  // (entries of free vertices are ignored). `out` receives the whole field (|V|).
  // A connected component (of L's graph) without constraints gets zero there: its
  // energy's minimiser (or one of them, where its connection is flat and L singular).
  SolveReport solve(std::span<const char> constrained, std::span<const cplx> values,
                    std::span<cplx> out);
  // As above, with soft constraints too: a free vertex v with penalty[v] = μ_v > 0 adds
  // μ_v |z_v − values[v]|² to the energy (μ_v on the diagonal, μ_v·values[v] on the right),
  // so a constraint can fade in and out continuously (the constrained generator's moving
  // elements). An empty span means no penalty.
  SolveReport solve(std::span<const char> constrained, std::span<const cplx> values,
                    std::span<cplx> out, std::span<const double> penalty);

  // The factorization in use (automatic resolved).
  DirichletFactorization factorization() const { return factorization_; }

private:
  struct Impl;
  void analyze();

  const ConnectionLaplacian& laplacian_;
  DirichletFactorization factorization_;
  std::unique_ptr<Impl> impl_;
  std::vector<int> component_;  // per vertex: its connected component in L's graph
  int num_components_ = 0;
};

}  // namespace tvf
