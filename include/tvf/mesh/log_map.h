#pragma once
// Local planar coordinates around a point: the logarithmic map (DESIGN §4).
//
// On a flat domain the log map is exact: log_p(x) = x − p, and the frame at p is the
// global frame everywhere. On a curved mesh it is assembled from short-time heat flows
// (Crane, Weischedel, Wardetzky 2013; Sharp, Soliman, Crane 2019, §8):
//  - the frame at p is heat-flowed with the connection Laplacian (vector heat method),
//    which gives its parallel transport along geodesics;
//  - a point delta at p is heat-flowed with the scalar Laplacian; −∇u/|∇u| is the
//    direction of the geodesic from p, and the Poisson solve L φ = −div of it gives the
//    geodesic distance (the heat method).
// log_p(x) is the distance times the geodesic direction measured against the transported
// frame; within a few edge lengths of p, where the heat gradient's direction error is
// O(h / r), it is blended into the projection onto p's tangent plane (equal to second
// order in r). (A diffused ring of radial vectors, the other option of the vector heat paper,
// was measured to be biased by up to 0.5 rad towards the ring's seeds when p lies inside
// a face; the point delta has no preferred direction.) The three systems (M + tL∇,
// complex Hermitian; M + tL and L + a pin per connected component, real) are factored once
// per mesh with sparse Cholesky; each point then costs three back-substitutions and two
// passes over the faces. L∇ and L (and the heat method's gradient and divergence) are
// taken on the intrinsic Delaunay triangulation (intrinsic_triangulation.h), so their cotan
// weights are non-negative on any mesh; M stays the input's lumped areas. Vertices of
// another connected component than p's get a distance far beyond any element's falloff
// (10³ times the mesh's diameter).
#include "tvf/field/field_sampler.h"
#include "tvf/mesh/tangent_bundle.h"

#include <memory>
#include <vector>

namespace tvf {

// Log map around a point p, for every vertex v.
struct LocalChart {
  // log_p(x_v) as a complex number in the frame at p (world units): its modulus is the
  // geodesic distance, its argument the direction of the geodesic from p.
  std::vector<cplx> coords;
  // The frame at p's first axis carried to v by parallel transport, as a unit complex
  // number in v's basis: a vector z in p's frame is z·frame[v] at v.
  std::vector<cplx> frame;
};

struct LogMapOptions {
  // Diffusion time t = time_factor · h², h the mean edge length (the paper's choice is 1).
  double time_factor = 1.0;
};

class LogMap {
public:
  explicit LogMap(const TangentBundle& bundle, LogMapOptions options = {});
  ~LogMap();
  LogMap(const LogMap&) = delete;
  LogMap& operator=(const LogMap&) = delete;

  // The frame at p is the frame of face p.face (TangentBundle::face_e1/e2). Thread-safe.
  void compute(const SurfacePoint& p, LocalChart& chart) const;
  // The chart where it is needed only: every vertex within geodesic distance `radius` of
  // p gets the same construction on a patch around p (the vertices within edge-path
  // distance 1.5·radius + 8h; the three systems assembled from the patch's own faces, so
  // Neumann on its boundary, and factored for this call), which agrees with compute()
  // there to the discretization: frames to ~1e-7, coordinates to ~1 % of the radius
  // (measured 0.1–2 % on spheres, a torus, a hemisphere's rim and the bunny; the whole
  // mesh's chart is within 3 % of the closed form on the sphere). Vertices beyond the patch get coords = +∞ (and frame 1). Where the patch would
  // hold more than a quarter of the vertices (or on flat domains), this is compute().
  // Thread-safe.
  void compute_local(const SurfacePoint& p, double radius, LocalChart& chart) const;

  bool exact() const { return bundle_.is_flat(); }

private:
  struct Solvers;
  const TangentBundle& bundle_;
  LogMapOptions options_;
  std::unique_ptr<Solvers> solvers_;  // null on flat domains
};

}  // namespace tvf
