#pragma once
// Finite-time Lyapunov exponents (Lagrangian coherent structures, Haller 2001; Shadden,
// Lekien & Marsden 2005) of a time-varying field on a planar domain or a surface
// (DESIGN §12, "FTLE"): for each frame t_j and vertex v,
//     σ_T(v, t_j) = ln(largest singular value of ∇φ) / |T|,
// φ the flow map from t_j to t_j + T (forward; its ridges are repelling LCS) or to t_j − T
// (backward; attracting LCS), computed by RK4 over the frames (flow_map.h), every vertex
// in parallel.
//
// The gradient ∇φ at v is the least-squares fit over v's one-ring: the 2 × 2 matrix F
// minimising Σ_u |(φ(u) − φ(v)) − F (x_u − x_v)|², x_u − x_v written in v's tangent basis
// (TangentBundle::vertex_e1/e2) and φ(u) − φ(v) in the frame of the face that φ(v) lies in
// (on a planar grid both are world x, y, and the fit is exact for a linear flow map). A
// neighbour whose particle left the domain is left out of the fit; a vertex whose own
// particle left the domain before T, or with fewer than two independent neighbours left,
// gets NaN.
//
// A horizon that reaches past the field's time range: by default (HorizonPolicy::clamp)
// the window is cut at the range's end and σ is divided by the time actually integrated
// (so the last frame forward and the first frame backward, with nothing to integrate,
// are NaN); HorizonPolicy::nan gives NaN to every frame whose window does not fit. The
// result says how many frames were cut.
#include "tvf/field/field.h"
#include "tvf/integrate/flow_map.h"
#include "tvf/mesh/tangent_bundle.h"

#include <functional>
#include <vector>

namespace tvf {

enum class HorizonPolicy {
  clamp,  // integrate to the end of the range, divide by the time integrated
  nan,    // frames whose window leaves the range are NaN
};
const char* to_string(HorizonPolicy p);

struct FtleOptions {
  double horizon = 1.0;  // T > 0, in the field's time units
  bool forward = true;
  bool backward = true;
  HorizonPolicy beyond_range = HorizonPolicy::clamp;
  std::vector<int> frames;  // the frames to compute (the others are NaN); empty: all
  FlowMapOptions flow;
  // Planar grids only (ignored elsewhere): flow-map composition (Brunton & Rowley 2010).
  // Each frame interval's one-step maps φ_{k→k+1} and φ_{k+1→k} are integrated once at
  // the vertices (RK4, as above), and every frame's φ_{j→j±T} is their composition, a
  // one-step map taken off the vertices by barycentric interpolation (a window ending
  // between frames is finished by RK4; a particle is gone once a corner it is interpolated
  // from left the domain). For whole series: the work per frame drops from T/dt RK4 steps
  // to T/(frame spacing) interpolations per vertex, at the price of the interpolation's
  // error, which grows with T along the ridges (docs/benchmarks.md, "FTLE", measures it on
  // the double gyre; the tests bound it).
  bool compose = false;
  std::function<void(int done, int total)> progress;  // after each frame and direction
};

struct FtleResult {
  int frames = 0;
  int vertices = 0;
  double horizon = 0.0;
  // frames × vertices, frame-major; NaN where undefined. Empty for a direction not asked.
  std::vector<float> forward, backward;
  // Per frame, the time actually integrated (|T| unless cut at the range's end; 0 for a
  // frame not computed or with nothing to integrate).
  std::vector<double> forward_span, backward_span;
  int forward_cut = 0, backward_cut = 0;  // frames whose window was cut (or NaN'd) at the range's end
  long forward_left = 0, backward_left = 0;  // vertex-frames whose particle left the domain
  float at(const std::vector<float>& values, int frame, int v) const {
    return values[static_cast<size_t>(frame) * static_cast<size_t>(vertices) + static_cast<size_t>(v)];
  }
};

// Throws tvf::Error on a horizon that is not positive and finite or so short that no
// particle moves a millionth of the mean edge length (the fit would see rounding, not
// stretch), or a frame out of range.
FtleResult compute_ftle(const TangentBundle& bundle, const Field& field, const FtleOptions& options);

// The FTLE at one time t (a frame's or any in the field's range) in one direction
// (+1 forward, −1 backward): what the designer overlays at its current time. The window
// [t, t ± T] is cut or NaN'd at the range's end as in compute_ftle (`policy`).
struct FtleSlice {
  std::vector<float> values;  // per vertex; NaN where undefined
  double span = 0.0;          // the time integrated (0: nothing to integrate)
  bool cut = false;           // the window reached past the range's end
  long left = 0;              // vertices whose particle left the domain
};
// Throws tvf::Error on a horizon as compute_ftle does, t outside the range, or a
// direction other than ±1.
FtleSlice compute_ftle_at(const TangentBundle& bundle, const Field& field, double t, double horizon, int direction,
                          HorizonPolicy policy = HorizonPolicy::clamp, const FlowMapOptions& flow = {});

// The FTLE of one set of flow-mapped vertices: given where every vertex's particle went
// (FlowMap::advect of each vertex, at its vertex position) over a time `span`, σ per vertex
// (NaN where the particle left, or the fit has fewer than two independent neighbours).
std::vector<float> ftle_from_flow_map(const TangentBundle& bundle, const std::vector<FlowMapResult>& mapped,
                                      double span);

}  // namespace tvf
