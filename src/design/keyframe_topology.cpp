#include "tvf/design/keyframe_topology.h"

#include "design/element_regions.h"

#include "tvf/analysis/topology.h"
#include "tvf/core/error.h"
#include "tvf/design/element_field.h"
#include "tvf/design/keyframes.h"
#include "tvf/field/field.h"
#include "tvf/field/field_sampler.h"
#include "tvf/integrate/surface_path.h"
#include "tvf/integrate/surface_walk.h"
#include "tvf/mesh/edge_paths.h"
#include "tvf/scene/scene_json.h"

#include <Eigen/Dense>
#include <Eigen/SparseLU>

#include <algorithm>
#include <numeric>
#include <cstdlib>
#include <functional>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <queue>
#include <optional>
#include <string>
#include <tuple>

namespace tvf {

namespace {

// A real linear map of the plane as J w = α w + β w̄ (w complex). det J = |α|² − |β|²;
// a rotation of the frame by φ leaves α and turns β by −2φ.
struct Linear {
  cplx alpha{0, 0}, beta{0, 0};
};

Linear to_linear(const Mat2& m) {
  return {cplx(m(0, 0) + m(1, 1), m(1, 0) - m(0, 1)) / 2.0, cplx(m(0, 0) - m(1, 1), m(1, 0) + m(0, 1)) / 2.0};
}

Mat2 to_matrix(const Linear& l) {
  Mat2 m;
  m << l.alpha.real() + l.beta.real(), l.beta.imag() - l.alpha.imag(), l.alpha.imag() + l.beta.imag(),
      l.alpha.real() - l.beta.real();
  return m;
}

// Moduli linearly, arguments along the shorter arc: |α| − |β| (the sign of det J) moves
// linearly between its two ends, so it keeps its sign when both ends have the same.
cplx blend(cplx a, cplx b, double s) {
  const double r = (1 - s) * std::abs(a) + s * std::abs(b);
  if (r == 0) return {0, 0};
  const double pa = std::abs(a) > 0 ? std::arg(a) : std::arg(b);
  const double pb = std::abs(b) > 0 ? std::arg(b) : pa;
  return std::polar(r, pa + s * std::remainder(pb - pa, 2 * std::numbers::pi));
}

double smoothstep(double u) {
  u = std::clamp(u, 0.0, 1.0);
  return u * u * (3 - 2 * u);
}

// The time warp of one key-frame interval: u(τ), τ = (t − t0)/(t1 − t0) clamped to [0, 1],
// the cubic Hermite curve from 0 to 1 with slopes m0 and m1 at its ends (monotone for
// slopes in [0, 3]). At the scene's first and last key frames the slope is 0 (smoothstep:
// the motion starts and stops there); at a middle key frame it is 1, the rate of the linear
// interpolation the paper's spacetime solve makes there, so the paths and the field go on
// through it instead of pausing (a track's speed at the key frame is then its path's
// length over the interval's duration on each side: C⁰ in velocity, not C¹).
struct Ease {
  double m0 = 0, m1 = 0;
  double operator()(double tau) const {
    const double x = std::clamp(tau, 0.0, 1.0);
    return x * x * (3 - 2 * x) + (m0 * (1 - x) - m1 * x) * x * (1 - x);
  }
  double at(double t, double t0, double t1) const { return (*this)((t - t0) / (t1 - t0)); }
};

// The warp of an interval (or of a path) from time a to time b: slope 1 at an end that is a
// key frame strictly between the scene's first and last (keyframe_times ascending).
Ease interval_ease(const std::vector<double>& keyframe_times, double a, double b) {
  auto middle = [&](double t) {
    return keyframe_times.size() > 2 && t > keyframe_times.front() && t < keyframe_times.back() &&
           std::find(keyframe_times.begin(), keyframe_times.end(), t) != keyframe_times.end();
  };
  return {middle(a) ? 1.0 : 0.0, middle(b) ? 1.0 : 0.0};
}

// +1 repelling, −1 attracting, 0 neither (saddles and centers).
int stability(SingularityType t) {
  switch (t) {
    case SingularityType::source:
    case SingularityType::repelling_focus: return 1;
    case SingularityType::sink:
    case SingularityType::attracting_focus: return -1;
    default: return 0;
  }
}

// The detour's profile along a path: 0 at both ends, 1 over [rise, fall] (inside (0, 1)),
// smoothstep up before it and down after, so the path stays C¹ and its ends keep the
// velocity of the undetoured path (zero at the first and last key frames).
double bump(double s, double rise, double fall) {
  return s < rise ? smoothstep(s / rise) : s > fall ? smoothstep((1 - s) / (1 - fall)) : 1.0;
}

// The joint detour's shapes: sin(πs) sin(kπs), k = 1, 2, …: zero with zero slope at both
// ends (the key frames keep their positions and the undetoured path's velocity there), k = 1 a bump, the
// higher ones moving it earlier or later and sharpening it.
double wave_shape(int k, double s) {
  return std::sin(std::numbers::pi * s) * std::sin(k * std::numbers::pi * s);
}

}  // namespace

namespace {

// A path's curve on a surface (surface_curve, below): a polyline of points on the surface
// from p0 to p1, `along` each point's arclength over the whole (0 … 1).
struct SurfaceCurve {
  // The domain the plan was made on (the plan is used with it alone, and it outlives the
  // plan: the generator and the design check hold both).
  const DesignSpace* space = nullptr;
  std::vector<Vec3> points;
  std::vector<double> along;
  double length = 0;
  // The point reached from the surface point nearest p by walking the world vector
  // `offset` (its part in that face's plane) along the surface (walk_surface: the offset's
  // straight line unfolded across the edges it meets): a detour that stays on the surface
  // however it curves, where p + offset's nearest surface point would jump to another
  // sheet beyond a fold or across a thin part.
  Vec3 walked(const Vec3& p, const Vec3& offset) const { return walked(p, space->locate(p), offset); }
  // The same from p already located (`on`, its surface point).
  Vec3 walked(const Vec3& p, const SurfacePoint& on, const Vec3& offset) const {
    const cplx d = space->bundle().world_to_face(on.face, offset);
    if (std::abs(d) == 0) return p;
    return surface_position(space->mesh(), walk_surface(space->bundle(), on, d).end);
  }
  // Where the polyline's chords cut across the surface (surface_curve): the walks that
  // join its points (SurfacePaths::Route: walking steps[k] from starts[k] reaches
  // points[k + 1]); empty otherwise.
  std::vector<SurfacePoint> starts;
  std::vector<cplx> steps;
  // The point at arclength fraction s (linear between the polyline's points: within a
  // hair of the surface, which locate() snaps; along the walk between them where the curve
  // is a route).
  Vec3 at(double s) const {
    if (s <= 0) return points.front();
    if (s >= 1) return points.back();
    const auto k = static_cast<size_t>(std::upper_bound(along.begin(), along.end(), s) - along.begin()) - 1;
    const double w = along[k + 1] > along[k] ? (s - along[k]) / (along[k + 1] - along[k]) : 0.0;
    if (!steps.empty())
      return w > 0 ? surface_position(space->mesh(), walk_surface(space->bundle(), starts[k], w * steps[k]).end)
                   : points[k];
    return points[k] + w * (points[k + 1] - points[k]);
  }
  // The curve's chord at arclength fraction s (the first at 0, the last at 1).
  Vec3 chord_at(double s) const {
    const auto k = std::min(
        static_cast<size_t>(std::max<std::ptrdiff_t>(std::upper_bound(along.begin(), along.end(), s) - along.begin() - 1, 0)),
        points.size() - 2);
    return points[k + 1] - points[k];
  }
  // The curve's frame at the surface point `on` (the curve's point at s): its direction
  // there in the face's plane and the face normal × it (zero where the chord is normal to
  // the face).
  std::pair<Vec3, Vec3> frame(double s, const SurfacePoint& on) const {
    const Vec3 n = space->bundle().face_normal(on.face);
    Vec3 t = chord_at(s);
    t -= t.dot(n) * n;
    if (!(t.norm() > 0)) return {Vec3::Zero(), Vec3::Zero()};
    t.normalize();
    return {t, n.cross(t)};
  }
  // walked() from the curve's point at s moved `in_frame` in the curve's frame (its real
  // part along the curve: the point at arclength fraction s + Re/length, straight on past
  // an end; its imaginary part across it, to the left), plus the world offset `extra`.
  // An offset so given is carried along the curve as it turns over the surface (a
  // geodesic's frame is parallel) and its part along the curve stays on it, where one
  // world vector of an end, projected into a long leg's far faces, pointed anywhere and
  // walked the path off the surface (CGAL's man: static saddles coming to rest, offsets
  // 0.08 along curves 1.0 long round the body).
  Vec3 walked_from(double s, cplx in_frame, const Vec3& extra) const {
    if (in_frame == cplx{0, 0}) return walked(at(s), extra);
    const double u = s + in_frame.real() / length;
    const double past = u < 0 ? u : u > 1 ? u - 1 : 0.0;  // beyond an end, in fractions of the length
    const double v = std::clamp(u, 0.0, 1.0);
    const Vec3 p = at(v);
    const SurfacePoint on = space->locate(p);
    const auto [t, b] = frame(v, on);
    return walked(p, on, extra + past * length * t + in_frame.imag() * b);
  }
};

}  // namespace

// One singularity carried from (p0, t0) to (p1, t1), present for t0 < t < t1. Its linear
// field is given in the frame of face `ref` (the frame at p0): the ends' α and β.
struct KeyframeTopologyPlan::Track {
  Vec3 p0, p1;
  // On a surface, the path's curve on it (the shortest path from p0 to p1, straightened on
  // the surface; shared between copies of the track); null on planar domains, where the
  // path is the straight segment.
  std::shared_ptr<const SurfaceCurve> curve;
  double t0 = 0, t1 = 0;
  Linear j0, j1;
  Vec3 ref_e1 = Vec3::UnitX();  // the first axis of the reference frame, world
  SingularityType type = SingularityType::source;
  // The second key frame's type: of the other stability for a node matched as the last
  // resort, whose α then turns through a center (the shorter way round unless `other_way`).
  SingularityType to_type = SingularityType::source;
  bool other_way = false;
  int index = 0;   // +1 or −1 (0: a template standing in the router's way)
  int group = -1;  // ≥ 0: one of a created or cancelled pair (the two are meant to meet)
  int slot = -1;   // its place among the interval's tracks while PathRouter::route() runs
  bool guided = false;  // its interval's guide field constrains the frames (Guide, below)
  bool free = false;    // its interval could not be guided and is left free (no constraint)
  // A detour bent into the path (PathRouter, below): amplitude · bump(s, rise, fall) · dir.
  struct Bend {
    double rise = 0.5, fall = 0.5, amplitude = 0;
    Vec3 dir = Vec3::Zero();  // unit, world, tangent to the domain where the paths meet
  };
  std::vector<Bend> bends;  // empty: the straight segment
  // A joint detour (PathRouter::joint, below): Σ_k wave[k] · wave_shape(k + 1, s), world
  // vectors; empty when the pairwise bends sufficed.
  std::vector<Vec3> wave;
  // How far the singularity's neighbourhood has turned since the track's first end, as the
  // doubled angle of its neighbours' directions (unwrapped), at u = k / (turn.size() − 1)
  // of the track's time; empty: the Jacobian is interpolated between the two ends alone.
  std::vector<double> turn;

  // Path parameter at time t: the interval's warp (Ease) from the key frame's end.
  Ease ease;
  double param(double t) const { return ease.at(t, t0, t1); }
  // Through a middle key frame the path goes on in the direction it leaves in (C¹; see
  // through_velocity): Hermite terms added to the segment, s(1 − s)² · through0 − s²(1 −
  // s) · through1, which change its derivative at s = 0 by through0 and at s = 1 by
  // through1 and nothing else at the ends. World vectors, tangent to the domain at p0 and
  // p1; zero at the scene's first and last key frames and where the singularity is not
  // carried on both sides. On a surface the two are kept in the curve's frame at their ends
  // (along it, across it: set_through_frames) and the terms are carried along the curve in
  // its frame and walked from its point like a detour (SurfaceCurve::walked_from): a world
  // vector of one end, projected into the faces of a long leg's other end (a camel's body
  // down a leg), pointed anywhere there and walked the path off the surface.
  Vec3 through0 = Vec3::Zero(), through1 = Vec3::Zero();
  cplx through_frame0{0, 0}, through_frame1{0, 0};
  bool bent_through() const { return through0 != Vec3::Zero() || through1 != Vec3::Zero(); }
  Vec3 through(double s) const { return s * (1 - s) * (1 - s) * through0 - s * s * (1 - s) * through1; }
  cplx through_in_frame(double s) const {
    return s * (1 - s) * (1 - s) * through_frame0 - s * s * (1 - s) * through_frame1;
  }
  void set_through_frames() {
    if (!curve) return;
    auto in_frame = [&](const Vec3& c, double s, const Vec3& p) {
      if (c == Vec3::Zero()) return cplx{0, 0};
      const auto [t, b] = curve->frame(s, curve->space->locate(p));
      return cplx{c.dot(t), c.dot(b)};
    };
    through_frame0 = in_frame(through0, 0, p0);
    through_frame1 = in_frame(through1, 1, p1);
  }
  // The path before any detour at parameter s: the straight segment's point, or on a
  // surface the curve's point at arclength fraction s; turned at a middle key frame by
  // the Hermite terms.
  Vec3 base(double s) const {
    if (curve) return bent_through() ? curve->walked_from(s, through_in_frame(s), Vec3::Zero()) : curve->at(s);
    return p0 + s * (p1 - p0) + through(s);
  }
  // The path's length before any detour.
  double base_length() const { return curve ? curve->length : (p1 - p0).norm(); }
  // The constraint's position at path parameter s (world; snapped to the domain where it
  // is placed). Without bends exactly base(s): on a planar domain the straight segment's
  // point; on a surface the curve's, and a detour (an offset tangent to the surface where
  // the paths meet) is walked along the surface from the curve's point (SurfaceCurve::walked).
  Vec3 raw(double s) const {
    if (curve) {
      if (bends.empty() && wave.empty()) return base(s);
      Vec3 offset = Vec3::Zero();
      for (const Bend& b : bends) offset += b.amplitude * bump(s, b.rise, b.fall) * b.dir;
      for (size_t k = 0; k < wave.size(); ++k) offset += wave_shape(static_cast<int>(k) + 1, s) * wave[k];
      return curve->walked_from(s, through_in_frame(s), offset);
    }
    Vec3 p = base(s);
    for (const Bend& b : bends) p += b.amplitude * bump(s, b.rise, b.fall) * b.dir;
    for (size_t k = 0; k < wave.size(); ++k) p += wave_shape(static_cast<int>(k) + 1, s) * wave[k];
    return p;
  }
  // The neighbourhood's turn at time t (linear between the samples; 0 without).
  double turned(double t) const {
    if (turn.empty()) return 0;
    const double x = std::clamp((t - t0) / (t1 - t0), 0.0, 1.0) * static_cast<double>(turn.size() - 1);
    const size_t k = std::min(static_cast<size_t>(x), turn.size() - 2);
    return turn[k] + (x - static_cast<double>(k)) * (turn[k + 1] - turn[k]);
  }
};

struct KeyframeTopologyPlan::Template {
  CompiledElement element;
  double t0 = 0, t1 = 0;  // present for t0 ≤ t ≤ t1
  double radius = 0;
  bool guided = false;  // its interval's guide field stands in for it
  bool free = false;    // its interval could not be guided and is left free (not placed)
};

// One interval's guide field on a planar domain: G(z, t) = h(z, t) · Π_k g_k(z, t), every
// free vertex of the frames strictly between the two key frames fixed to it. The factors
// carry the plan's zeros: a matched track's own linear field α(z − p) + β conj(z − p)
// (J(t) as its constraint has it), a created or cancelled pair's two linear factors while
// its tracks hold (J blended from the key frame's to z − p for the node and conj(z − p)
// for the saddle), and over [t_c − τ, t_c + τ] the pair's saddle–node factor
// |w|² + μ(t) + 2is Im w, w = (z − mid) conj(axis), μ from −s² to s² (the two zeros ±√−μ
// on the axis meet at t_c; the product of the two linear factors at t_c − τ). h has no
// zero: h_k = F_k / Π g_k(t_k) at the two key frames, h(t) = h₀ exp(u(t) log(h₁/h₀)) with
// the logarithm lifted continuously over the mesh and u the tracks' warp of time (Ease). So
// G's zeros are exactly the plan's, each of its index, and nothing else; G equals the key
// frames at both ends. Near a matched node the phase h Π_{k≠j} g_k would turn its type
// (a source into a centre): G is multiplied by exp(−Λ(z, t)), Λ the nodes' λ_j(t)
// interpolated by Shepard's weights |z − p_j|⁻⁴, the real part (the size) only near the
// nodes (lambda_at) (λ_j = log c_j less its two ends' values taken within (−π, π];
// c_j: G's factor over the node's own linear field at its point, tabled at kTable + 1
// times and unwrapped), and within min(0.7 radius, 1.5 h) of a node
// the value is the node's linear field itself (blended out to min(radius, 2.5 h)).
// Saddles keep G's own phase (a saddle stays a saddle).
struct KeyframeTopologyPlan::Guide {
  static constexpr int kTable = 256;
  size_t first = 0, last = 0;  // the interval's tracks
  double t0 = 0, t1 = 0;
  Ease ease;  // the interval's time warp (its tracks' too)
  double radius = 0;
  struct Pair {
    size_t node = 0, saddle = 0;  // tracks
    cplx mid{0, 0}, axis{1, 0};   // world plane; axis: unit, saddle towards node
    double s = 0, tc = 0, tau = 0;
    bool cancel = true;
  };
  std::vector<Pair> pairs;
  std::vector<cplx> h0, log_q;           // per vertex
  std::vector<std::vector<cplx>> lambda;  // per track of [first, last): λ at kTable + 1 times (empty: a pair's)
  // A created or cancelled pair's node held to its key frame's type: λ = i times the turn
  // of G's α at the node since that key frame, at kTable + 1 times over [a, b] (where the
  // node is: between t_c and that key frame), one more of the nodes Λ interpolates; before
  // its birth (after its death) a node at the template's middle whose λ goes from Λ's value
  // there without it, at the other key frame, to the node's λ at t_c. Empty: not held (G's
  // α had no direction somewhere).
  struct PairPhase {
    double a = 0, b = 0;
    std::vector<double> turn;
  };
  std::vector<PairPhase> pair_phase;  // per pair
};

// One interval's guide field on a surface, where no product of scalar factors has the
// carried zeros and no other (a scalar function's zeros on a closed surface sum to index
// 0). Ratio factors do: R_j = (z − p_j(t)) / (z − p_j(t₀)) (conjugated for a saddle) has
// index 0 seen from afar, so it can be blended to 1 without a zero. z is a log-map chart
// around the path's middle; log R_j is single-valued off the path (its argument is the
// angle the path from p_j(t₀) to p_j(t) subtends at z), so S_j = exp(w_j log R_j), w_j = 1
// within `inner` of the path (chart distance) and a smoothstep down to 0 at `outer`, is
// R_j itself near the path and has no zero or pole anywhere else. G₀(t) = F₀ Π_j S_j has
// the zeros p_j(t) alone (F₀'s own zeros p_j(t₀) are the poles'), each of its index; G₁(t)
// = F₁ Π_j S_j / S_j(t₁) likewise, and G₁/G₀ = H is the same at every t, without zero or
// pole. G(t) = G₀(t) · exp(u(t) log H), log H lifted over the mesh's edges: F₀ at t₀, F₁
// at t₁, and no zero but the plan's in between. A created or cancelled pair has one
// factor for its two tracks and its template, P = Q(t) / Q(t_ref) with Q the planar
// guide's: (z − n(t)) conj(z − s(t)) while the tracks hold, |w|² + μ(t) + 2iσ Im w over
// [t_c − τ, t_c + τ] (w = (z − mid) conj(axis) in the pair's chart, the template's zeros
// the tracks' ends, so the two agree at μ = −σ²), and the template's value at μ = σ² (no
// zero) where the pair does not exist. Q has index 0 seen from afar (+1 − 1), so P does
// too; log P is lifted along time (the arguments of Q's steps summed over kSamples, as
// log R_j is along the path) and is single-valued off the zeros' sweep.
struct KeyframeTopologyPlan::SurfaceGuide {
  double t0 = 0, t1 = 0;
  Ease ease;  // the interval's time warp (its tracks' too)
  std::vector<cplx> f0, log_h;  // per vertex (f0 in vertex bases)
  // A pair's factor at one time: (z − n) conj(z − s), or |w|² + μ + 2iσ Im w.
  struct PairState {
    bool linear = false;
    cplx n{0, 0}, s{0, 0};
    double mu = 0;
  };
  struct Path {
    size_t track = 0;                 // a pair's: its node's track
    bool conj = false;                // a saddle's factor is conjugated
    std::vector<cplx> coords;         // the chart, per vertex (+∞ beyond its patch)
    std::vector<size_t> support;      // the vertices with w > 0
    std::vector<double> w;            // their weights
    std::vector<cplx> x;              // the path in the chart at s = k / kSamples
    // The track's linear part J(s) in the chart (M J M⁻¹, M the chart's map of the face
    // holding x(s)) at the same s: the factor is A(s)(z − x(s)) / A(0)(z − x(0)). Empty:
    // the plain ratio (conjugated for a saddle).
    std::vector<Linear> a;
    // A created or cancelled pair (then `x` is unused).
    bool pair = false, cancel = true;
    size_t saddle = 0;                // its saddle's track
    double tc = 0, tau = 0;           // the template's time and half-width
    cplx mid{0, 0}, axis{1, 0};       // the template in the chart
    double sigma = 0;
    std::vector<PairState> states;    // at t₀ + (t₁ − t₀) k / kSamples
  };
  static constexpr int kSamples = 256;
  std::vector<Path> paths;
  // The nodes' phase: G's α at a node over the plan's (the track's J(t)), its argument at
  // kSamples + 1 times, unwrapped, less its ends' values within (−π, π]; G is turned by
  // −Λ, Λ the nodes' λ interpolated by Shepard's weights |x − p_j|⁻⁴ (the planar guide's
  // correction), so a node keeps its type while the configuration turns round it. Away
  // from its node a λ is taken averaged in time (far_lambda): read in one face, it jumps
  // where the node crosses an edge.
  std::vector<size_t> nodes;                // tracks
  std::vector<std::vector<double>> lambda;  // per node
  // The local correction (PhaseCheck's other choice): each node's λ applied within `inner`
  // of it and blended to 0 by a smoothstep at reach[n] (less than half its distance from
  // any other path), instead of Shepard's blend over the whole surface, which sweeps a
  // switch between nodes whose λ differ across the vertices between them as they move.
  // Within `inner` of a node (blended out by 2.5 edge lengths) the local choice also takes
  // the track's own linear field J(t)(z − p(t)), scaled by |G's α| / |J's α| at the node
  // (`scale`, tabled like λ), as the planar guide does: G's piecewise-linear zero can sit
  // half an edge off the planned point in a face whose Jacobian is another (CGAL's
  // mushroom: the carried center a sink at one frame with λ ≈ 0 at the planned face).
  // A node whose λ ends a whole turn is left as G carries it by the local choice
  // (`carried`: λ 0 and no linear field of its own, which would be the plan's type against
  // G's turned one around it); the others are kept to their types. (The sphere's knot: a
  // source and a center trading places, the source's λ ends −2π, the center's 0, and the
  // router's phase model finds no route that ends them nearer; the center was a focus
  // half the interval, trace/√det up to 1.46, and is now a center in every frame.)
  bool local = false;
  std::vector<char> carried;  // per node, the local choice's
  // The nodes the kept choice does not hold to their types (every node of a choice without
  // the nodes' correction; a carried one of the local choice): their λ as G leaves it, the
  // turn of their linear part from the plan's type (the report's phase_turns, phase_swing).
  struct Turning {
    size_t track = 0;
    double end = 0, swing = 0;  // λ at t₁ (a whole number of turns), its largest |λ|
  };
  std::vector<Turning> turning;
  double inner = 0, linear_reach = 0;
  std::vector<double> reach;                // per node
  std::vector<std::vector<double>> scale;   // per node, as lambda
  // A created or cancelled pair's node held to its key frame's type (the planar guide's
  // PairPhase): its λ is the turn of G's α (before the correction) at the node since that
  // key frame, at kSamples + 1 times over [a, b] (where the node is: between t_c and that
  // key frame), one more node of Λ; before its birth (after its death) a node at the
  // template's middle whose λ goes from what Λ is there without it, at the other key frame,
  // to the node's λ at t_c. (α of a face's linear field is the same in any frame of the
  // face, so its argument is the node's type: 0 a source, ±π/2 a center, π a sink.)
  struct PairHold {
    bool cancel = true;
    double t0 = 0, t1 = 0, tc = 0;  // the interval and the pair's event
    double a = 0, b = 0;
    Vec3 mid = Vec3::Zero();  // the template's middle on the surface
    std::vector<Vec3> at;     // the node's point at the tabled times
    std::vector<double> turn;
  };
  std::vector<PairHold> holds;
  // The paths' log factors (surface_log_factors) at the scene's frames inside the interval,
  // t[i], on the vertices of the paths' supports (`tube`; zero elsewhere): made once, in
  // time order, each vertex's argument sums carried on from frame to frame, for the
  // acceptance check and the solve's frames (the same values as summing from t₀ at each).
  // They do not depend on the phase correction, so the check's choices share them.
  struct FrameLogs {
    std::vector<double> t;
    std::vector<size_t> tube;
    std::vector<std::vector<cplx>> log;
  };
  std::shared_ptr<const FrameLogs> logs;  // null: made at each time asked
};

KeyframeTopologyPlan::~KeyframeTopologyPlan() = default;
KeyframeTopologyPlan::KeyframeTopologyPlan(KeyframeTopologyPlan&&) noexcept = default;

namespace {

// β of a Jacobian given in face f's frame, re-expressed in the frame whose first axis is
// the world vector e1 (projected onto f's plane): a vector z in that frame is z·c in f's.
cplx beta_in_frame(const TangentBundle& bundle, int f, const Vec3& e1, cplx beta) {
  const cplx c = bundle.world_to_face(f, e1);
  if (std::abs(c) == 0) return beta;
  const cplx u = c / std::abs(c);
  return beta * std::conj(u) * std::conj(u);
}

struct Candidate {
  double distance;
  size_t a, b;
};

// Greedy matching nearest first among the pairs `allowed` accepts.
template <class Allowed>
void match_nearest(std::span<const Singularity> A, std::span<const Singularity> B, std::vector<int>& match_a,
                   std::vector<int>& match_b, Allowed allowed, std::vector<std::pair<size_t, size_t>>& out) {
  std::vector<Candidate> c;
  for (size_t a = 0; a < A.size(); ++a)
    for (size_t b = 0; b < B.size(); ++b)
      if (match_a[a] < 0 && match_b[b] < 0 && allowed(A[a], B[b]))
        c.push_back({(A[a].position - B[b].position).norm(), a, b});
  std::sort(c.begin(), c.end(), [](const Candidate& x, const Candidate& y) {
    return x.distance < y.distance || (x.distance == y.distance && std::make_pair(x.a, x.b) < std::make_pair(y.a, y.b));
  });
  for (const Candidate& x : c) {
    if (match_a[x.a] >= 0 || match_b[x.b] >= 0) continue;
    match_a[x.a] = static_cast<int>(x.b);
    match_b[x.b] = static_cast<int>(x.a);
    out.emplace_back(x.a, x.b);
  }
}

// Pairs a saddle with a node (index +1) of one key frame's unmatched singularities,
// nearest first: (saddle, node) indices.
std::vector<std::pair<size_t, size_t>> pair_unmatched(std::span<const Singularity> S, const std::vector<int>& matched) {
  std::vector<Candidate> c;
  for (size_t a = 0; a < S.size(); ++a)
    for (size_t b = 0; b < S.size(); ++b)
      if (matched[a] < 0 && matched[b] < 0 && S[a].index < 0 && S[b].index > 0)
        c.push_back({(S[a].position - S[b].position).norm(), a, b});
  std::sort(c.begin(), c.end(), [](const Candidate& x, const Candidate& y) {
    return x.distance < y.distance || (x.distance == y.distance && std::make_pair(x.a, x.b) < std::make_pair(y.a, y.b));
  });
  std::vector<char> used(S.size(), 0);
  std::vector<std::pair<size_t, size_t>> out;
  for (const Candidate& x : c) {
    if (used[x.a] || used[x.b]) continue;
    used[x.a] = used[x.b] = 1;
    out.emplace_back(x.a, x.b);
  }
  return out;
}

using Track = KeyframeTopologyPlan::Track;

// A track's linear field at time t in the frame of face `face` (the face holding its
// point): |α| and |β| blended, their arguments along the shorter arc, β turned with the
// neighbourhood where the track has a turn, then carried from the track's reference frame.
Linear track_jacobian(const TangentBundle& bundle, const Track& tr, double t, int face) {
  const double s = tr.param(t);
  Linear j{blend(tr.j0.alpha, tr.j1.alpha, s), blend(tr.j0.beta, tr.j1.beta, s)};
  if (tr.other_way && std::abs(tr.j0.alpha) > 0 && std::abs(tr.j1.alpha) > 0) {
    // The longer arc: through the other center (a source's α turning clockwise instead).
    const double pa = std::arg(tr.j0.alpha);
    double d = std::remainder(std::arg(tr.j1.alpha) - pa, 2 * std::numbers::pi);
    d -= std::copysign(2 * std::numbers::pi, d);
    j.alpha = std::polar(std::abs(j.alpha), pa + s * d);
  }
  if (!tr.turn.empty()) {
    // β's argument follows the neighbourhood's turn, plus the shorter-arc remainder
    // that brings it to the second end's, spread linearly like blend().
    const double total = tr.turn.back();
    const double pa = std::abs(tr.j0.beta) > 0   ? std::arg(tr.j0.beta)
                      : std::abs(tr.j1.beta) > 0 ? std::arg(tr.j1.beta) - total
                                                 : 0.0;
    const double pb = std::abs(tr.j1.beta) > 0 ? std::arg(tr.j1.beta) : pa + total;
    const double rest = std::remainder(pb - pa - total, 2 * std::numbers::pi);
    const double r = (1 - s) * std::abs(tr.j0.beta) + s * std::abs(tr.j1.beta);
    j.beta = std::polar(r, pa + tr.turned(t) + s * rest);
  }
  // From the reference frame into the frame at p(t) (the face holding it).
  const cplx c = bundle.world_to_face(face, tr.ref_e1);
  if (std::abs(c) > 0) j.beta *= (c / std::abs(c)) * (c / std::abs(c));
  return j;
}

// "(x, y)" or "(x, y, z)" to three digits, without "-0" or 1e-17 for a zero.
std::string describe_point(const Vec3& p, bool planar, double unit) {
  auto c = [&](double x) { return std::abs(x) < 1e-9 * unit ? 0.0 : x; };
  return planar ? fmt::format("({:.3g}, {:.3g})", c(p.x()), c(p.y()))
                : fmt::format("({:.3g}, {:.3g}, {:.3g})", c(p.x()), c(p.y()), c(p.z()));
}

using Guide = KeyframeTopologyPlan::Guide;

cplx flat(const Vec3& w) { return {w.x(), w.y()}; }

// A linear field given in face f's frame, in world (plane) terms.
Linear world_linear(const TangentBundle& bundle, int face, const Linear& j) {
  const Vec3 &e1 = bundle.face_e1(face), &e2 = bundle.face_e2(face);
  Mat2 e;
  e << e1.x(), e2.x(), e1.y(), e2.y();
  return to_linear(e * to_matrix(j) * e.transpose());
}

// One factor of a guide: α(z − p) + β conj(z − p), or a pair's |w|² + μ + 2iσ Im w with
// w = (z − mid) conj(axis).
struct Factor {
  bool pair = false;
  cplx p{0, 0}, alpha{1, 0}, beta{0, 0};
  cplx mid{0, 0}, axis{1, 0};
  double mu = 0, sigma = 0;
  int track = -1;  // a matched track's factor: its index from the guide's first; else −1
  int index = 0;   // the matched track's index (+1 node, −1 saddle)
  cplx operator()(cplx z) const {
    if (!pair) {
      const cplx w = z - p;
      return alpha * w + beta * std::conj(w);
    }
    const cplx w = (z - mid) * std::conj(axis);
    return {std::norm(w) + mu, 2 * sigma * w.imag()};
  }
};

double smoothstep01(double t, double a, double b) { return smoothstep((t - a) / (b - a)); }

std::vector<Factor> guide_factors(const DesignSpace& space, const std::vector<Track>& tracks, const Guide& g,
                                  double t) {
  const TangentBundle& bundle = space.bundle();
  std::vector<char> in_pair(g.last - g.first, 0);
  for (const Guide::Pair& pr : g.pairs) in_pair[pr.node - g.first] = in_pair[pr.saddle - g.first] = 1;
  std::vector<Factor> out;
  for (size_t i = g.first; i < g.last; ++i) {
    if (in_pair[i - g.first]) continue;
    const Track& tr = tracks[i];
    const Vec3 p = tr.raw(tr.param(t));
    const int face = space.locate(p).face;
    const Linear j = world_linear(bundle, face, track_jacobian(bundle, tr, t, face));
    Factor f;
    f.p = flat(p);
    f.alpha = j.alpha;
    f.beta = j.beta;
    f.track = static_cast<int>(i - g.first);
    f.index = tr.index;
    out.push_back(f);
  }
  for (const Guide::Pair& pr : g.pairs) {
    const double a = pr.tc - pr.tau, b = pr.tc + pr.tau;
    if (pr.cancel ? t <= a : t >= b) {
      for (const size_t i : {pr.node, pr.saddle}) {
        const Track& tr = tracks[i];
        const double u = tr.param(t);
        const Vec3 p0 = tr.raw(0);
        const int f0 = space.locate(p0).face;
        const Linear key = world_linear(bundle, f0, track_jacobian(bundle, tr, tr.t0, f0));
        const bool node = tr.index > 0;
        Factor f;
        f.p = flat(tr.raw(u));
        f.alpha = blend(key.alpha, node ? cplx(1, 0) : cplx(0, 0), u);
        f.beta = blend(key.beta, node ? cplx(0, 0) : cplx(1, 0), u);
        out.push_back(f);
      }
    } else {
      const double u = smoothstep01(t, a, b);
      Factor f;
      f.pair = true;
      f.mid = pr.mid;
      f.axis = pr.axis;
      f.sigma = pr.s;
      f.mu = pr.s * pr.s * (pr.cancel ? 2 * u - 1 : 1 - 2 * u);
      out.push_back(f);
    }
  }
  return out;
}

// G's h at a point of face `at.face` (h₀ and log q interpolated linearly there).
cplx guide_h(const Mesh& mesh, const Guide& g, const SurfacePoint& at, double u) {
  cplx h0{0, 0}, lq{0, 0};
  for (int k = 0; k < 3; ++k) {
    const auto v = static_cast<size_t>(mesh.face(at.face)[static_cast<size_t>(k)]);
    h0 += at.bary[k] * g.h0[v];
    lq += at.bary[k] * g.log_q[v];
  }
  return h0 * std::exp(u * lq);
}

// Fills the vertices not `ok` with the mean of their filled neighbours, ring by ring (a
// smooth quantity at a vertex where it could not be evaluated: on a zero); false when one
// stays unfilled (no filled neighbour, or their mean is zero).
bool fill_from_neighbours(const std::vector<std::vector<size_t>>& nbr, std::vector<cplx>& values, std::vector<char>& ok) {
  for (bool changed = true; changed;) {
    changed = false;
    for (size_t v = 0; v < values.size(); ++v) {
      if (ok[v]) continue;
      cplx sum{0, 0};
      int n = 0;
      for (const size_t w : nbr[v])
        if (ok[w] == 1) sum += values[w], ++n;
      if (n == 0 || std::abs(sum) == 0) continue;
      values[v] = sum / static_cast<double>(n);
      ok[v] = 2;
      changed = true;
    }
    for (char& o : ok) o = o ? char{1} : char{0};
  }
  return std::all_of(ok.begin(), ok.end(), [](char o) { return o != 0; });
}

// The matched tracks' λ at time t, per factor (0 for the others).
std::vector<cplx> factor_lambda(const Guide& g, const std::vector<Factor>& factors, double t) {
  const double x = std::clamp((t - g.t0) / (g.t1 - g.t0), 0.0, 1.0) * Guide::kTable;
  const auto k = std::min(static_cast<size_t>(x), static_cast<size_t>(Guide::kTable - 1));
  std::vector<cplx> lambda(factors.size(), cplx(0, 0));
  for (size_t m = 0; m < factors.size(); ++m)
    if (factors[m].track >= 0 && !g.lambda[static_cast<size_t>(factors[m].track)].empty()) {
      const std::vector<cplx>& l = g.lambda[static_cast<size_t>(factors[m].track)];
      lambda[m] = l[k] + (x - static_cast<double>(k)) * (l[k + 1] - l[k]);
    }
  return lambda;
}

// Λ(z): the nodes' λ, interpolated by Shepard's weights |z − p|⁻⁴ (Λ(p_j) = λ_j with zero
// slope there). Saddles keep their type whatever the phase: G's own (their axes turn with
// the neighbourhood, and no linear region is blended in, which for a weak saddle made
// zeros where G's quadratic terms take over). The phase (Im λ, what keeps a node's type) is
// spread so; the size (Re λ) only near its node (lambda_at).
struct PhaseNode {
  cplx p, lambda;
};
// Λ at z. Its real part: the nodes' Re λ_j (the size of G against the node's own linear
// field, which apply_guide blends in near it: the two must agree in size there, or the
// blend can hold extra zeros), by Shepard's weights |z − p_j|⁻⁴ beside a weight (2r)⁻⁴ of
// 0 (r the region radius): Re λ_j at its node, half of it 2r away, nothing far off.
// exp(−Re Λ) is positive, so it moves no zero. Spread over the whole domain like the phase
// (until session 25), the nodes' size set the far field's: half-way between example 26's
// knot's key frames its median size was 15 times theirs (65²; now 1.2), and a node crossing
// a ridge of h (a key frame's region edge) changed the size of the whole field at once.
// Its imaginary part: the nodes' Im λ_j by Shepard's weights alone (0 without nodes).
cplx lambda_at(const std::vector<PhaseNode>& nodes, double radius, cplx z) {
  double size = 0, size_den = 1 / std::pow(2 * radius, 4), phase = 0, phase_den = 0;
  for (const PhaseNode& n : nodes) {
    const double w = 1 / std::pow(std::max(std::abs(z - n.p), 1e-12 * radius), 4);
    size += w * n.lambda.real();
    size_den += w;
    phase += w * n.lambda.imag();
    phase_den += w;
  }
  return {size / size_den, phase_den > 0 ? phase / phase_den : 0.0};
}

// A created or cancelled pair's node at time t (world plane), where it is: on its track
// while that holds, else the template's zero on +axis, √−μ from its middle.
std::optional<cplx> pair_node(const std::vector<Track>& tracks, const Guide::Pair& pr, double t) {
  if (pr.cancel ? t > pr.tc : t < pr.tc) return std::nullopt;
  const double a = pr.tc - pr.tau, b = pr.tc + pr.tau;
  if (pr.cancel ? t <= a : t >= b) {
    const Track& tr = tracks[pr.node];
    return flat(tr.raw(tr.param(t)));
  }
  const double u = smoothstep01(t, a, b);
  const double mu = pr.s * pr.s * (pr.cancel ? 2 * u - 1 : 1 - 2 * u);
  return pr.mid + pr.axis * std::sqrt(std::max(-mu, 0.0));
}

// The nodes whose phase Λ holds at time t: the matched nodes (their λ tabled) and the
// created or cancelled pairs' (PairPhase).
std::vector<PhaseNode> phase_nodes(const std::vector<Track>& tracks, const Guide& g,
                                   const std::vector<Factor>& factors, double t) {
  std::vector<PhaseNode> nodes;
  const std::vector<cplx> lambda = factor_lambda(g, factors, t);
  for (size_t m = 0; m < factors.size(); ++m)
    if (factors[m].track >= 0 && factors[m].index > 0) nodes.push_back({factors[m].p, lambda[m]});
  const size_t matched = nodes.size();
  for (size_t q = 0; q < g.pair_phase.size(); ++q) {
    const Guide::PairPhase& ph = g.pair_phase[q];
    if (ph.turn.empty()) continue;
    const Guide::Pair& pr = g.pairs[q];
    if (const auto p = pair_node(tracks, pr, t)) {
      const double x = std::clamp((t - ph.a) / (ph.b - ph.a), 0.0, 1.0) * Guide::kTable;
      const auto k = std::min(static_cast<size_t>(x), static_cast<size_t>(Guide::kTable - 1));
      nodes.push_back({*p, cplx(0, ph.turn[k] + (x - static_cast<double>(k)) * (ph.turn[k + 1] - ph.turn[k]))});
    } else {
      // Not born yet (or dead): at the template's middle, from what Λ is there without it
      // (at the other key frame, where the matched nodes' λ is 0) to its λ at t_c.
      const std::vector<PhaseNode> others(nodes.begin(), nodes.begin() + static_cast<std::ptrdiff_t>(matched));
      const double r = pr.cancel ? smoothstep01(t, g.t1, pr.tc) : smoothstep01(t, g.t0, pr.tc);
      const cplx at_tc(0, pr.cancel ? ph.turn.back() : ph.turn.front());
      nodes.push_back({pr.mid, r * at_tc + (1 - r) * cplx(0, lambda_at(others, g.radius, pr.mid).imag())});
    }
  }
  return nodes;
}

// Fills h₀, log q and λ of a guide whose tracks, pairs and times are set; false when a
// key frame's field has a zero the factors do not (then the interval is left to the
// regions and the solve).
bool build_guide(const DesignSpace& space, const std::vector<Track>& tracks, const std::vector<cplx>& f0,
                 const std::vector<cplx>& f1, Guide& g) {
  const Mesh& mesh = space.mesh();
  const TangentBundle& bundle = space.bundle();
  const auto nv = static_cast<size_t>(mesh.num_vertices());
  std::vector<std::vector<size_t>> nbr(nv);
  for (int h = 0; h < mesh.num_halfedges(); ++h) {
    const auto a = static_cast<size_t>(mesh.tail(h)), b = static_cast<size_t>(mesh.head(h));
    nbr[a].push_back(b);
    nbr[b].push_back(a);
  }
  const double tiny = 1e-9 * mesh.mean_edge_length();
  std::vector<cplx> hk[2];
  for (int e = 0; e < 2; ++e) {
    const std::vector<cplx>& f = e == 0 ? f0 : f1;
    const std::vector<Factor> factors = guide_factors(space, tracks, g, e == 0 ? g.t0 : g.t1);
    std::vector<cplx>& h = hk[e];
    h.assign(nv, cplx(0, 0));
    std::vector<char> ok(nv, 0);
    for (size_t v = 0; v < nv; ++v) {
      const cplx z = flat(mesh.position(static_cast<int>(v)));
      const cplx fv = flat(bundle.vertex_to_world(static_cast<int>(v), f[v]));
      cplx prod{1, 0};
      bool on_zero = false;
      for (const Factor& fa : factors) {
        on_zero = on_zero || (!fa.pair && std::abs(z - fa.p) <= tiny);
        prod *= fa(z);
      }
      if (on_zero || std::abs(fv) == 0 || !(std::abs(prod) > 0) || !std::isfinite(std::abs(prod))) continue;
      h[v] = fv / prod;
      ok[v] = 1;
    }
    // A vertex on a zero: the mean of its neighbours' h (h is smooth there).
    if (!fill_from_neighbours(nbr, h, ok)) return false;
  }
  // log(h₁/h₀), its argument lifted continuously along the mesh's edges.
  g.h0 = hk[0];
  g.log_q.assign(nv, cplx(0, 0));
  std::vector<char> seen(nv, 0);
  double sum_arg = 0;
  for (size_t root = 0; root < nv; ++root) {
    if (seen[root]) continue;
    std::vector<size_t> queue{root};
    seen[root] = 1;
    const cplx q0 = hk[1][root] / hk[0][root];
    g.log_q[root] = {std::log(std::abs(q0)), std::arg(q0)};
    for (size_t k = 0; k < queue.size(); ++k) {
      const size_t v = queue[k];
      const cplx qv = hk[1][v] / hk[0][v];
      for (const size_t w : nbr[v]) {
        if (seen[w]) continue;
        seen[w] = 1;
        const cplx qw = hk[1][w] / hk[0][w];
        g.log_q[w] = {std::log(std::abs(qw)), g.log_q[v].imag() + std::arg(qw / qv)};
        queue.push_back(w);
      }
    }
  }
  for (const cplx& l : g.log_q) sum_arg += l.imag();
  // The far field turns the shorter way: the mean lifted argument within (−π, π].
  const double shift = 2 * std::numbers::pi * std::round(sum_arg / static_cast<double>(nv) / (2 * std::numbers::pi));
  for (cplx& l : g.log_q) l -= cplx(0, shift);
  // λ of the matched tracks.
  g.lambda.assign(g.last - g.first, {});
  std::vector<std::vector<cplx>> logc(g.last - g.first);
  for (int k = 0; k <= Guide::kTable; ++k) {
    const double t = g.t0 + (g.t1 - g.t0) * k / Guide::kTable;
    const double u = g.ease.at(t, g.t0, g.t1);
    const std::vector<Factor> factors = guide_factors(space, tracks, g, t);
    for (const Factor& fa : factors) {
      if (fa.track < 0) continue;
      const Vec3 p(fa.p.real(), fa.p.imag(), 0);
      cplx c = guide_h(mesh, g, space.locate(p), u);
      for (const Factor& other : factors)
        if (&other != &fa) c *= other(fa.p);
      if (!(std::abs(c) > 0) || !std::isfinite(std::abs(c))) return false;  // two zeros on one point
      std::vector<cplx>& l = logc[static_cast<size_t>(fa.track)];
      const double arg = l.empty() ? std::arg(c) : l.back().imag() + std::remainder(std::arg(c) - l.back().imag(), 2 * std::numbers::pi);
      l.emplace_back(std::log(std::abs(c)), arg);
    }
  }
  for (size_t i = 0; i < logc.size(); ++i) {
    if (logc[i].empty()) continue;
    std::vector<cplx>& lam = g.lambda[i];
    for (int k = 0; k <= Guide::kTable; ++k) {
      const double u = g.ease(static_cast<double>(k) / Guide::kTable);
      // The ends' values taken within (−π, π]: the whole turns in between are what the
      // correction takes out (at the ends exp(−λ) is then 1).
      const cplx a = logc[i].front(), b = logc[i].back();
      const cplx a0(a.real(), std::remainder(a.imag(), 2 * std::numbers::pi));
      const cplx b0(b.real(), std::remainder(b.imag(), 2 * std::numbers::pi));
      lam.push_back(logc[i][static_cast<size_t>(k)] - ((1 - u) * a0 + u * b0));
    }
  }
  // The pairs' nodes: the argument of G's α at the node (G without Λ, as for the matched
  // nodes' c; α by central differences: G(p + ε) ≈ αε + β conj ε), unwrapped, less its
  // value at the key frame where the pair is (there G is that key frame, whose type the
  // node keeps).
  const double delta = 1e-4 * mesh.mean_edge_length();
  g.pair_phase.assign(g.pairs.size(), {});
  for (size_t q = 0; q < g.pairs.size(); ++q) {
    const Guide::Pair& pr = g.pairs[q];
    Guide::PairPhase& ph = g.pair_phase[q];
    ph.a = pr.cancel ? g.t0 : pr.tc;
    ph.b = pr.cancel ? pr.tc : g.t1;
    std::vector<double> arg;
    for (int k = 0; k <= Guide::kTable; ++k) {
      const double t = ph.a + (ph.b - ph.a) * k / Guide::kTable;
      const std::vector<Factor> factors = guide_factors(space, tracks, g, t);
      const double u = g.ease.at(t, g.t0, g.t1);
      const cplx p = pair_node(tracks, pr, t).value_or(pr.mid);
      auto value = [&](cplx z) {
        cplx val = guide_h(mesh, g, space.locate(Vec3(z.real(), z.imag(), 0)), u);
        for (const Factor& fa : factors) val *= fa(z);
        return val;
      };
      const cplx alpha = ((value(p + delta) - value(p - delta)) - cplx(0, 1) * (value(p + cplx(0, delta)) - value(p - cplx(0, delta)))) /
                         (4 * delta);
      if (!(std::abs(alpha) > 0) || !std::isfinite(std::abs(alpha))) {
        arg.clear();
        break;
      }
      arg.push_back(arg.empty() ? std::arg(alpha) : arg.back() + std::remainder(std::arg(alpha) - arg.back(), 2 * std::numbers::pi));
    }
    if (arg.empty()) continue;
    const double key = pr.cancel ? arg.front() : arg.back();
    for (const double a : arg) ph.turn.push_back(a - key);
  }
  return true;
}

// Fixes every free vertex of a frame at time t (strictly inside the guide's interval) to G.
void apply_guide(const DesignSpace& space, const std::vector<Track>& tracks, const Guide& g, double t,
                 std::span<char> fixed, std::span<cplx> values) {
  const Mesh& mesh = space.mesh();
  const TangentBundle& bundle = space.bundle();
  const std::vector<Factor> factors = guide_factors(space, tracks, g, t);
  const double u = g.ease.at(t, g.t0, g.t1);
  const std::vector<PhaseNode> nodes = phase_nodes(tracks, g, factors, t);
  // The tracks' own linear fields within `outer` (G's nonlinear terms matter farther out
  // for a weak saddle): the whole face around the point inside `inner`.
  const double h = mesh.mean_edge_length();
  const double inner = std::min(0.7 * g.radius, 1.5 * h), outer = std::min(g.radius, 2.5 * h);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const auto vi = static_cast<size_t>(v);
    if (fixed[vi]) continue;
    const cplx z = flat(mesh.position(v));
    cplx val = g.h0[vi] * std::exp(u * g.log_q[vi]);
    size_t nearest = factors.size();
    double rn = std::numeric_limits<double>::infinity();
    for (size_t m = 0; m < factors.size(); ++m) {
      val *= factors[m](z);
      if (factors[m].track < 0) continue;
      const double r = std::abs(z - factors[m].p);
      if (r < rn) rn = r, nearest = m;
    }
    val *= std::exp(-lambda_at(nodes, g.radius, z));
    if (nearest < factors.size() && factors[nearest].index > 0 && rn < outer) {
      const double w = rn <= inner ? 1.0 : smoothstep01(rn, outer, inner);
      val = w * factors[nearest](z) + (1 - w) * val;
    }
    fixed[vi] = 1;
    values[vi] = bundle.world_to_vertex(v, Vec3(val.real(), val.imag(), 0));
  }
}

// The pairs' holds turn G by Λ, which then varies between a pair's node and the matched
// nodes near it by what each turned (a sink passing round a cancelled pair's source: 2.1
// against −1.6 radians about 0.3 apart), and where G is small (round a template) the
// piecewise-linear field then holds extra zeros. So they are kept only where they do no
// harm, by measurement as on surfaces: G with and without them at 31 times, the holds
// dropped when their frames hold other than the plan's zeros more often.
void keep_pair_phase_if_resolved(const DesignSpace& space, const std::vector<Track>& tracks, Guide& g) {
  if (std::all_of(g.pair_phase.begin(), g.pair_phase.end(), [](const Guide::PairPhase& ph) { return ph.turn.empty(); }))
    return;
  const auto nv = static_cast<size_t>(space.mesh().num_vertices());
  auto wrong_frames = [&](const Guide& guide) {
    int wrong = 0;
    for (int k = 1; k < 32; ++k) {
      const double t = guide.t0 + (guide.t1 - guide.t0) * k / 32.0;
      size_t planned = guide.last - guide.first;
      for (const Guide::Pair& pr : guide.pairs) planned -= pair_node(tracks, pr, t) ? 0 : 2;
      std::vector<char> fixed(nv, 0);
      std::vector<cplx> values(nv, cplx(0, 0));
      apply_guide(space, tracks, guide, t, fixed, values);
      if (find_singularities(space.bundle(), values).size() != planned) ++wrong;
    }
    return wrong;
  };
  Guide plain = g;
  plain.pair_phase.clear();
  if (wrong_frames(g) > wrong_frames(plain)) g.pair_phase.clear();
}

using SurfaceGuide = KeyframeTopologyPlan::SurfaceGuide;

// A point of the surface in a chart (its face's corners' coordinates, barycentric); NaN
// when a corner is beyond the chart's patch.
cplx chart_point(const Mesh& mesh, const std::vector<cplx>& coords, const SurfacePoint& at) {
  cplx z{0, 0};
  for (int k = 0; k < 3; ++k) {
    const cplx c = coords[static_cast<size_t>(mesh.face(at.face)[static_cast<size_t>(k)])];
    if (!std::isfinite(c.real()) || !std::isfinite(c.imag())) return {std::nan(""), 0};
    z += at.bary[k] * c;
  }
  return z;
}

// The surface point at chart point z: the face of the chart's patch whose chart triangle
// holds z (barycentric), or the one nearest to holding it (largest smallest barycentric
// coordinate). Empty when no face is in the patch.
std::optional<SurfacePoint> chart_locate(const Mesh& mesh, const std::vector<cplx>& coords, cplx z) {
  std::optional<SurfacePoint> best;
  double best_min = -std::numeric_limits<double>::infinity();
  for (int f = 0; f < mesh.num_faces(); ++f) {
    std::array<cplx, 3> c;
    bool in = true;
    for (int k = 0; k < 3; ++k) {
      c[static_cast<size_t>(k)] = coords[static_cast<size_t>(mesh.face(f)[static_cast<size_t>(k)])];
      in = in && std::isfinite(c[static_cast<size_t>(k)].real()) && std::isfinite(c[static_cast<size_t>(k)].imag());
    }
    if (!in) continue;
    const cplx e1 = c[1] - c[0], e2 = c[2] - c[0], d = z - c[0];
    const double det = e1.real() * e2.imag() - e1.imag() * e2.real();
    if (det == 0) continue;
    const double b1 = (d.real() * e2.imag() - d.imag() * e2.real()) / det;
    const double b2 = (e1.real() * d.imag() - e1.imag() * d.real()) / det;
    const double b0 = 1 - b1 - b2;
    const double lo = std::min({b0, b1, b2});
    if (lo > best_min) {
      best_min = lo;
      best = SurfacePoint{f, Vec3(b0, b1, b2)};
      if (lo >= 0) break;
    }
  }
  return best;
}

// A linear map's value at w: αw + β conj w.
cplx apply_linear(const Linear& l, cplx w) { return l.alpha * w + l.beta * std::conj(w); }

// A sum of arguments along a sampled curve, d(0), d(1), …, kept so that it can be carried
// on to a later sample (the acceptance check's frames, in time order, extend each vertex's
// sum instead of summing again from d(0): the same additions in the same order, so the same
// value to the bit). `k` is the last sample summed, `prev` its value.
struct ArgSum {
  size_t k = 0;
  double angle = 0;
  cplx prev{0, 0};
  double log_d0 = 0;  // log |d(0)|
};

// Starts a sum at d(0), or carries it on to sample `last` (from d(0) again when it is past
// `last`), `d(k)` the curve's k-th sample; then log(d_end / d(0)), its argument the sum's
// plus d_end's turn from d(last).
template <typename D>
cplx arg_sum_log(ArgSum& sum, bool started, size_t last, D&& d, cplx d_end) {
  if (!started || sum.k > last) {
    sum.k = 0;
    sum.angle = 0;
    sum.prev = d(size_t{0});
    sum.log_d0 = std::log(std::abs(sum.prev));
  }
  for (size_t k = sum.k + 1; k <= last; ++k) {
    const cplx next = d(k);
    sum.angle += std::arg(next / sum.prev);
    sum.prev = next;
  }
  sum.k = std::max(sum.k, last);
  return {std::log(std::abs(d_end)) - sum.log_d0, sum.angle + std::arg(d_end / sum.prev)};
}

// The last sample at or before parameter s of a path sampled at x[k], s = k / (x.size() − 1).
size_t path_last(const std::vector<cplx>& x, double s) {
  const auto n = static_cast<double>(x.size() - 1);
  return std::min(static_cast<size_t>(std::max(s, 0.0) * n), x.size() - 1);
}

// log((z − x(s)) / (z − x(0))) for a path sampled at x[k] ending at `end` = x(s): the
// argument is the angle the path subtends at z, so the value is continuous in z off the
// path (and jumps by 2πi across it, where exp does not see it). With the linear parts `a`
// (a[k] at x[k], `a_end` at `end`; empty: the identity): log(A(s)(z − x(s)) / A(0)(z − x(0))),
// its argument summed over the steps likewise. `sum`, `started`: as arg_sum_log's.
cplx log_ratio(ArgSum& sum, bool started, cplx z, const std::vector<cplx>& x, const std::vector<Linear>& a, double s,
               cplx end, const Linear& a_end) {
  auto at = [&](size_t k) { return a.empty() ? z - x[k] : apply_linear(a[k], z - x[k]); };
  const cplx d_end = a.empty() ? z - end : apply_linear(a_end, z - end);
  return arg_sum_log(sum, started, path_last(x, s), at, d_end);
}

// A pair's Q at chart point z.
cplx pair_q(const SurfaceGuide::Path& p, const SurfaceGuide::PairState& q, cplx z) {
  if (q.linear) return (z - q.n) * std::conj(z - q.s);
  const cplx w = (z - p.mid) * std::conj(p.axis);
  return {std::norm(w) + q.mu, 2 * p.sigma * w.imag()};
}

// A pair's Q at time t: its tracks' points in the chart while they hold (the node's and
// the saddle's linear factors), else the template's μ (the tracks end on its zeros at
// μ = −σ², so Q is continuous there).
SurfaceGuide::PairState pair_state(const DesignSpace& space, const std::vector<Track>& tracks,
                                   const SurfaceGuide::Path& p, double t) {
  const double a = p.tc - p.tau, b = p.tc + p.tau;
  SurfaceGuide::PairState q;
  if (p.cancel ? t < a : t > b) {
    const Track &n = tracks[p.track], &sd = tracks[p.saddle];
    q.linear = true;
    q.n = chart_point(space.mesh(), p.coords, space.locate(n.raw(n.param(t))));
    q.s = chart_point(space.mesh(), p.coords, space.locate(sd.raw(sd.param(t))));
    return q;
  }
  const double u = smoothstep01(t, a, b);
  q.mu = p.sigma * p.sigma * (p.cancel ? 2 * u - 1 : 1 - 2 * u);
  return q;
}

// log(Q(z, t) / Q(z, t₀)) for the state `now` at time t: the argument is Q's turn summed
// over the tabled times up to t (continuous in z off the zeros' sweep, as log_ratio is
// off the path).
cplx pair_log(ArgSum& sum, bool started, const SurfaceGuide& g, const SurfaceGuide::Path& p, cplx z, double t,
              const SurfaceGuide::PairState& now) {
  const double x = std::clamp((t - g.t0) / (g.t1 - g.t0), 0.0, 1.0) * SurfaceGuide::kSamples;
  const auto last = std::min(static_cast<size_t>(x), p.states.size() - 1);
  return arg_sum_log(sum, started, last, [&](size_t k) { return pair_q(p, p.states[k], z); }, pair_q(p, now, z));
}

// What a path's factor needs at time t: a track's point on its path (parameter and chart
// point), or a pair's state.
struct PathNow {
  double t = 0, s = 0;
  cplx end{0, 0};
  Linear a;  // the track's linear part in the chart at `end` (with the path's `a`)
  SurfaceGuide::PairState q;
};

// The chart's linear map (face frame to chart) on face f; none when a corner is off the
// chart's patch or the face is degenerate.
std::optional<Mat2> chart_map(const DesignSpace& space, const std::vector<cplx>& coords, int f) {
  const Mesh& mesh = space.mesh();
  const TangentBundle& bundle = space.bundle();
  const Vec3& x0 = mesh.position(mesh.face(f)[0]);
  const cplx c0 = coords[static_cast<size_t>(mesh.face(f)[0])];
  Mat2 Y, Z;
  for (int c = 1; c < 3; ++c) {
    const Vec3 d = mesh.position(mesh.face(f)[static_cast<size_t>(c)]) - x0;
    Y.col(c - 1) = Vec2(d.dot(bundle.face_e1(f)), d.dot(bundle.face_e2(f)));
    const cplx dz = coords[static_cast<size_t>(mesh.face(f)[static_cast<size_t>(c)])] - c0;
    if (!std::isfinite(dz.real()) || !std::isfinite(dz.imag())) return std::nullopt;
    Z.col(c - 1) = Vec2(dz.real(), dz.imag());
  }
  if (Y.determinant() == 0 || Z.determinant() == 0) return std::nullopt;
  return Z * Y.inverse();
}

// The track's J at time t in the chart, M J M⁻¹ on the face holding its point; none where
// the chart has no map there or J's determinant is not of the track's index's sign.
std::optional<Linear> chart_jacobian(const DesignSpace& space, const Track& tr, const std::vector<cplx>& coords,
                                     double t, int f) {
  const std::optional<Mat2> m = chart_map(space, coords, f);
  if (!m) return std::nullopt;
  const Mat2 j = to_matrix(track_jacobian(space.bundle(), tr, t, f));
  const Mat2 a = *m * j * m->inverse();
  const double det = a.determinant();
  if (!std::isfinite(det) || det * tr.index <= 0) return std::nullopt;
  // Its shape only: divided by its dominant coefficient (α for a node, β for a saddle), so
  // that far from the path the ratio tends to 1 and does not turn the tube's phase as J
  // turns (a node changing stability): the type is Λ's to hold, as before.
  const Linear l = to_linear(a);
  const cplx d = tr.index > 0 ? l.alpha : l.beta;
  return Linear{l.alpha / d, l.beta / d};
}

// The time at which a track's path parameter (its warp of time, Ease) is s (bisection).
double time_at(const Track& tr, double s) {
  double lo = tr.t0, hi = tr.t1;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (tr.param(mid) < s ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

PathNow path_now(const DesignSpace& space, const std::vector<Track>& tracks, const SurfaceGuide::Path& path,
                 double t) {
  PathNow now;
  now.t = t;
  if (path.pair) {
    now.q = pair_state(space, tracks, path, t);
    return now;
  }
  const Track& tr = tracks[path.track];
  now.s = tr.param(t);
  const SurfacePoint at = space.locate(tr.raw(now.s));
  now.end = chart_point(space.mesh(), path.coords, at);
  if (!path.a.empty()) {
    // Off the chart's map (not seen: the path's samples all have one): the nearest sample's.
    const auto k = std::min(static_cast<size_t>(std::lround(now.s * SurfaceGuide::kSamples)), path.a.size() - 1);
    now.a = chart_jacobian(space, tr, path.coords, t, at.face).value_or(path.a[k]);
  }
  return now;
}

// w log(factor) at the path's m-th support vertex (`sum`: its argument sum so far, when
// `started`).
cplx path_log(ArgSum& sum, bool started, const SurfaceGuide& g, const SurfaceGuide::Path& path, size_t m,
              const PathNow& now) {
  const cplx z = path.coords[path.support[m]];
  if (path.pair) return path.w[m] * pair_log(sum, started, g, path, z, now.t, now.q);
  const cplx l = path.w[m] * log_ratio(sum, started, z, path.x, path.a, now.s, now.end, now.a);
  return path.conj && path.a.empty() ? std::conj(l) : l;
}

cplx path_log(const SurfaceGuide& g, const SurfaceGuide::Path& path, size_t m, const PathNow& now) {
  ArgSum sum;
  return path_log(sum, false, g, path, m, now);
}

// Σ_j w_j log(factor_j) at every vertex, the factors at time t.
std::vector<cplx> surface_log_factors(const DesignSpace& space, const std::vector<Track>& tracks,
                                      const SurfaceGuide& g, double t) {
  std::vector<cplx> out(static_cast<size_t>(space.mesh().num_vertices()), cplx(0, 0));
  for (const SurfaceGuide::Path& path : g.paths) {
    const PathNow now = path_now(space, tracks, path, t);
    for (size_t m = 0; m < path.support.size(); ++m) out[path.support[m]] += path_log(g, path, m, now);
  }
  return out;
}

// The same at a series of times, each vertex's argument sums carried on from the last
// time's (cheapest in time order; the values are surface_log_factors's to the bit).
class SurfaceLogSweep {
 public:
  explicit SurfaceLogSweep(const SurfaceGuide& g) : g_(g), sums_(g.paths.size()) {
    for (size_t j = 0; j < g.paths.size(); ++j) sums_[j].resize(g.paths[j].support.size());
  }
  void at(const DesignSpace& space, const std::vector<Track>& tracks, double t, std::vector<cplx>& out) {
    out.assign(static_cast<size_t>(space.mesh().num_vertices()), cplx(0, 0));
    for (size_t j = 0; j < g_.paths.size(); ++j) {
      const SurfaceGuide::Path& path = g_.paths[j];
      const PathNow now = path_now(space, tracks, path, t);
      for (size_t m = 0; m < path.support.size(); ++m)
        out[path.support[m]] += path_log(sums_[j][m], started_, g_, path, m, now);
    }
    started_ = true;
  }

 private:
  const SurfaceGuide& g_;
  std::vector<std::vector<ArgSum>> sums_;
  bool started_ = false;
};

// Makes g's frame logs at `times` (ascending).
void keep_frame_logs(const DesignSpace& space, const std::vector<Track>& tracks, SurfaceGuide& g,
                     std::span<const double> times) {
  auto logs = std::make_shared<SurfaceGuide::FrameLogs>();
  for (const SurfaceGuide::Path& p : g.paths) logs->tube.insert(logs->tube.end(), p.support.begin(), p.support.end());
  std::sort(logs->tube.begin(), logs->tube.end());
  logs->tube.erase(std::unique(logs->tube.begin(), logs->tube.end()), logs->tube.end());
  logs->t.assign(times.begin(), times.end());
  logs->log.assign(times.size(), {});
  SurfaceLogSweep sweep(g);
  std::vector<cplx> l;
  for (size_t i = 0; i < times.size(); ++i) {
    sweep.at(space, tracks, times[i], l);
    logs->log[i].reserve(logs->tube.size());
    for (const size_t v : logs->tube) logs->log[i].push_back(l[v]);
  }
  g.logs = std::move(logs);
}

// g's log factors at its i-th frame, at every vertex.
void frame_logs(const SurfaceGuide& g, size_t i, size_t nv, std::vector<cplx>& out) {
  out.assign(nv, cplx(0, 0));
  const SurfaceGuide::FrameLogs& logs = *g.logs;
  for (size_t j = 0; j < logs.tube.size(); ++j) out[logs.tube[j]] = logs.log[i][j];
}

// A vertex on a pole of the ratio (a key frame's zero placed on it: F₀ / (z − p(t₀)) is 0/0
// there) takes the value at it of the affine field that fits its neighbours' values best
// (least squares in its tangent plane: G is smooth there, and its zero p(t) may be within an
// edge of it, next to the key frame, where their mean is far off). `value_at(w)`: a
// neighbour's value in its own frame, or none. Fewer than three neighbours with a value, or
// all on a line: their mean; none: no value.
std::optional<cplx> affine_fill(const Mesh& mesh, const TangentBundle& bundle, int v,
                                const std::function<std::optional<cplx>(int)>& value_at) {
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d re = Eigen::Vector3d::Zero(), im = Eigen::Vector3d::Zero();
  Vec3 sum = Vec3::Zero();
  int count = 0;
  for (const int out : mesh.outgoing(v))
    for (const int w : {mesh.head(out), mesh.tail(Mesh::prev(out))}) {
      const std::optional<cplx> value = value_at(w);
      if (!value) continue;
      const Vec3 world = bundle.vertex_to_world(w, *value);
      sum += world;
      ++count;
      const cplx d = bundle.world_to_vertex(v, mesh.position(w) - mesh.position(v));
      const cplx gw = bundle.world_to_vertex(v, world);
      const Eigen::Vector3d row(1, d.real(), d.imag());
      normal += row * row.transpose();
      re += gw.real() * row;
      im += gw.imag() * row;
    }
  if (count == 0) return std::nullopt;
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(normal);
  const double scale = normal.diagonal().maxCoeff();
  if (count >= 3 && ldlt.info() == Eigen::Success && ldlt.vectorD().minCoeff() > 1e-9 * scale)
    return cplx(ldlt.solve(re)(0), ldlt.solve(im)(0));
  return bundle.world_to_vertex(v, sum / count);
}

// G at the corners of face f at time t (before the phase correction), in the face's frame;
// a corner on a pole of the ratio (next to the first key frame) filled as apply_surface_guide
// fills it (affine_fill), so that the nodes' λ and scale have values there too.
std::array<cplx, 3> surface_guide_on_face(const DesignSpace& space, const std::vector<Track>& tracks,
                                          const SurfaceGuide& g, double t, int f) {
  const Mesh& mesh = space.mesh();
  const double u = g.ease.at(t, g.t0, g.t1);
  std::vector<PathNow> now;
  for (const SurfaceGuide::Path& path : g.paths) now.push_back(path_now(space, tracks, path, t));
  // G at vertex v, in its frame (non-finite on a pole).
  auto at_vertex = [&](size_t v) {
    cplx l = u * g.log_h[v];
    for (size_t j = 0; j < g.paths.size(); ++j) {
      const SurfaceGuide::Path& path = g.paths[j];
      const auto it = std::lower_bound(path.support.begin(), path.support.end(), v);
      if (it == path.support.end() || *it != v) continue;
      l += path_log(g, path, static_cast<size_t>(it - path.support.begin()), now[j]);
    }
    return g.f0[v] * std::exp(l);
  };
  auto finite = [](cplx z) { return std::isfinite(z.real()) && std::isfinite(z.imag()); };
  std::array<cplx, 3> out;
  for (int c = 0; c < 3; ++c) {
    const int v = mesh.face(f)[static_cast<size_t>(c)];
    cplx value = at_vertex(static_cast<size_t>(v));
    if (!finite(value)) {
      const std::optional<cplx> filled = affine_fill(mesh, space.bundle(), v, [&](int w) -> std::optional<cplx> {
        const cplx gw = at_vertex(static_cast<size_t>(w));
        return finite(gw) ? std::optional<cplx>(gw) : std::nullopt;
      });
      if (filled) value = *filled;
    }
    out[static_cast<size_t>(c)] = space.bundle().corner_to_face(3 * f + c) * value;
  }
  return out;
}

// The α of the linear interpolant of face values w (in the face frame) over face f.
cplx face_alpha(const DesignSpace& space, int f, const std::array<cplx, 3>& w) {
  const Mesh& mesh = space.mesh();
  const TangentBundle& bundle = space.bundle();
  const Vec3& x0 = mesh.position(mesh.face(f)[0]);
  Mat2 Y, W;
  for (int c = 1; c < 3; ++c) {
    const Vec3 d = mesh.position(mesh.face(f)[static_cast<size_t>(c)]) - x0;
    Y.col(c - 1) = Vec2(d.dot(bundle.face_e1(f)), d.dot(bundle.face_e2(f)));
    const cplx dw = w[static_cast<size_t>(c)] - w[0];
    W.col(c - 1) = Vec2(dw.real(), dw.imag());
  }
  return to_linear(W * Y.inverse()).alpha;
}

// A chart that follows the path, for a tube no plane fits (a thin or crumpled part of
// the surface, where the faces within an edge length of the path already face away from
// any one plane): the faces whose corners all lie within `out_r` of the path, when those
// joined to `start_face` form a disk, mapped by Tutte's embedding with Floater's
// mean-value weights, the disk's boundary laid on an ellipse whose long axis runs from
// the boundary vertex nearest `from` to the one nearest `to` (boundary length kept in
// proportion along each side). Positive weights and a convex boundary make the map one to
// one (Floater 2003), and it is linear on every face as the projection is, so a factor's
// zero is where the face's linear interpolant has it and F₀ / (z − p(t₀)) has no noise.
// Returns the coordinates (+∞ off the disk), or none when the faces are not a disk.
std::vector<cplx> follow_chart(const Mesh& mesh, const std::vector<double>& dist, double out_r, int start_face,
                               const Vec3& from, const Vec3& to) {
  const auto nv = static_cast<size_t>(mesh.num_vertices());
  const auto nf = static_cast<size_t>(mesh.num_faces());
  auto inside = [&](size_t f) {
    const Face& c = mesh.face(static_cast<int>(f));
    return dist[static_cast<size_t>(c[0])] < out_r && dist[static_cast<size_t>(c[1])] < out_r &&
           dist[static_cast<size_t>(c[2])] < out_r;
  };
  if (start_face < 0 || !inside(static_cast<size_t>(start_face))) return {};
  std::vector<char> in(nf, 0);
  std::vector<int> faces{start_face};
  in[static_cast<size_t>(start_face)] = 1;
  for (size_t k = 0; k < faces.size(); ++k)
    for (int c = 0; c < 3; ++c) {
      const int t = mesh.twin(3 * faces[k] + c);
      if (t < 0) continue;
      const auto g = static_cast<size_t>(Mesh::face_of(t));
      if (!in[g] && inside(g)) in[g] = 1, faces.push_back(static_cast<int>(g));
    }
  // A disk: V − E + F = 1 and one boundary loop (no vertex with two boundary edges out).
  std::vector<int> local(nv, -1), out_of(nv, -1), boundary;
  size_t nverts = 0, interior_halfedges = 0;
  for (const int f : faces)
    for (int c = 0; c < 3; ++c) {
      const int h = 3 * f + c;
      const auto v = static_cast<size_t>(mesh.tail(h));
      if (local[v] < 0) local[v] = static_cast<int>(nverts++);
      const int t = mesh.twin(h);
      if (t >= 0 && in[static_cast<size_t>(Mesh::face_of(t))]) {
        ++interior_halfedges;
        continue;
      }
      if (out_of[v] >= 0) return {};
      out_of[v] = h;
      boundary.push_back(h);
    }
  const size_t edges = boundary.size() + interior_halfedges / 2;
  if (boundary.size() < 3 || nverts + faces.size() != edges + 1) return {};
  std::vector<int> loop{mesh.tail(boundary.front())};
  for (int h = out_of[static_cast<size_t>(mesh.head(boundary.front()))]; mesh.tail(h) != loop.front();
       h = out_of[static_cast<size_t>(mesh.head(h))]) {
    loop.push_back(mesh.tail(h));
    if (loop.size() > boundary.size()) return {};
  }
  if (loop.size() != boundary.size()) return {};
  // The boundary on the ellipse, counter-clockwise (the faces' orientation).
  auto nearest = [&](const Vec3& x) {
    size_t best = 0;
    for (size_t k = 1; k < loop.size(); ++k)
      if ((mesh.position(loop[k]) - x).squaredNorm() < (mesh.position(loop[best]) - x).squaredNorm()) best = k;
    return best;
  };
  const size_t a = nearest(from), b = nearest(to), n = loop.size();
  std::vector<double> along(n + 1, 0);  // boundary length from a
  for (size_t k = 0; k < n; ++k)
    along[k + 1] = along[k] + (mesh.position(loop[(a + k + 1) % n]) - mesh.position(loop[(a + k) % n])).norm();
  const size_t mid = (b + n - a) % n;  // b's place after a
  const double half = 0.5 * (from - to).norm() + out_r, width = out_r;
  std::vector<cplx> coords(nv, cplx(std::numeric_limits<double>::infinity(), 0));
  for (size_t k = 0; k < n; ++k) {
    double angle = 0;
    if (mid == 0)
      angle = std::numbers::pi + 2 * std::numbers::pi * along[k] / along[n];
    else if (k <= mid)
      angle = std::numbers::pi + std::numbers::pi * along[k] / along[mid];
    else
      angle = std::numbers::pi * (along[k] - along[mid]) / (along[n] - along[mid]);
    coords[static_cast<size_t>(loop[(a + k) % n])] = {half * std::cos(angle), width * std::sin(angle)};
  }
  // The interior: Σ_j w_ij (z_i − z_j) = 0, w_ij = (tan(θ₁/2) + tan(θ₂/2)) / |x_j − x_i|.
  std::vector<int> unknown(nv, -1);
  size_t nu = 0;
  for (size_t v = 0; v < nv; ++v)
    if (local[v] >= 0 && out_of[v] < 0) unknown[v] = static_cast<int>(nu++);
  if (nu > 0) {
    std::vector<Eigen::Triplet<double>> entries;
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(nu), 2);
    for (const int f : faces)
      for (int c = 0; c < 3; ++c) {
        const int h = 3 * f + c;
        const auto i = static_cast<size_t>(mesh.tail(h));
        if (unknown[i] < 0) continue;
        const double t = std::tan(0.5 * mesh.corner_angle(h));
        for (const int j : {mesh.head(h), mesh.tail(Mesh::prev(h))}) {
          const double w = t / (mesh.position(j) - mesh.position(static_cast<int>(i))).norm();
          entries.emplace_back(unknown[i], unknown[i], w);
          const auto ju = static_cast<size_t>(j);
          if (unknown[ju] >= 0) {
            entries.emplace_back(unknown[i], unknown[ju], -w);
          } else {
            rhs(unknown[i], 0) += w * coords[ju].real();
            rhs(unknown[i], 1) += w * coords[ju].imag();
          }
        }
      }
    Eigen::SparseMatrix<double> m(static_cast<Eigen::Index>(nu), static_cast<Eigen::Index>(nu));
    m.setFromTriplets(entries.begin(), entries.end());
    Eigen::SparseLU<Eigen::SparseMatrix<double>> lu(m);
    if (lu.info() != Eigen::Success) return {};
    const Eigen::MatrixXd z = lu.solve(rhs);
    for (size_t v = 0; v < nv; ++v)
      if (unknown[v] >= 0) coords[v] = {z(unknown[v], 0), z(unknown[v], 1)};
  }
  // One to one in exact arithmetic; checked in floating point.
  for (const int f : faces) {
    const Face& c = mesh.face(f);
    const cplx p = coords[static_cast<size_t>(c[1])] - coords[static_cast<size_t>(c[0])];
    const cplx q = coords[static_cast<size_t>(c[2])] - coords[static_cast<size_t>(c[0])];
    if (!(p.real() * q.imag() - p.imag() * q.real() > 0)) return {};
  }
  return coords;
}

// A sampled path or curve leaves the surface where two consecutive samples' surface points
// are more than this many mean edge lengths apart (its largest step, below): a path's
// samples are a few hundredths of an edge length apart where they stay on the surface.
constexpr double kSurfaceJumpEdges = 2;

// The largest distance between consecutive points.
double largest_step(const std::vector<Vec3>& points) {
  double out = 0;
  for (size_t k = 0; k + 1 < points.size(); ++k) out = std::max(out, (points[k + 1] - points[k]).norm());
  return out;
}

// Why a track's path is no curve on the surface, in one sentence (empty when it is): its
// points at kSamples + 1 parameters, `on` (snapped to the surface), jump more than two edge
// lengths between two of them. The path's curve (surface_curve) is on the surface, so this
// fires only where no edge path joined its ends (the straight segment then runs through
// the solid, and its nearest surface points jump across, as every path's did through
// CGAL's elephant's leg before the paths were curves on it), or where a long detour walked
// across a thin part is not continuous along the path (the walk passing a vertex or a
// fold on one side, then the other: 0.093 on an elephant, docs/benchmarks.md).
std::string leaves_surface(const DesignSpace& space, const Track& tr, const std::vector<SurfacePoint>& on) {
  const Mesh& mesh = space.mesh();
  const double h = mesh.mean_edge_length();
  std::vector<Vec3> points;
  for (const SurfacePoint& p : on) points.push_back(surface_position(mesh, p));
  const double jump = largest_step(points);
  if (jump <= kSurfaceJumpEdges * h) return {};
  return fmt::format("the {}'s path from {} to {} leaves the surface (its nearest surface points jump {:.2g}, "
                     "{:.0f} edge lengths, between two of its {} samples)",
                     to_string(tr.type), describe_point(tr.p0, false, 1), describe_point(tr.p1, false, 1), jump,
                     jump / h, on.size());
}

// A path's tube and chart (SurfaceGuide::Path before its `a`) by (a pair's, track or pair
// index, ramp): the same at every try with that ramp (the shaped ratio's tries reuse the
// plain ratio's tubes).
using TubeCache = std::map<std::tuple<bool, size_t, double>, KeyframeTopologyPlan::SurfaceGuide::Path>;

// Tabled samples with no value (NaN: G had none there) take the nearest earlier sample's,
// the leading ones the first valued one's (`none` when no sample has a value): the nodes'
// λ and scale, the pairs' holds' turns.
void fill_gaps(std::vector<double>& x, double none) {
  const auto it = std::find_if(x.begin(), x.end(), [](double y) { return !std::isnan(y); });
  double prev = it == x.end() ? none : *it;
  for (double& y : x) {
    if (std::isnan(y))
      y = prev;
    else
      prev = y;
  }
}

// Builds a surface guide for the tracks [first, last) (spanning [t0, t1]; the tracks of
// `pairs` are created or cancelled pairs', the others matched); false when a path leaves
// its chart or a key frame's field has a zero no track carries. `ramp` widens the band
// where the factors' weights fall from 1 to 0.
bool build_surface_guide(const DesignSpace& space, const std::vector<Track>& tracks, size_t first, size_t last,
                         const std::vector<Guide::Pair>& pairs, double radius, double ramp, bool shaped,
                         const std::vector<cplx>& f0, const std::vector<cplx>& f1, TubeCache& tubes,
                         SurfaceGuide& g, std::string& why) {
  const Mesh& mesh = space.mesh();
  const auto nv = static_cast<size_t>(mesh.num_vertices());
  const double h = mesh.mean_edge_length();
  const double inner = std::max(radius, 1.5 * h), outer = inner + ramp * std::max(radius, 2 * h);
  auto samples = [&](const Track& tr) {
    std::vector<SurfacePoint> on(SurfaceGuide::kSamples + 1);
    for (int k = 0; k <= SurfaceGuide::kSamples; ++k)
      on[static_cast<size_t>(k)] = space.locate(tr.raw(static_cast<double>(k) / SurfaceGuide::kSamples));
    return on;
  };
  // A path's chart and tube: the polylines `lines` on the surface (a track's path; a
  // pair's two and the segment between their ends), `mid` a point of them near their middle.
  auto make_tube = [&](SurfaceGuide::Path& path, const std::vector<std::vector<SurfacePoint>>& lines,
                       const SurfacePoint& mid) {
    const Vec3 centre = surface_position(mesh, mid);
    double reach = 0;
    for (const auto& on : lines)
      for (const SurfacePoint& p : on) reach = std::max(reach, (surface_position(mesh, p) - centre).norm());
    // The chart: the projection onto the plane through the path's middle normal to the
    // path's mean normal, linear on every face (so the factors' zeros and poles are where
    // the face's linear interpolant has them, and the quotient F₀ / (z − p(t₀)) has no
    // noise), on the vertices the log map puts within `outer` of the path, geodesically;
    // the faces there must face the plane's way (the projection is then one to one).
    Vec3 normal = Vec3::Zero();
    for (const auto& on : lines)
      for (const SurfacePoint& p : on) normal += space.bundle().face_normal(p.face);
    if (normal.norm() == 0) return false;
    normal.normalize();
    const Vec3 e1 = (std::abs(normal.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(normal).normalized();
    const Vec3 e2 = normal.cross(e1);
    auto project = [&](const Vec3& x) { return cplx((x - centre).dot(e1), (x - centre).dot(e2)); };
    std::vector<std::vector<Vec3>> world(lines.size());
    for (size_t l = 0; l < lines.size(); ++l)
      for (const SurfacePoint& p : lines[l]) world[l].push_back(surface_position(mesh, p));
    // The narrowest tube tried: an edge length where the path runs (the mean of the edges of
    // the faces holding it), not the mesh's mean. A scanned mesh is finer where it is
    // curved (CGAL's cow at a static saddle: faces of 0.3 mean edge lengths, those half an
    // edge length away facing back), and a tube of its own edges holds the path there.
    double local_sum = 0;
    int local_count = 0;
    for (const auto& on : lines)
      for (const SurfacePoint& p : on) {
        const Face& c = mesh.face(p.face);
        for (int k = 0; k < 3; ++k)
          local_sum += (mesh.position(c[static_cast<size_t>((k + 1) % 3)]) - mesh.position(c[static_cast<size_t>(k)])).norm();
        local_count += 3;
      }
    const double hl = std::min(h, local_sum / std::max(local_count, 1));
    // Every vertex's distance from the path (chord, to the polylines), of those `near` it.
    std::vector<double> dist;
    auto measure = [&](auto near) {
      dist.assign(nv, std::numeric_limits<double>::infinity());
      for (size_t v = 0; v < nv; ++v) {
        if (!near(v)) continue;
        const Vec3& x = mesh.position(static_cast<int>(v));
        for (const std::vector<Vec3>& line : world)
          for (size_t k = 0; k + 1 < line.size(); ++k) {
            const Vec3 e = line[k + 1] - line[k];
            const double n2 = e.squaredNorm();
            const double u = n2 > 0 ? std::clamp((x - line[k]).dot(e) / n2, 0.0, 1.0) : 0.0;
            dist[v] = std::min(dist[v], (x - line[k] - u * e).norm());
          }
      }
    };
    // The plane fits no tube when a face holding the path faces away from it (the tube
    // is never narrower than that face): then the chart that follows the path at once.
    bool plane = true;
    for (const auto& on : lines)
      for (const SurfacePoint& p : on) plane = plane && space.bundle().face_normal(p.face).dot(normal) > 0;
    bool found = false;
    if (plane) {
      LocalChart chart;
      space.log_map().compute_local(mid, reach + 2 * outer + 2 * h, chart);
      measure([&](size_t v) {
        const cplx geo = chart.coords[v];
        return std::isfinite(geo.real()) && std::isfinite(geo.imag()) && std::abs(geo) <= reach + 1.5 * outer;
      });
      // The widest tube (of inner, outer; then narrower, down to one edge length where the
      // path runs) whose faces all face the plane's way.
      for (double shrink = 1; !found && shrink * inner >= hl; shrink *= 0.7) {
        const double in_r = shrink * inner, out_r = shrink * outer;
        found = true;
        for (int f = 0; f < mesh.num_faces() && found; ++f) {
          const Face& c = mesh.face(f);
          if (std::min({dist[static_cast<size_t>(c[0])], dist[static_cast<size_t>(c[1])], dist[static_cast<size_t>(c[2])]}) <
                  out_r &&
              space.bundle().face_normal(f).dot(normal) <= 0)
            found = false;
        }
        if (!found) continue;
        path.coords.assign(nv, cplx(std::numeric_limits<double>::infinity(), 0));
        for (size_t v = 0; v < nv; ++v) {
          if (dist[v] >= out_r) continue;
          path.coords[v] = project(mesh.position(static_cast<int>(v)));
          path.support.push_back(v);
          path.w.push_back(dist[v] <= in_r ? 1.0 : smoothstep((out_r - dist[v]) / (out_r - in_r)));
        }
        if (!path.pair)
          for (const Vec3& x : world[0]) path.x.push_back(project(x));
      }
      if (found) return true;
    }
    auto follow = [&] {
      for (double shrink = 1; !found && shrink * outer >= 1.5 * hl; shrink *= 0.7) {
        const double in_r = shrink * inner, out_r = shrink * outer;
        std::vector<cplx> coords = follow_chart(mesh, dist, out_r, lines[0].front().face, world[0].front(), world[0].back());
        if (coords.empty()) continue;
        std::vector<cplx> x;
        bool on_chart = true;
        for (const auto& on : lines)
          for (const SurfacePoint& p : on) {
            const cplx z = chart_point(mesh, coords, p);
            on_chart = on_chart && std::isfinite(z.real());
            if (&on == &lines[0]) x.push_back(z);
          }
        if (!on_chart) continue;
        found = true;
        path.coords = std::move(coords);
        path.support.clear();
        path.w.clear();
        for (size_t v = 0; v < nv; ++v) {
          if (!std::isfinite(path.coords[v].real())) continue;
          path.support.push_back(v);
          path.w.push_back(dist[v] <= in_r ? 1.0 : smoothstep((out_r - dist[v]) / (out_r - in_r)));
        }
        if (!path.pair) path.x = std::move(x);
      }
    };
    // The chart that follows the path (follow_chart): the widest tube whose faces are a disk,
    // the tube measured in space (chord) and, where no such tube is a disk, on the surface.
    measure([&](size_t v) { return (mesh.position(static_cast<int>(v)) - centre).norm() <= reach + 1.5 * outer; });
    follow();
    if (!found) {
      // Along the edges from the vertices of the faces holding the path (their chord distance
      // exact): a thin part's far side (an ear or horn of about the tube's width, CGAL's cow)
      // is then as far as the way round it, and the tube a strip on its near side.
      std::vector<EdgePathSeed> seeds;
      for (const auto& on : lines)
        for (const SurfacePoint& p : on)
          for (const int v : mesh.face(p.face)) seeds.push_back({v, dist[static_cast<size_t>(v)]});
      dist = edge_path_distances(mesh, seeds, outer);
      follow();
    }
    return found;  // else neither chart fits within an edge length of the path
  };
  auto cached_tube = [&](SurfaceGuide::Path& path, size_t which, const std::vector<std::vector<SurfacePoint>>& lines,
                         const SurfacePoint& mid) {
    const auto key = std::tuple{path.pair, which, ramp};
    if (const auto it = tubes.find(key); it != tubes.end()) {
      path = it->second;
      return true;
    }
    if (!make_tube(path, lines, mid)) return false;
    tubes.emplace(key, path);
    return true;
  };
  // First, cheaply, every path's points on the surface: a guard (leaves_surface), since no
  // chart holds a path that is not a curve on the surface. The paths are curves on it
  // (surface_curve), so only a detour bent off it makes them jump. (Each track's samples
  // are kept for the tubes below.)
  std::vector<std::vector<SurfacePoint>> sampled(last - first);
  for (size_t i = first; i < last; ++i) {
    const Track& tr = tracks[i];
    sampled[i - first] = samples(tr);
    why = leaves_surface(space, tr, sampled[i - first]);
    if (!why.empty()) return false;
  }
  for (size_t i = first; i < last; ++i) {
    const Track& tr = tracks[i];
    if (tr.group >= 0) continue;  // a pair's (below)
    SurfaceGuide::Path path;
    path.track = i;
    path.conj = tr.index < 0;
    // The path on the surface, and the chart around its middle reaching `outer` past it.
    const std::vector<SurfacePoint>& on = sampled[i - first];
    const SurfacePoint mid = on[SurfaceGuide::kSamples / 2];
    double reach = 0;
    for (const SurfacePoint& p : on)
      reach = std::max(reach, (surface_position(mesh, p) - surface_position(mesh, mid)).norm());
    // A singularity that stays (the key frames' static solves put it within a thousandth
    // of an edge length, CGAL's elephant's foci 1e-8 apart): F₀ and F₁ share it, H carries it.
    if (reach < 1e-3 * h) continue;
    if (!cached_tube(path, i, {on}, mid)) {
      why = fmt::format("the surface folds over the chart of the {}'s path from {} to {} within an edge length of it "
                        "(and its tube is no disk down to 1.5 edge lengths wide)",
                        to_string(tr.type), describe_point(tr.p0, false, 1), describe_point(tr.p1, false, 1));
      return false;
    }
    // The shaped ratio: the key frames' linear parts along the path (`a`), where every
    // sample has one.
    for (int k = 0; shaped && k <= SurfaceGuide::kSamples; ++k) {
      const double s = static_cast<double>(k) / SurfaceGuide::kSamples;
      const std::optional<Linear> a = chart_jacobian(space, tr, path.coords, time_at(tr, s), on[static_cast<size_t>(k)].face);
      if (!a) {
        path.a.clear();
        break;
      }
      path.a.push_back(*a);
    }
    g.paths.push_back(std::move(path));
  }
  for (size_t pi = 0; pi < pairs.size(); ++pi) {
    const Guide::Pair& pr = pairs[pi];
    SurfaceGuide::Path path;
    path.pair = true;
    path.cancel = pr.cancel;
    path.track = pr.node;
    path.saddle = pr.saddle;
    path.tc = pr.tc;
    path.tau = pr.tau;
    // The two paths run from the key frame (s = 0) to the template's zeros (s = 1).
    auto kept = [&](size_t t) { return t >= first && t < last ? sampled[t - first] : samples(tracks[t]); };
    const std::vector<SurfacePoint> on_node = kept(pr.node), on_saddle = kept(pr.saddle);
    const std::vector<SurfacePoint> between{on_saddle.back(), on_node.back()};
    // The middle: the surface point nearest the mean of the two paths.
    Vec3 mean = Vec3::Zero();
    for (const auto* on : {&on_node, &on_saddle})
      for (const SurfacePoint& p : *on) mean += surface_position(mesh, p);
    const SurfacePoint mid = space.locate(mean / (2.0 * (SurfaceGuide::kSamples + 1)));
    if (!cached_tube(path, pi, {on_node, on_saddle, between}, mid)) {
      why = fmt::format("the surface folds over the chart of the pair at {} within an edge length of its paths",
                        describe_point(surface_position(mesh, mid), false, 1));
      return false;
    }
    // The template in the chart: its zeros are the tracks' ends.
    const cplx xn = chart_point(mesh, path.coords, on_node.back()), xs = chart_point(mesh, path.coords, on_saddle.back());
    if (!std::isfinite(std::abs(xn)) || !std::isfinite(std::abs(xs)) || std::abs(xn - xs) == 0) {
      why = fmt::format("the pair at {} has no template in its chart", describe_point(surface_position(mesh, mid), false, 1));
      return false;
    }
    path.mid = 0.5 * (xn + xs);
    path.sigma = 0.5 * std::abs(xn - xs);
    path.axis = (xn - xs) / std::abs(xn - xs);
    for (int k = 0; k <= SurfaceGuide::kSamples; ++k)
      path.states.push_back(pair_state(space, tracks, path, g.t0 + (g.t1 - g.t0) * k / SurfaceGuide::kSamples));
    g.paths.push_back(std::move(path));
  }
  // H = F₁ / F₀ · exp(−Σ_j w_j log R_j(t₁)), with no zero or pole: its log, lifted.
  const std::vector<cplx> l1 = surface_log_factors(space, tracks, g, g.t1);
  std::vector<cplx> hv(nv, cplx(0, 0));
  std::vector<char> ok(nv, 0);
  for (size_t v = 0; v < nv; ++v) {
    const cplx q = f1[v] / f0[v] * std::exp(-l1[v]);
    if (std::abs(f0[v]) == 0 || !std::isfinite(q.real()) || !std::isfinite(q.imag()) || std::abs(q) == 0) continue;
    hv[v] = q;
    ok[v] = 1;
  }
  std::vector<std::vector<size_t>> nbr(nv);
  for (int e = 0; e < mesh.num_halfedges(); ++e) {
    const auto a = static_cast<size_t>(mesh.tail(e)), b = static_cast<size_t>(mesh.head(e));
    nbr[a].push_back(b);
    nbr[b].push_back(a);
  }
  // A vertex on a key frame's zero: the mean of its neighbours' H (H is smooth there).
  if (!fill_from_neighbours(nbr, hv, ok)) {
    why = "the key frames' fields have no zero-free quotient (a part of the surface where one of them vanishes)";
    return false;
  }
  g.log_h.assign(nv, cplx(0, 0));
  std::vector<char> seen(nv, 0);
  double sum_arg = 0;
  for (size_t root = 0; root < nv; ++root) {
    if (seen[root]) continue;
    std::vector<size_t> queue{root};
    seen[root] = 1;
    g.log_h[root] = {std::log(std::abs(hv[root])), std::arg(hv[root])};
    for (size_t k = 0; k < queue.size(); ++k) {
      const size_t v = queue[k];
      for (const size_t w : nbr[v]) {
        if (seen[w]) continue;
        seen[w] = 1;
        g.log_h[w] = {std::log(std::abs(hv[w])), g.log_h[v].imag() + std::arg(hv[w] / hv[v])};
        queue.push_back(w);
      }
    }
  }
  for (const cplx& l : g.log_h) sum_arg += l.imag();
  // The far field turns the shorter way: the mean lifted argument within (−π, π].
  const double shift = 2 * std::numbers::pi * std::round(sum_arg / static_cast<double>(nv) / (2 * std::numbers::pi));
  for (cplx& l : g.log_h) l -= cplx(0, shift);
  g.f0 = f0;
  // λ of the nodes.
  for (size_t i = first; i < last; ++i) {
    const Track& tr = tracks[i];
    if (tr.index <= 0 || tr.group >= 0) continue;  // a pair's node: its hold, below
    // λ and the scale at each sample; NaN where G's or the plan's α has no value (a degenerate
    // face; a corner on a key frame's zero has affine_fill's).
    constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
    std::vector<double> lam, scale;
    std::optional<double> valued;
    for (int k = 0; k <= SurfaceGuide::kSamples; ++k) {
      const double t = g.t0 + (g.t1 - g.t0) * k / SurfaceGuide::kSamples;
      const int f = space.locate(tr.raw(tr.param(t))).face;
      const cplx a = face_alpha(space, f, surface_guide_on_face(space, tracks, g, t, f));
      const cplx plan = track_jacobian(space.bundle(), tr, t, f).alpha;
      if (!(std::abs(a) > 0) || !(std::abs(plan) > 0) || !std::isfinite(std::abs(a))) {
        lam.push_back(kNone);
        scale.push_back(kNone);
        continue;
      }
      scale.push_back(std::abs(a) / std::abs(plan));
      const double arg = std::arg(a / plan);
      lam.push_back(valued ? *valued + std::remainder(arg - *valued, 2 * std::numbers::pi) : arg);
      valued = lam.back();
    }
    // (A scale of 0 where G has no value made the node's own linear field vanish: CGAL's
    // mushroom's and bear's carried centers read trace/√det up to 2.5 and −6.4 in the frames
    // next to the first key frame, before its corners were filled.)
    fill_gaps(lam, 0.0);
    fill_gaps(scale, 1.0);
    const double a0 = std::remainder(lam.front(), 2 * std::numbers::pi);
    const double b0 = std::remainder(lam.back(), 2 * std::numbers::pi);
    for (int k = 0; k <= SurfaceGuide::kSamples; ++k) {
      const double u = g.ease(static_cast<double>(k) / SurfaceGuide::kSamples);
      lam[static_cast<size_t>(k)] -= (1 - u) * a0 + u * b0;
    }
    g.nodes.push_back(i);
    g.carried.push_back(0);
    g.lambda.push_back(std::move(lam));
    g.scale.push_back(std::move(scale));
  }
  // The local correction's radii: flat over 1.5 edge lengths (the node's face), falling to
  // 0 over at least 2 edge lengths, or 4/π edge lengths a radian of the node's largest |λ|
  // (a quarter turn an edge at most), but never as far as half the node's distance from
  // another path at any time.
  g.inner = 1.5 * h;
  g.linear_reach = 2.5 * h;
  g.reach.clear();
  for (size_t n = 0; n < g.nodes.size(); ++n) {
    double most = 0;
    for (const double l : g.lambda[n]) most = std::max(most, std::abs(l));
    double apart = std::numeric_limits<double>::infinity();
    const Track& tr = tracks[g.nodes[n]];
    for (int k = 0; k <= SurfaceGuide::kSamples; k += 4) {
      const double t = g.t0 + (g.t1 - g.t0) * k / SurfaceGuide::kSamples;
      const Vec3 p = tr.raw(tr.param(t));
      for (size_t j = first; j < last; ++j) {
        if (j == g.nodes[n]) continue;
        const Track& o = tracks[j];
        const double lo = std::min(o.t0, o.t1), hi = std::max(o.t0, o.t1);
        apart = std::min(apart, (o.raw(o.param(std::clamp(t, lo, hi))) - p).norm());
      }
    }
    g.reach.push_back(std::max(g.inner + h, std::min(g.inner + std::max(2.0, 4 * most / std::numbers::pi) * h,
                                                     0.5 * apart)));
  }
  // The pairs' nodes (PairHold): G's α at the node's face, its argument unwrapped, less its
  // value at the key frame where the pair is (there G is that key frame, whose type the
  // node keeps). In the template's window the node is Q's zero on +axis, √−μ from the
  // middle, found in the chart; a face where G has no value (a degenerate one; a corner on
  // a key frame's zero has affine_fill's) takes the nearest valued sample's turn (fill_gaps).
  for (const SurfaceGuide::Path& path : g.paths) {
    if (!path.pair) continue;
    SurfaceGuide::PairHold hold;
    hold.cancel = path.cancel;
    hold.t0 = g.t0;
    hold.t1 = g.t1;
    hold.tc = path.tc;
    hold.a = path.cancel ? g.t0 : path.tc;
    hold.b = path.cancel ? path.tc : g.t1;
    const std::optional<SurfacePoint> mid = chart_locate(mesh, path.coords, path.mid);
    if (!mid) continue;
    hold.mid = surface_position(mesh, *mid);
    std::vector<double> arg;
    std::optional<double> valued;  // the last sample with a value
    for (int k = 0; k <= SurfaceGuide::kSamples; ++k) {
      const double t = hold.a + (hold.b - hold.a) * k / SurfaceGuide::kSamples;
      const SurfaceGuide::PairState q = pair_state(space, tracks, path, t);
      std::optional<SurfacePoint> at;
      if (q.linear) {
        const Track& tr = tracks[path.track];
        at = space.locate(tr.raw(tr.param(t)));
      } else {
        at = chart_locate(mesh, path.coords, path.mid + path.axis * std::sqrt(std::max(-q.mu, 0.0)));
      }
      if (!at) break;
      hold.at.push_back(surface_position(mesh, *at));
      const cplx a = face_alpha(space, at->face, surface_guide_on_face(space, tracks, g, t, at->face));
      if (!(std::abs(a) > 0) || !std::isfinite(std::abs(a))) {
        arg.push_back(std::numeric_limits<double>::quiet_NaN());
        continue;
      }
      arg.push_back(valued ? *valued + std::remainder(std::arg(a) - *valued, 2 * std::numbers::pi) : std::arg(a));
      valued = arg.back();
    }
    if (hold.at.size() != static_cast<size_t>(SurfaceGuide::kSamples + 1)) continue;
    fill_gaps(arg, 0.0);
    const double key = path.cancel ? arg.front() : arg.back();
    for (const double x : arg) hold.turn.push_back(x - key);
    g.holds.push_back(std::move(hold));
  }
  return true;
}

// A node's λ for Λ away from it: its table at x (in samples) averaged over ±kFarWindow
// samples (fewer near the ends, which it keeps). The table is G's phase read in the face
// holding the node, which jumps by up to a quarter radian where the node crosses an edge
// (G is not linear across it); spread by Shepard's weights, each jump turned the whole far
// field at once (the sphere knot with a middle key frame: the far hemisphere turned 0.114
// rad in one frame against 0.07 on either side). Near its node λ stays exact (apply_surface_
// guide adds back what the average leaves out), so the node keeps its type as before.
constexpr int kFarWindow = 32;
double far_lambda(const std::vector<double>& lam, double x) {
  const int last = static_cast<int>(lam.size()) - 1;
  auto averaged = [&](int k) {
    const int w = std::min({kFarWindow, k, last - k});
    double sum = 0;
    for (int j = k - w; j <= k + w; ++j) sum += lam[static_cast<size_t>(j)];
    return sum / (2 * w + 1);
  };
  const int k = std::clamp(static_cast<int>(x), 0, last - 1);
  const double r = x - k;
  return (1 - r) * averaged(k) + r * averaged(k + 1);
}

// Fixes every free vertex of a frame at time t (strictly inside the interval) to G(t), `l`
// the paths' log factors at t (surface_log_factors: they depend on the paths alone, not on
// the phase correction, so the acceptance check computes them once for all its choices).
void apply_surface_guide(const DesignSpace& space, const std::vector<Track>& tracks, const SurfaceGuide& g,
                         double t, const std::vector<cplx>& l, std::span<char> fixed, std::span<cplx> values) {
  const Mesh& mesh = space.mesh();
  const double u = g.ease.at(t, g.t0, g.t1);
  const double x = std::clamp((t - g.t0) / (g.t1 - g.t0), 0.0, 1.0) * SurfaceGuide::kSamples;
  const auto k = std::min(static_cast<size_t>(x), static_cast<size_t>(SurfaceGuide::kSamples - 1));
  const double floor = 1e-12 * space.diameter(), mesh_h = mesh.mean_edge_length();
  // Each matched node's λ in two parts: `lambda`, blended over the surface by Shepard's
  // weights, and `local_lambda`, applied near the node alone, flat within `inner` and falling
  // to 0 at `local_reach`. The local choice: λ near each node alone (out to its `reach`; the
  // holds, if any, by Shepard's blend with the matched nodes at λ = 0, as the holds-alone
  // choice has them). Shepard's choice: the far values (far_lambda) blended, and near each
  // node what they leave out, so that the node's face sees its exact λ (out to an edge length
  // past `inner`).
  std::vector<Vec3> at;
  std::vector<double> lambda, local_lambda, local_reach;
  for (size_t n = 0; n < g.nodes.size(); ++n) {
    const Track& tr = tracks[g.nodes[n]];
    at.push_back(surface_position(mesh, space.locate(tr.raw(tr.param(t)))));
    const std::vector<double>& lam = g.lambda[n];
    const double exact = lam[k] + (x - static_cast<double>(k)) * (lam[k + 1] - lam[k]);
    lambda.push_back(g.local ? 0.0 : far_lambda(lam, x));
    local_lambda.push_back(exact - lambda.back());
    local_reach.push_back(g.local ? g.reach[n] : g.inner + mesh_h);
  }
  // Λ at a point from the nodes so far (Shepard's weights |x − p|⁻⁴).
  auto shepard_at = [&](const Vec3& point, size_t count) {
    double num = 0, den = 0;
    for (size_t n = 0; n < count; ++n) {
      const double w = 1 / std::pow(std::max((point - at[n]).norm(), floor), 4);
      num += w * lambda[n];
      den += w;
    }
    return den > 0 ? num / den : 0.0;
  };
  const size_t matched = at.size();
  for (const SurfaceGuide::PairHold& h : g.holds) {
    if (t >= h.a && t <= h.b) {
      const double y = (t - h.a) / (h.b - h.a) * SurfaceGuide::kSamples;
      const auto j = std::min(static_cast<size_t>(std::max(y, 0.0)), static_cast<size_t>(SurfaceGuide::kSamples - 1));
      const double r = y - static_cast<double>(j);
      at.push_back((1 - r) * h.at[j] + r * h.at[j + 1]);
      lambda.push_back((1 - r) * h.turn[j] + r * h.turn[j + 1]);
    } else {
      // Not born yet (or dead): at the template's middle, from what Λ is there without it
      // (at the other key frame) to its λ at t_c.
      const double r = h.cancel ? smoothstep01(t, h.t1, h.tc) : smoothstep01(t, h.t0, h.tc);
      const double at_tc = h.cancel ? h.turn.back() : h.turn.front();
      lambda.push_back(r * at_tc + (1 - r) * shepard_at(h.mid, matched));
      at.push_back(h.mid);
    }
  }
  std::vector<size_t> poles;
  auto local_at = [&](const Vec3& point) {
    double out = 0;
    for (size_t n = 0; n < local_lambda.size(); ++n) {
      const double d = (point - at[n]).norm();
      if (d < local_reach[n]) out += local_lambda[n] * (1 - smoothstep01(d, g.inner, local_reach[n]));
    }
    return out;
  };
  const bool blend = !g.local || at.size() > matched;
  // The nodes' own linear fields near them (the local choice): J(t)(z − p(t)) in the face
  // holding p(t), scaled to G's magnitude there, within `inner`, blended into G out to
  // `linear_reach` (not past the node's `reach`).
  struct Near {
    Vec3 p;
    int face;
    Linear j;
    double inner, reach;
  };
  std::vector<Near> near;
  if (g.local) {
    for (size_t n = 0; n < local_lambda.size() && n < matched; ++n) {
      if (g.carried[n]) continue;
      const Track& tr = tracks[g.nodes[n]];
      const int f = space.locate(at[n]).face;
      Linear j = track_jacobian(space.bundle(), tr, t, f);
      const std::vector<double>& sc = g.scale[n];
      const double c = sc[k] + (x - static_cast<double>(k)) * (sc[k + 1] - sc[k]);
      j.alpha *= c;
      j.beta *= c;
      near.push_back({at[n], f, j, g.inner, std::max(std::min(g.linear_reach, g.reach[n]), g.inner + 1e-9)});
    }
  }
  auto linear_at = [&](int v, const Vec3& point, cplx val) {
    for (const Near& nn : near) {
      const double d = (point - nn.p).norm();
      if (d >= nn.reach) continue;
      const double b = 1 - smoothstep01(d, nn.inner, nn.reach);
      const cplx z = space.bundle().world_to_face(nn.face, point - nn.p);
      const cplx lin = space.bundle().world_to_vertex(
          v, space.bundle().face_to_world(nn.face, nn.j.alpha * z + nn.j.beta * std::conj(z)));
      val = (1 - b) * val + b * lin;
    }
    return val;
  };
  for (size_t v = 0; v < l.size(); ++v) {
    if (fixed[v]) continue;
    const Vec3& point = mesh.position(static_cast<int>(v));
    const double turn = (blend ? shepard_at(point, at.size()) : 0.0) + local_at(point);
    cplx val = g.f0[v] * std::exp(l[v] + u * g.log_h[v] - cplx(0, turn));
    if (g.local) val = linear_at(static_cast<int>(v), point, val);
    if (!std::isfinite(val.real()) || !std::isfinite(val.imag())) {
      poles.push_back(v);
      continue;
    }
    fixed[v] = 1;
    values[v] = val;
  }
  // A vertex on a pole of the ratio (a key frame's zero on it) takes the affine fit of its
  // fixed neighbours' values (affine_fill), and the acceptance check (PhaseCheck) reads the
  // frame the solve gets. Left to the solve, it was pulled towards the key frame's zero there
  // by the temporal term, and the solved frames held a pair around it that the check had not
  // seen (CGAL's head: a guided knot with 6 events not asked for).
  std::vector<std::pair<size_t, cplx>> filled;
  for (const size_t v : poles) {
    const std::optional<cplx> value =
        affine_fill(mesh, space.bundle(), static_cast<int>(v), [&](int w) -> std::optional<cplx> {
          if (!fixed[static_cast<size_t>(w)]) return std::nullopt;
          return values[static_cast<size_t>(w)];
        });
    if (value) filled.emplace_back(v, *value);
  }
  for (const auto& [v, val] : filled) fixed[v] = 1, values[v] = val;
}

// The same with the log factors computed here.
void apply_surface_guide(const DesignSpace& space, const std::vector<Track>& tracks, const SurfaceGuide& g,
                         double t, std::span<char> fixed, std::span<cplx> values) {
  apply_surface_guide(space, tracks, g, t, surface_log_factors(space, tracks, g, t), fixed, values);
}

// A wrong frame in words, for unguided_reason: "the first at t = 0.452: 30 singularities
// where the plan carries 26; an extra saddle at (…), 0.038 from the plan's saddle, in a face
// 2.8 mean edge lengths long" (the face's size where it is two mean edge lengths or more),
// or "… the plan's source at (…) has none within 0.05".
std::string wrong_frame_sentence(const KeyframeIntervalReport::WrongFrame& w) {
  const std::string at = describe_point(w.at, false, 1);
  const bool other = std::isfinite(w.distance);
  std::string where =
      w.extra ? (other ? fmt::format("an extra {} at {}, {:.2g} from the plan's {}", to_string(w.type), at,
                                     w.distance, to_string(w.nearest_type))
                       : fmt::format("an extra {} at {}", to_string(w.type), at))
              : (other ? fmt::format("the plan's {} at {} has none within {:.2g}", to_string(w.type), at, w.distance)
                       : fmt::format("the plan's {} at {} has none", to_string(w.type), at));
  if (w.face_edges >= 2) where += fmt::format(", in a face {:.1f} mean edge lengths long", w.face_edges);
  return fmt::format("the first at t = {:.3g}: {} singularities where the plan carries {}; {}", w.t, w.found,
                     w.planned, where);
}

// The phase correction turns G by a field that varies by the nodes' whole turns (2π for
// the knot's center) over their distance, which a coarse mesh does not resolve: the
// faces between the nodes then hold extra zeros. So it is kept only where it does no
// harm, by measurement: G with and without it at the scene's frames inside the interval
// (`times`: what the analysis will see; 31 evenly spaced times were sampled before, and a
// pair living a third of their spacing slipped between them on CGAL's bunny), and the
// correction dropped when its frames hold more singularities than the plan carries more
// often (`matched` throughout, and each pair's two while it exists; not counted within half
// a frame of a pair's event, where its two zeros are too close to tell). A vertex G leaves
// to the solve (on a key frame's zero, none of its neighbours fixed) counts as their sum.
// A surface guide is kept only when none of those frames holds another number of
// singularities than the plan carries: a frame that does is a bifurcation the user did not
// ask for in the analysis (two, with the pair's birth and death), so the interval is left
// free instead, and says why. (The knot with a created pair at subdivisions 4, whose
// matched saddle and focus move across it, with the narrow ramp: 12 of 31 sampled frames,
// 135 bifurcations against 19 unguided; every scene the tests guide: 0.)
//
// The check is cheap to fail: the interval tries up to four guides (PhaseCheck's users,
// below) and keeps the first with a choice that holds no wrong frame, so a choice's frames
// are counted only until its first wrong one (from both ends of the interval inwards, where
// the guide meets the key frames and the failures were seen on CGAL's bunny), and counted
// on from there only when no guide is kept and the report says how many frames were wrong.
// The frames' log factors (keep_frame_logs) are made once per guide for all its choices,
// which differ in the phase correction alone, and the faces' curvature once per interval.
class PhaseCheck {
 public:
  // checkpoint: the plan's (called before each frame is made; may throw to stop).
  PhaseCheck(const DesignSpace& space, const std::vector<Track>& tracks, size_t matched,
             std::span<const double> times, const std::function<void()>& checkpoint)
      : space_(space), tracks_(tracks), matched_(matched), times_(times.begin(), times.end()),
        curvature_(face_curvatures(space.bundle())), checkpoint_(checkpoint) {
    const Mesh& mesh = space.mesh();
    nbr_.resize(static_cast<size_t>(mesh.num_vertices()));
    for (int e = 0; e < mesh.num_halfedges(); ++e) {
      const auto a = static_cast<size_t>(mesh.tail(e)), b = static_cast<size_t>(mesh.head(e));
      nbr_[a].push_back(b);
      nbr_[b].push_back(a);
    }
    for (size_t lo = 0, hi = times_.size(); lo < hi;) {
      order_.push_back(lo++);
      if (lo < hi) order_.push_back(--hi);
    }
  }

  // One built guide and its choices of phase correction.
  struct Trial {
    SurfaceGuide g;
    struct Choice {
      bool nodes = true, holds = true;
      bool local = false;  // the nodes' correction near each node alone (SurfaceGuide::local)
      int wrong = 0;     // counted so far (int max: not a choice, its nodes end apart)
      size_t next = 0;   // in the check's order, the next frame to count
    };
    std::vector<Choice> choices;
    // The most saddle–node events not planned that the tracking found in a choice with no
    // wrong frame (accept()), 0 if none was tracked or none had any.
    int unplanned = 0;
  };

  // The matched nodes' correction and the pairs' holds, each kept only where it adds no
  // wrong frame: the first of (both, the nodes' alone, the holds alone, neither) with the
  // fewest. The holds alone keep the matched nodes with λ = 0: Λ must stay 0 at them (a
  // pair's node alone would make Λ its λ everywhere, turning every other node's type: the
  // knot's source into a sink on the sphere 3 knot with a cancelled pair).
  // A correction whose matched nodes end their interval with different whole turns (the
  // knot's center 2π, its source 0) leaves Λ at t₁ their Shepard blend, π midway between
  // them: G(t) then tends to F₁ turned by up to π there, and the last frame before the key
  // frame pops (CGAL's and the tests' sphere knot: vectors reversed between the nodes, the
  // coherence series' last step 28× its median). Such a correction is not one of the
  // choices; a node's λ at t₁ is a whole turn, and they must all be the same one.
  Trial start(SurfaceGuide g) const {
    Trial trial;
    keep_frame_logs(space_, tracks_, g, times_);
    trial.g = std::move(g);
    const SurfaceGuide& s = trial.g;
    trial.choices.push_back({true, true});
    if (!s.nodes.empty() || !s.holds.empty()) {
      if (!s.holds.empty() && !s.nodes.empty()) trial.choices.push_back({true, false});
      if (!s.nodes.empty()) {
        trial.choices.push_back({true, true, true});
        if (!s.holds.empty()) trial.choices.push_back({true, false, true});
      }
      if (!s.holds.empty() && !s.nodes.empty()) trial.choices.push_back({false, true});
      trial.choices.push_back({false, false});
    }
    // The nodes' λ as they are (without the nodes' correction: none, or 0 throughout). The
    // local correction keeps the nodes whose λ ends at 0 (a whole turn left in a node's
    // annulus at t₁ is no identity there: those are left as G carries them), so it needs one.
    bool ends = true, zero = false;
    for (const std::vector<double>& lam : s.lambda) {
      ends = ends && std::abs(lam.back() - s.lambda.front().back()) <= 1e-6;
      zero = zero || std::abs(lam.back()) <= 1e-6;
    }
    for (Trial::Choice& c : trial.choices)
      if (c.nodes && (c.local ? !zero : !ends)) c.wrong = std::numeric_limits<int>::max(), c.next = order_.size();
    return trial;
  }

  // Whether a choice holds no wrong frame; then the trial's guide is the first such. A choice
  // with the nodes' correction must also not turn the frames faster than the same choice
  // without it (roughness(): at most twice its largest change of a vertex from frame to
  // frame): Λ blends nodes whose λ differ (up to 1.6 rad on CGAL's mushroom) and the switch
  // between them sweeps over vertices as the nodes move; there it turned single vertices by
  // six times the field's mean magnitude from one frame to the next (coherence max/median
  // 4.1 against 1.6), and the solved frames held a pair the count of G's zeros did not see.
  // The two corrections of the nodes with the same holds (Shepard's blend, then the local
  // one) compete when both pass: the smoother is kept. Both hold the nodes' types; which is
  // smoother depends on how far apart the nodes' λ are. Since Shepard's blend takes the far
  // λ averaged in time (far_lambda) it passes the bound on CGAL's mushroom and bear too, and
  // kept there it made both worse: the mushroom's center a focus in 5 frames (trace/√det 0.83
  // and −1.65 at frames 7 and 8, a Hopf event not asked for), the bear's change max/median
  // 1.46 → 1.76. Their roughness against the local one's: 0.125 and 0.091, 0.166 and 0.136
  // (the local one kept, as before); the sphere knot with a middle key frame: 0.051 and
  // 0.057 (Shepard's kept).
  bool accept(Trial& trial) const {
    struct Kept {
      double rough = 0;
      bool nodes = false, holds = false;
      SurfaceGuide guide;
    };
    std::optional<Kept> kept;
    for (Trial::Choice& c : trial.choices) {
      // Once a choice is kept, only its twin may compete.
      const bool twin = kept && c.nodes && kept->nodes && c.holds == kept->holds;
      if (kept && !twin) continue;
      count(trial, c, 1);
      if (c.wrong != 0) continue;
      double rough = 0;
      if (c.nodes && !trial.g.nodes.empty()) {
        const Trial::Choice plain{false, c.holds, false};
        rough = roughness(trial.g, variant(trial.g, c));
        if (rough > 2 * roughness(trial.g, variant(trial.g, plain))) {
          c.wrong = std::numeric_limits<int>::max(), c.next = order_.size();
          continue;
        }
      }
      SurfaceGuide guide = variant(trial.g, c);
      if (const int extra = unplanned_events(trial.g, guide); extra > 0) {
        trial.unplanned = std::max(trial.unplanned, extra);
        c.wrong = std::numeric_limits<int>::max(), c.next = order_.size();
        continue;
      }
      if (!kept || rough < kept->rough) kept = Kept{rough, c.nodes, c.holds, std::move(guide)};
    }
    if (!kept) return false;
    trial.g = std::move(kept->guide);
    return true;
  }

  // The fewest wrong frames of the trial's choices, every frame counted.
  int fewest(Trial& trial) const {
    int best = std::numeric_limits<int>::max();
    for (Trial::Choice& c : trial.choices) {
      count(trial, c, std::numeric_limits<int>::max());
      best = std::min(best, c.wrong);
    }
    return best;
  }

  // Where the first wrong frame (in time) of the trial's choice with the fewest (fewest()
  // counted them) goes wrong, for the report (KeyframeIntervalReport::WrongFrame; in words
  // by wrong_frame_sentence): the count the frame holds against the plan's, and the
  // singularity found farthest from every planned one (or the plan's farthest from any
  // found, where the frame holds fewer). None when no choice has a countable wrong frame.
  std::optional<KeyframeIntervalReport::WrongFrame> first_wrong(const Trial& trial) const {
    const Trial::Choice* best = nullptr;
    for (const Trial::Choice& c : trial.choices)
      if (c.wrong < std::numeric_limits<int>::max() && (!best || c.wrong < best->wrong)) best = &c;
    if (!best || best->wrong == 0) return std::nullopt;
    const SurfaceGuide guide = variant(trial.g, *best);
    const Mesh& mesh = space_.mesh();
    for (size_t i = 0; i < times_.size(); ++i) {
      if (!wrong_frame(trial.g, guide, i)) continue;
      const double t = times_[i];
      // Every singularity the plan has at t: the interval's tracks present then (those that
      // stay put too, which the guide keeps through H rather than a path; the plan's tracks
      // end with this interval's while it is being built).
      std::vector<Vec3> planned;
      std::vector<SingularityType> planned_type;
      for (const Track& tr : tracks_)
        if (t > std::min(tr.t0, tr.t1) && t < std::max(tr.t0, tr.t1)) {
          planned.push_back(tr.raw(tr.param(t)));
          planned_type.push_back(tr.type);
        }
      // A created or cancelled pair between its tracks and its event: its template's two
      // zeros, √−μ either side of its middle in its chart (the node on +axis), which the
      // count holds as the plan's (CGAL's cow: the cancelled pair's saddle was named the
      // extra singularity, 1.2 region radii from every track).
      for (const SurfaceGuide::Path& p : guide.paths) {
        if (!p.pair) continue;
        const SurfaceGuide::PairState q = pair_state(space_, tracks_, p, t);
        if (q.linear || q.mu >= 0) continue;
        for (const double side : {1.0, -1.0})
          if (const std::optional<SurfacePoint> on =
                  chart_locate(mesh, p.coords, p.mid + side * std::sqrt(-q.mu) * p.axis)) {
            planned.push_back(surface_position(mesh, *on));
            planned_type.push_back(side > 0 ? tracks_[p.track].type : SingularityType::saddle);
          }
      }
      std::vector<cplx> values(static_cast<size_t>(mesh.num_vertices()), cplx(0, 0));
      frame_values(trial.g, guide, i, values);
      const std::vector<Singularity> found = find_singularities(space_.bundle(), values, curvature_);
      std::vector<Vec3> found_at;
      std::vector<SingularityType> found_type;
      for (const Singularity& f : found) found_at.push_back(f.position), found_type.push_back(f.type);
      // The longest edge of a face in mean edge lengths: the extras of CGAL's cow, homer and
      // elephant knots lie in faces 2.1 to 2.8 long (6–14% of those meshes' faces), beside a
      // carried singularity whose zero splits into three there (docs/benchmarks.md, session 38).
      auto face_edges = [&](int face) {
        double longest = 0;
        for (int c = 0; c < 3; ++c) longest = std::max(longest, mesh.edge_length(3 * face + c));
        return longest / mesh.mean_edge_length();
      };
      KeyframeIntervalReport::WrongFrame w;
      w.t = t;
      w.found = static_cast<int>(found.size());
      w.planned = static_cast<int>(planned.size());
      w.extra = found.size() > planned.size();
      // The point of `from` farthest from every point of `to`, its distance and the nearest's type.
      const std::vector<Vec3>& from = w.extra ? found_at : planned;
      const std::vector<Vec3>& to = w.extra ? planned : found_at;
      const std::vector<SingularityType>& from_type = w.extra ? found_type : planned_type;
      const std::vector<SingularityType>& to_type = w.extra ? planned_type : found_type;
      if (from.empty()) continue;  // neither holds one (the count disagrees all the same): no place to name
      double farthest = -1;
      for (size_t a = 0; a < from.size(); ++a) {
        double d = std::numeric_limits<double>::infinity();
        size_t near = 0;
        for (size_t b = 0; b < to.size(); ++b)
          if (const double e = (from[a] - to[b]).norm(); e < d) d = e, near = b;
        if (d <= farthest) continue;
        farthest = d;
        w.type = from_type[a];
        w.at = from[a];
        w.distance = d;
        if (!to.empty()) w.nearest_type = to_type[near];
        w.face_edges = face_edges(w.extra ? found[a].where.face : space_.locate(planned[a]).face);
      }
      return w;
    }
    return std::nullopt;
  }

 private:
  // The guide with a choice's correction (its frame logs shared with g's).
  static SurfaceGuide variant(const SurfaceGuide& g, const Trial::Choice& c) {
    SurfaceGuide v = g;
    v.local = c.nodes && c.local;
    // A node the choice does not hold (none of its nodes' correction, or a whole turn the
    // local one carries): its λ recorded for the report; a carried one's λ zeroed.
    v.turning.clear();
    for (size_t n = 0; n < g.nodes.size(); ++n) {
      const std::vector<double>& lam = g.lambda[n];
      const bool carried_turn = v.local && std::abs(lam.back()) > 1e-6;
      if (c.nodes && !carried_turn) continue;
      double swing = 0;
      for (const double l : lam) swing = std::max(swing, std::abs(l));
      v.turning.push_back({g.nodes[n], lam.back(), swing});
      if (carried_turn) {
        v.carried[n] = 1;
        std::fill(v.lambda[n].begin(), v.lambda[n].end(), 0.0);
      }
    }
    if (!c.nodes && c.holds)
      for (std::vector<double>& lam : v.lambda) std::fill(lam.begin(), lam.end(), 0.0);
    else if (!c.nodes)
      v.nodes.clear(), v.lambda.clear(), v.carried.clear();
    if (!c.holds) v.holds.clear();
    return v;
  }

  // Counts a choice's wrong frames on from where it stopped, until `bound` or the last.
  void count(const Trial& trial, Trial::Choice& c, int bound) const {
    if (c.wrong >= bound || c.next >= order_.size()) return;
    const SurfaceGuide guide = variant(trial.g, c);
    for (; c.next < order_.size() && c.wrong < bound; ++c.next)
      if (wrong_frame(trial.g, guide, order_[c.next])) ++c.wrong;
  }

  // The largest change of a vertex's value from one of the interval's frames to the next.
  double roughness(const SurfaceGuide& g, const SurfaceGuide& guide) const {
    const auto nv = static_cast<size_t>(space_.mesh().num_vertices());
    std::vector<cplx> prev, values, l;
    std::vector<char> prev_fixed, fixed;
    double out = 0;
    for (size_t i = 0; i < times_.size(); ++i) {
      const double t = times_[i];
      if (!(t > guide.t0 && t < guide.t1)) continue;
      if (checkpoint_) checkpoint_();
      frame_logs(g, i, nv, l);
      fixed.assign(nv, 0);
      values.assign(nv, cplx(0, 0));
      apply_surface_guide(space_, tracks_, guide, t, l, fixed, values);
      if (!prev.empty())
        for (size_t v = 0; v < nv; ++v)
          if (fixed[v] && prev_fixed[v]) out = std::max(out, std::abs(values[v] - prev[v]));
      prev.swap(values);
      prev_fixed.swap(fixed);
    }
    return out;
  }

  // Whether frame i of `guide` (a choice of g's) holds another number of singularities
  // than the plan carries (false within half a frame of a pair's event).
  bool wrong_frame(const SurfaceGuide& g, const SurfaceGuide& guide, size_t i) const {
    const auto nv = static_cast<size_t>(space_.mesh().num_vertices());
    const double t = times_[i];
    if (!(t > guide.t0 && t < guide.t1)) return false;
    // Half the frames' spacing (the pair's event is not told within it).
    const double half = times_.size() > 1 ? 0.5 * std::abs(times_[1] - times_[0]) : 0.0;
    size_t carried = matched_;
    bool at_event = false;
    for (const SurfaceGuide::Path& p : guide.paths) {
      if (!p.pair) continue;
      at_event = at_event || std::abs(t - p.tc) < half;
      if (p.cancel ? t < p.tc : t > p.tc) carried += 2;
    }
    if (at_event) return false;
    std::vector<cplx> values(nv, cplx(0, 0));
    frame_values(g, guide, i, values);
    return find_singularities(space_.bundle(), values, curvature_).size() != carried;
  }

  // A choice's frame i as counted: G at every vertex it fixes, the others their fixed
  // neighbours' mean.
  void frame_values(const SurfaceGuide& g, const SurfaceGuide& guide, size_t i, std::span<cplx> values) const {
    if (checkpoint_) checkpoint_();
    const TangentBundle& bundle = space_.bundle();
    const auto nv = static_cast<size_t>(space_.mesh().num_vertices());
    std::vector<cplx> l;
    frame_logs(g, i, nv, l);
    std::vector<char> fixed(nv, 0);
    apply_surface_guide(space_, tracks_, guide, times_[i], l, fixed, values);
    for (size_t v = 0; v < nv; ++v) {
      if (fixed[v]) continue;
      Vec3 sum = Vec3::Zero();
      for (const size_t w : nbr_[v])
        if (fixed[w]) sum += bundle.vertex_to_world(static_cast<int>(w), values[w]);
      values[v] = bundle.world_to_vertex(static_cast<int>(v), sum);
    }
  }

  // The saddle–node events the analysis's tracking (analyze_topology) finds in a choice's
  // frames beyond the plan's pairs' events among them. The frame count holds every frame to
  // the plan's number of zeros, but not where they are: on a coarse mesh (the sphere knot at
  // 42 vertices, its far pairs created and cancelled at t = 0.5) a pair's zeros sat 2.4 edge
  // lengths from where the plan carries them, jumping from frame to frame, and the analysis
  // of the solved field tracked four events not asked for.
  int unplanned_events(const SurfaceGuide& g, const SurfaceGuide& guide) const {
    if (times_.size() < 2) return 0;
    const int n = static_cast<int>(times_.size());
    Field frames(TimeSampling{times_.front(), times_.back(), n}, space_.mesh().num_vertices());
    for (int i = 0; i < n; ++i) frame_values(g, guide, static_cast<size_t>(i), frames.frame(i));
    TopologyOptions options;
    options.parallel = false;
    const Topology topology = analyze_topology(space_.bundle(), frames, options);
    int planned = 0;
    for (const SurfaceGuide::Path& p : guide.paths)
      if (p.pair && p.tc > times_.front() && p.tc < times_.back()) ++planned;
    return std::max(0, static_cast<int>(topology.bifurcations.size()) - planned);
  }

  const DesignSpace& space_;
  const std::vector<Track>& tracks_;
  size_t matched_;
  std::vector<double> times_;
  std::vector<double> curvature_;
  std::vector<std::vector<size_t>> nbr_;
  std::vector<size_t> order_;  // the frames' order of counting: from both ends inwards
  const std::function<void()>& checkpoint_;
};

// The shortest path on a surface from p to q (points on it), as a curve on the surface:
// SurfacePaths::between (integrate/surface_path.h: the edge path resampled at about an
// edge length apart, at most kCurvePoints segments, straightened into a discrete geodesic).
// Null when no edge path joins them (another connected component) or the curve has no
// length: then the path is the straight segment.
constexpr int kCurvePoints = 96;

std::shared_ptr<const SurfaceCurve> surface_curve(const DesignSpace& space, const SurfacePaths& paths, const Vec3& p,
                                                  const Vec3& q) {
  std::vector<Vec3> x = paths.between(p, q, kCurvePoints);
  if (x.empty()) return nullptr;
  auto curve = std::make_shared<SurfaceCurve>();
  curve->space = &space;
  if (x.size() == 2 && !((x[1] - x[0]).norm() > 0)) {  // p and q one point
    curve->points = {p, q};
    curve->along = {0.0, 1.0};
    return curve;
  }
  auto lengths = [](SurfaceCurve& c) {
    c.along.assign(c.points.size(), 0.0);
    for (size_t k = 1; k < c.points.size(); ++k)
      c.along[k] = c.along[k - 1] +
                   (c.steps.empty() ? (c.points[k] - c.points[k - 1]).norm() : std::abs(c.steps[k - 1]));
    c.length = c.along.back();
    if (!(c.length > 0)) return false;
    for (double& a : c.along) a /= c.length;
    return true;
  };
  curve->points = std::move(x);
  if (!lengths(*curve)) return nullptr;  // straightened to a point: the segment
  // Where a chord of the straightened polyline cuts across a fold or a concave crease, its
  // points' nearest surface points jump to the other side (CGAL's man: a curve pulled out
  // of the armpit, two points 3.6 edge lengths apart on either side of it), and the path
  // leaves the surface; the route (every segment a walk on the surface) goes round instead.
  // (The same test as leaves_surface's, on the curve's own 257 samples.)
  const Mesh& mesh = space.mesh();
  std::vector<Vec3> on{curve->points.front()};
  for (int k = 1; k <= 256; ++k) on.push_back(surface_position(mesh, space.locate(curve->at(k / 256.0))));
  if (largest_step(on) <= kSurfaceJumpEdges * mesh.mean_edge_length()) return curve;
  SurfacePaths::Route r = paths.route(p, q, kCurvePoints);
  if (r.steps.empty()) return curve;
  auto routed = std::make_shared<SurfaceCurve>();
  routed->space = &space;
  routed->points = std::move(r.points);
  routed->starts = std::move(r.starts);
  routed->steps = std::move(r.steps);
  if (!lengths(*routed)) return curve;
  return routed;
}

// A path's derivative in its parameter at its first end (at_end false) or its last, before
// any Hermite term or detour: the segment's p1 − p0; on a surface the curve's direction
// there (its first or last chord, about an edge length) times its length, in the plane
// normal to `normal` (the surface's at that end).
Vec3 end_velocity(const Vec3& p0, const Vec3& p1, const SurfaceCurve* curve, bool at_end, const Vec3& normal) {
  Vec3 d = p1 - p0;
  if (curve) {
    const std::vector<Vec3>& x = curve->points;
    const Vec3 chord = at_end ? Vec3(x[x.size() - 1] - x[x.size() - 2]) : Vec3(x[1] - x[0]);
    d = chord.norm() > 0 ? Vec3(chord.normalized() * curve->length) : Vec3::Zero();
  }
  return d - d.dot(normal) * normal;
}

// The velocity a singularity carried through a middle key frame has there: Bessel's
// tangent, the slope at the key frame of the parabola through its three places, (Δt₂ v₁ +
// Δt₁ v₂)/(Δt₁ + Δt₂) from the velocities v₁ = leg/Δt₁ it arrives with and v₂ it leaves
// with (the way an animation curve's key is smoothed: straight on where the two legs run
// on; a quarter turn round a pole each way, as example 26's sphere knot does, goes round
// in an arc instead of a corner; a reversal comes to rest). No more than twice the slower
// leg's speed, so a singularity that stays put on one side (a hold before it moves) sets
// off from rest instead of drifting off before the key frame, and a short leg is not
// swung out far by a long one (a monotone spline's limit, as Fritsch and Carlson's).
Vec3 through_velocity(const Vec3& v1, const Vec3& v2, double dt1, double dt2) {
  Vec3 v = (dt2 * v1 + dt1 * v2) / (dt1 + dt2);
  const double cap = 2 * std::min(v1.norm(), v2.norm());
  if (v.norm() > cap) v *= cap / v.norm();
  return v;
}

// Where the +1 singularities' phase drifts (each one's phase change less their mean, so
// summing to 0) must end for the key frames' types with no whole turn between two of them:
// each drift's value within (−π, π], unwrapped across the largest gap on the circle (the
// tightest cluster), less the cluster's whole turns' mean. A drift that ends elsewhere winds
// whole turns round the others, which no correction of the phase undoes (a source and a
// center trading places round a saddle on CGAL's mushroom ended at +3.06 and −3.06: each
// within (−π, π], the two a whole turn apart; their targets are ∓0.08). Where the values lie
// within π of each other, without wrapping, the targets are those values themselves.
std::vector<double> phase_targets(const std::vector<double>& ends) {
  const double two_pi = 2 * std::numbers::pi;
  std::vector<double> r;
  for (const double e : ends) r.push_back(std::remainder(e, two_pi));
  if (r.size() < 2) return r;
  std::vector<size_t> order(r.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return r[a] < r[b]; });
  // The largest gap: after order[cut − 1] (cut 0: the gap across ±π, no unwrapping).
  size_t cut = 0;
  double widest = r[order.front()] + two_pi - r[order.back()];
  for (size_t k = 1; k < order.size(); ++k)
    if (r[order[k]] - r[order[k - 1]] > widest) widest = r[order[k]] - r[order[k - 1]], cut = k;
  for (size_t k = 0; k < cut; ++k) r[order[k]] += two_pi;
  double turns = 0;
  for (size_t i = 0; i < r.size(); ++i) turns += std::round((r[i] - ends[i]) / two_pi);
  turns /= static_cast<double>(r.size());
  if (turns != 0)
    for (double& x : r) x -= two_pi * turns;
  return r;
}

// The +1 tracks' phase drifts from their mean, D_i(g) = Φ_i(g) − Φ_i(0) − mean_k(Φ_k(g) −
// Φ_k(0)) (`phi` the tracks' unwrapped phases, `plus` the +1 tracks), and where they must
// end (phase_targets of their values at the last sample), in the order of `plus`.
struct PhaseDrifts {
  const std::vector<std::vector<double>>& phi;
  const std::vector<size_t>& plus;
  double operator()(size_t i, size_t g) const {
    double mean = 0;
    for (const size_t k : plus) mean += phi[k][g] - phi[k][0];
    return phi[i][g] - phi[i][0] - mean / static_cast<double>(plus.size());
  }
  std::vector<double> targets(size_t last) const {
    std::vector<double> ends;
    for (const size_t i : plus) ends.push_back((*this)(i, last));
    return phase_targets(ends);
  }
};

// Keeps the singularities carried through one key-frame interval `separation` apart: two
// paths that come closer at the same time (paths that cross, or pass close) get a detour,
// a bump perpendicular to their relative motion at the closest approach, full over the
// time they are too close and vanishing at the key frames (ends and times kept). Distances are straight-line (chord)
// distances between the points on the domain: on a surface never more than the geodesic
// distance, so a chord separation of D keeps the geodesic one ≥ D too.
class PathRouter {
public:
  static constexpr int kSamples = 256;
  // A pairwise detour's largest offset, in separations (separate()).
  static constexpr double kMaxDetour = 2;

  // keyframe_times: the scene's key frames' times (where the paths' ends are the key
  // frames' singularities; required() never asks a pair for more than those hold it).
  // checkpoint: the plan's (called each round; may throw to stop). joint_search: whether
  // route() may route all the paths at once (joint()) where the pairwise detours do not
  // hold (seconds on a scanned mesh; the lowered separation's tries go without).
  PathRouter(const DesignSpace& space, double separation, std::vector<double> keyframe_times,
             const std::function<void()>& checkpoint, bool joint_search = true)
      : space_(space), separation_(separation), keyframe_times_(std::move(keyframe_times)), checkpoint_(checkpoint),
        joint_search_(joint_search) {
    const Mesh& mesh = space.mesh();
    for (int h = 0; h < mesh.num_halfedges(); ++h)
      if (mesh.is_boundary_halfedge(h)) boundary_.emplace_back(mesh.position(mesh.tail(h)), mesh.position(mesh.head(h)));
  }

  // The carried singularity's point on the domain at time t.
  Vec3 at(const Track& tr, double t, int* face = nullptr) const {
    const Vec3 raw = tr.raw(tr.param(t));
    if (space_.planar()) return raw;
    const SurfacePoint sp = space_.locate(raw);
    if (face) *face = sp.face;
    return surface_position(space_.mesh(), sp);
  }

  // The distance two tracks must keep at time t of their common time [from, to]: the
  // separation, eased near the two ends (over the first and last fifth, by a smoothstep)
  // down to what their straight paths hold there, so that two singularities a key frame
  // holds closer than the separation need only part from there as they would anyway; for
  // two of the interval being routed, never more than set_caps() allows them.
  double required(const Track& a, const Track& b, double t, double from, double to) const {
    const double u = (t - from) / (to - from);
    const double ease = smoothstep(std::min(u, 1 - u) / 0.2);
    Track sa = a, sb = b;
    sa.bends.clear();
    sb.bends.clear();
    const double straight = (at(sa, t) - at(sb, t)).norm();
    double most = separation_;
    if (a.slot >= 0 && b.slot >= 0 && static_cast<size_t>(a.slot) < caps_n_ && static_cast<size_t>(b.slot) < caps_n_)
      most = caps_[static_cast<size_t>(a.slot) * caps_n_ + static_cast<size_t>(b.slot)];
    return std::min(separation_, std::max(straight, ease * most));
  }

  // A path that moves less than a tenth of the separation (the static solve's own saddles
  // and foci on a scanned surface, most of which stay put between key frames): the pairwise
  // router bends the other path round it, never it (bent, such paths pushed the next ones
  // about, and 20–26 paths' bends on CGAL's meshes never settled), and two such keep what
  // their straight paths keep (set_caps()).
  bool settled(const Track& tr) const { return tr.base_length() < 0.1 * separation_; }

  // What each two of the tracks [first, last) must keep at most (required()), their slots
  // set. Two settled paths: nothing (neither is bent; they keep what they keep). Two that
  // both key frames hold closer than the separation and whose straight paths never come
  // nearer than half of what the nearer key frame holds them (they neither cross nor pass
  // close): what their straight paths keep at their closest, so that they are not bent for
  // their own sake, only kept from being pushed closer by the others' detours. The static
  // solve's own saddles and foci on a scanned surface sit 0.02 apart where the separation
  // is 0.1 and barely move; asked to part in between, every such pair set off the router,
  // and 20–26 paths' bends never settled (CGAL's cow, camel, elephant, bear). Any other
  // two: the separation, as before, also two that part from a key frame that holds them
  // close to one that holds them farther than the separation (a sphere's sink running
  // nearly to its antipode beside a saddle, capped, made 3 bifurcations where 1 was
  // planned).
  void set_caps(std::vector<Track>& tracks, size_t first, size_t last) const {
    const size_t n = last - first;
    caps_n_ = n;
    caps_.assign(n * n, separation_);
    double tmin = std::numeric_limits<double>::infinity(), tmax = -tmin;
    for (size_t i = first; i < last; ++i) {
      tracks[i].slot = static_cast<int>(i - first);
      tmin = std::min({tmin, tracks[i].t0, tracks[i].t1}), tmax = std::max({tmax, tracks[i].t0, tracks[i].t1});
    }
    if (!(tmax > tmin)) return;
    auto time = [&](int k) { return tmin + (tmax - tmin) * k / kSamples; };
    std::vector<std::vector<Vec3>> straight(n);
    for (size_t i = 0; i < n; ++i) {
      Track tr = tracks[first + i];
      tr.bends.clear();
      for (int k = 0; k <= kSamples; ++k) straight[i].push_back(at(tr, time(k)));
    }
    auto is_keyframe = [&](double t) {
      return std::find(keyframe_times_.begin(), keyframe_times_.end(), t) != keyframe_times_.end();
    };
    for (size_t i = 0; i < n; ++i)
      for (size_t j = i + 1; j < n; ++j) {
        const Track &a = tracks[first + i], &b = tracks[first + j];
        const double from = std::max(std::min(a.t0, a.t1), std::min(b.t0, b.t1));
        const double to = std::min(std::max(a.t0, a.t1), std::max(b.t0, b.t1));
        if (!(to > from)) continue;
        if (settled(a) && settled(b)) {
          caps_[i * n + j] = caps_[j * n + i] = 0;
          continue;
        }
        if (!is_keyframe(from) || !is_keyframe(to)) continue;
        double nearer = std::numeric_limits<double>::infinity(), farther = 0, closest = nearer;
        for (int k = 0; k <= kSamples; ++k) {
          const double t = time(k);
          if (t < from || t > to) continue;
          const double d = (straight[i][static_cast<size_t>(k)] - straight[j][static_cast<size_t>(k)]).norm();
          closest = std::min(closest, d);
          if (t == from || t == to) nearer = std::min(nearer, d), farther = std::max(farther, d);
        }
        if (farther < separation_ && closest >= 0.5 * nearer) caps_[i * n + j] = caps_[j * n + i] = closest;
      }
  }

  // Over the two tracks' common time: where they come closest relative to what they must
  // keep (the smallest distance / required), with the distance and the requirement there.
  struct Approach {
    double ratio = 0, distance = 0, required = 0, t = 0, from = 0, to = 0;
  };
  std::optional<Approach> approach(const Track& a, const Track& b) const {
    const double from = std::max(std::min(a.t0, a.t1), std::min(b.t0, b.t1));
    const double to = std::min(std::max(a.t0, a.t1), std::max(b.t0, b.t1));
    if (!(to > from)) return std::nullopt;
    Approach out{std::numeric_limits<double>::infinity(), 0, 0, from, from, to};
    for (int k = 0; k <= kSamples; ++k) {
      const double t = from + (to - from) * k / kSamples;
      const double dist = (at(a, t) - at(b, t)).norm();
      const double req = required(a, b, t, from, to);
      if (req <= 0) continue;
      if (dist / req < out.ratio) out.ratio = dist / req, out.distance = dist, out.required = req, out.t = t;
    }
    return out;
  }

  // The smallest distance between two tracks over their common time (infinite without one).
  double closest(const Track& a, const Track& b) const {
    const double from = std::max(std::min(a.t0, a.t1), std::min(b.t0, b.t1));
    const double to = std::min(std::max(a.t0, a.t1), std::max(b.t0, b.t1));
    double out = std::numeric_limits<double>::infinity();
    if (!(to > from)) return out;
    for (int k = 0; k <= kSamples; ++k) {
      const double t = from + (to - from) * k / kSamples;
      out = std::min(out, (at(a, t) - at(b, t)).norm());
    }
    return out;
  }

  // Bends a's and b's paths apart so that they keep what they must; false when no detour
  // (either side, shared by length or taken by one path alone) stays inside the domain.
  // `why_not`, when false: none within kMaxDetour (one inside the domain was found), none
  // inside the domain (one parting them was found), or none parting them at all: on a
  // closed surface a detour is walked along it, and no walk keeps two points farther apart
  // in space than the part of the surface they are on is thick (CGAL's man: a knot along
  // an arm 0.045 thick, the separation 0.11).
  bool separate(Track& a, Track& b, const Approach& ap, const char*& why_not) const {
    bool capped = false, parted = false;
    const double dt = (ap.to - ap.from) / kSamples;
    const double ta = std::max(ap.from, ap.t - dt), tb = std::min(ap.to, ap.t + dt);
    const Vec3 pa = at(a, ap.t), pb = at(b, ap.t);
    const Vec3 v = (at(a, tb) - at(a, ta)) - (at(b, tb) - at(b, ta));  // relative motion
    const Vec3 normal = space_.planar() ? Vec3::UnitZ() : space_.bundle().face_normal(space_.locate(pa).face);
    Vec3 n = normal.cross(v);
    const Vec3 r = pa - pb;
    if (n.norm() <= 1e-12 * space_.diameter()) n = r - r.dot(normal) * normal;  // no relative motion: push apart
    if (n.norm() <= 1e-12 * space_.diameter()) n = space_.bundle().face_e1(space_.locate(pa).face);
    n.normalize();
    // The side the two already pass on (the left of the relative motion when they meet head on).
    const double side = r.dot(n) < -1e-12 * separation_ ? -1.0 : 1.0;
    const double la = a.base_length(), lb = b.base_length();
    std::vector<std::pair<double, double>> shares;
    if (settled(a) != settled(b)) {
      shares.emplace_back(settled(a) ? 0.0 : 1.0, settled(a) ? 1.0 : 0.0);  // only the one that moves
    } else {
      if (la + lb > 0) shares.emplace_back(la / (la + lb), lb / (la + lb));  // the shortest pair of paths
      shares.emplace_back(1.0, 0.0);
      shares.emplace_back(0.0, 1.0);
    }
    std::pair<int, int> window{0, kSamples};
    {
      auto too_close = [&](int k) {
        const double t = ap.from + (ap.to - ap.from) * k / kSamples;
        return (at(a, t) - at(b, t)).norm() < required(a, b, t, ap.from, ap.to) * (1 - 1e-9);
      };
      const int k0 = static_cast<int>(std::lround((ap.t - ap.from) / (ap.to - ap.from) * kSamples));
      window = {k0, k0};
      while (window.first > 0 && too_close(window.first - 1)) --window.first;
      while (window.second < kSamples && too_close(window.second + 1)) ++window.second;
    }
    // Each path's detour is full over the encounter (its own path parameters there).
    auto span = [&](const Track& x) {
      const double s0 = x.param(ap.from + (ap.to - ap.from) * window.first / kSamples);
      const double s1 = x.param(ap.from + (ap.to - ap.from) * window.second / kSamples);
      return std::pair{std::clamp(std::min(s0, s1), 0.15, 0.85), std::clamp(std::max(s0, s1), 0.15, 0.85)};
    };
    const auto [rise_a, fall_a] = span(a);
    const auto [rise_b, fall_b] = span(b);
    double best_cost = std::numeric_limits<double>::infinity();
    std::optional<std::pair<Track, Track>> best;
    for (const double sign : {side, -side})
      for (const auto& [wa, wb] : shares) {
        auto bent = [&](double c) {
          std::pair<Track, Track> out{a, b};
          if (wa > 0) out.first.bends.push_back({rise_a, fall_a, c * wa, sign * n});
          if (wb > 0) out.second.bends.push_back({rise_b, fall_b, c * wb, -sign * n});
          return out;
        };
        // Apart over this encounter (the samples around the closest approach that are too
        // close now): another encounter of the same two, on the other side, is the next
        // round's.
        auto apart = [&](double c) {
          const auto [x, y] = bent(c);
          for (int k = window.first; k <= window.second; ++k) {
            const double t = ap.from + (ap.to - ap.from) * k / kSamples;
            if ((at(x, t) - at(y, t)).norm() < required(x, y, t, ap.from, ap.to) * (1 - 1e-9)) return false;
          }
          return true;
        };
        double hi = ap.required;
        while (!apart(hi) && hi < 2 * space_.diameter()) hi *= 2;
        if (!apart(hi)) continue;
        parted = true;
        double lo = 0;
        for (int it = 0; it < 40; ++it) (apart(0.5 * (lo + hi)) ? hi : lo) = 0.5 * (lo + hi);
        // A margin of 2 % of the detour, so that frames between the samples keep it too.
        double c = 1.02 * hi;
        if (!apart(c)) c = hi;
        auto candidate = bent(c);
        if ((wa > 0 && !inside(candidate.first, a)) || (wb > 0 && !inside(candidate.second, b))) continue;
        // A detour more than kMaxDetour separations off the path's curve does not part the
        // two where they meet but sends one round the others (CGAL's bear: a saddle pushed
        // to and fro between two paths, then 1.15 away on a 0.27 path, its walk across the
        // body jumping): no pairwise detour, and the joint routing is tried instead.
        if ((wa > 0 && offset_size(candidate.first) > kMaxDetour * separation_) ||
            (wb > 0 && offset_size(candidate.second) > kMaxDetour * separation_)) {
          capped = true;
          continue;
        }
        // Detours that keep the two apart over their whole common time first.
        const bool everywhere = approach(candidate.first, candidate.second)->ratio >= 1 - 1e-9;
        const double cost = length(candidate.first) - length(a) + length(candidate.second) - length(b) +
                            (everywhere ? 0.0 : 4 * space_.diameter());
        if (cost < best_cost) best_cost = cost, best = std::move(candidate);
      }
    if (!best) {
      why_not = capped   ? "no detour within twice the separation of the paths"
                : parted ? "no detour inside the domain"
                         : "no detour along the surface";
      if (space_.planar() && !capped && !parted) why_not = "no detour inside the domain";
      return false;
    }
    a = std::move(best->first);
    b = std::move(best->second);
    return true;
  }

  // Routes the tracks [first, last) of one interval, keeping them apart from each other and
  // from `obstacles` (the interval's saddle–node templates, as tracks that stay put while
  // the template holds; a template's own pair is not kept from it). First one pair at a
  // time (separate(), closest first); when that does not settle, or leaves a path too near
  // a template, all the interval's paths at once (joint()). When neither keeps them apart,
  // leaves the interval's paths straight and returns why, in one sentence naming `where`.
  // `how` says which routing held: "straight" (nothing came too close), "pairwise" or "joint".
  // Null when the paths are kept apart; else why not, in one sentence, and `place` says where.
  std::optional<std::string> route(std::vector<Track>& tracks, size_t first, size_t last,
                                   const std::vector<Track>& obstacles, const Scene& scene, const std::string& where,
                                   const std::string& interval, std::string& how,
                                   std::optional<KeyframeIntervalReport::Collision>& place) const {
    place.reset();
    how = "straight";
    if (separation_ <= 0) return std::nullopt;
    set_caps(tracks, first, last);
    const std::vector<Track> before(tracks.begin() + static_cast<std::ptrdiff_t>(first),
                                    tracks.begin() + static_cast<std::ptrdiff_t>(last));
    const size_t n = last - first;
    // Rounds: 8n² + 8, at most 300 (a round bends two paths, each bend making the paths
    // costlier to place: a knot on CGAL's cow whose static solves hold 26 singularities
    // took 0.3 s a round, and 8n² + 8 = 5,416 rounds would have run about half an hour
    // before falling back; the tests' scenes take at most 114 rounds, with 6 paths, and
    // the sphere knot 125 with 4).
    const int rounds = static_cast<int>(std::min(8 * n * n + 8, size_t{300}));
    const char* why = nullptr;
    const char* const rounds_out = "no set of detours tried";
    size_t wi = 0, wj = 0;
    Approach wap;
    // A cheap test first: the paths spanning the whole interval at kCoarse + 1 times; two
    // whose samples stay farther apart than the separation plus twice the largest step of
    // each between samples cannot come within it (approach() is 257 samples of both, each
    // a point location on a surface: 0.3 s a round for the elephant's 190 pairs).
    constexpr int kCoarse = 64;
    double tmin = std::numeric_limits<double>::infinity(), tmax = -tmin;
    for (size_t i = first; i < last; ++i)
      tmin = std::min({tmin, tracks[i].t0, tracks[i].t1}), tmax = std::max({tmax, tracks[i].t0, tracks[i].t1});
    std::vector<std::vector<Vec3>> coarse(n);
    std::vector<double> step(n, 0.0);
    auto spans_all = [&](const Track& tr) { return std::min(tr.t0, tr.t1) == tmin && std::max(tr.t0, tr.t1) == tmax; };
    auto far_apart = [&](size_t i, size_t j) {
      if (coarse[i - first].empty() || coarse[j - first].empty()) return false;
      double closest = std::numeric_limits<double>::infinity();
      for (int k = 0; k <= kCoarse; ++k)
        closest = std::min(closest, (coarse[i - first][static_cast<size_t>(k)] - coarse[j - first][static_cast<size_t>(k)]).norm());
      return closest > separation_ + 2 * (step[i - first] + step[j - first]);
    };
    // Each round bends two paths (separate()): only their samples and the pairs they are in
    // are looked at again (the same pair chosen as when every pair was, to the bit; that
    // cow's 40 rounds 14.9 → 13.0 s, the rest separate()'s search for a detour).
    std::vector<char> changed(n, 1);
    std::vector<std::optional<Approach>> approaches(n * n);
    for (int round = 0;; ++round) {
      if (checkpoint_) checkpoint_();
      for (size_t i = first; i < last; ++i) {
        if (!changed[i - first]) continue;
        coarse[i - first].clear();
        step[i - first] = 0;
        if (!spans_all(tracks[i])) continue;
        for (int k = 0; k <= kCoarse; ++k) {
          coarse[i - first].push_back(at(tracks[i], tmin + (tmax - tmin) * k / kCoarse));
          if (k > 0)
            step[i - first] = std::max(step[i - first], (coarse[i - first][static_cast<size_t>(k)] -
                                                         coarse[i - first][static_cast<size_t>(k) - 1]).norm());
        }
      }
      // The pair that comes closest relative to what it must keep, first.
      double worst = 1 - 1e-6;
      for (size_t i = first; i < last; ++i)
        for (size_t j = i + 1; j < last; ++j) {
          if (tracks[i].group >= 0 && tracks[i].group == tracks[j].group) continue;
          std::optional<Approach>& ap = approaches[(i - first) * n + (j - first)];
          if (changed[i - first] || changed[j - first])
            ap = far_apart(i, j) ? std::nullopt : approach(tracks[i], tracks[j]);
          if (ap && ap->ratio < worst) worst = ap->ratio, wi = i, wj = j, wap = *ap;
        }
      std::fill(changed.begin(), changed.end(), 0);
      if (worst >= 1 - 1e-6) break;
      if (round == 0) how = "pairwise";
      const char* why_not = nullptr;
      why = round >= rounds                                    ? rounds_out
            : separate(tracks[wi], tracks[wj], wap, why_not) ? nullptr
                                                             : why_not;
      changed[wi - first] = changed[wj - first] = 1;
      if (why) break;
    }
    // The templates: the worst path that comes too near one, if any.
    size_t oi = 0, oj = 0;
    double o_worst = 1 - 1e-6;
    Approach oap;
    if (!why)
      for (size_t i = first; i < last; ++i)
        for (size_t j = 0; j < obstacles.size(); ++j) {
          if (tracks[i].group >= 0 && tracks[i].group == obstacles[j].group) continue;
          const auto ap = approach(tracks[i], obstacles[j]);
          if (ap && ap->ratio < o_worst) o_worst = ap->ratio, oi = i, oj = j, oap = *ap;
        }
    if (!why && o_worst >= 1 - 1e-6) {
      // Apart, but the +1 singularities' phases may drift a turn apart (three or more
      // passing each other): then the field needs bifurcations to join them. Routed together
      // when that keeps the drift smaller.
      if (how == "straight") return std::nullopt;
      const double drift = interval_phase_error(tracks, first, last);
      if (drift <= 0.5 * std::numbers::pi) return std::nullopt;
      const std::vector<Track> pairwise(tracks.begin() + static_cast<std::ptrdiff_t>(first),
                                        tracks.begin() + static_cast<std::ptrdiff_t>(last));
      if (joint_search_ && joint(tracks, first, last, obstacles) && interval_phase_error(tracks, first, last) < drift) {
        how = "joint";
        return std::nullopt;
      }
      std::copy(pairwise.begin(), pairwise.end(), tracks.begin() + static_cast<std::ptrdiff_t>(first));
      return std::nullopt;
    }
    // Jointly, from the pairwise bends when they held, else from the straight paths.
    const Track a = tracks[why ? wi : oi];
    const Track b = why ? tracks[wj] : obstacles[oj];
    if (why) std::copy(before.begin(), before.end(), tracks.begin() + static_cast<std::ptrdiff_t>(first));
    // The key frames' own collision: two paths that no detour of their own parts, already
    // closer than the separation at a key frame (where their ends are fixed), are not
    // parted by bending the others either; the joint search (seconds on a surface with
    // tens of paths) is not tried. Not where the rounds ran out (detours did part them,
    // and chased each other: CGAL's mushroom's three paths at 0.9996 of the separation
    // after 300 rounds are routed together and guided), nor for a pair that need keep only
    // what its straight paths keep (set_caps(): the others' detours pushed it closer, which
    // routing them together may undo).
    std::string held;
    if (why && why != rounds_out && caps_[(wi - first) * n + (wj - first)] >= separation_) {
      const double from = wap.from, to = wap.to;
      for (const double t : {from, to}) {
        const double d = (at(before[wi - first], t) - at(before[wj - first], t)).norm();
        const bool keyframe = t == std::min(a.t0, a.t1) || t == std::max(a.t0, a.t1);
        if (keyframe && d < separation_ * (1 - 1e-9) && held.empty())
          held = fmt::format("no detour (the key frame at t = {:.3g} holds them {:.3g} apart already)", t, d);
      }
      if (!held.empty()) why = held.c_str();
    }
    if (held.empty() && joint_search_ && joint(tracks, first, last, obstacles)) {
      how = "joint";
      return std::nullopt;
    }
    how = "straight";
    std::copy(before.begin(), before.end(), tracks.begin() + static_cast<std::ptrdiff_t>(first));
    const bool planar = space_.planar();
    const double unit = space_.diameter();
    {
      const Approach& ap = why ? wap : oap;
      KeyframeIntervalReport::Collision c;
      c.t = ap.t;
      c.points = {at(a, ap.t), at(b, ap.t)};
      c.types = {a.type, b.type};
      c.template_ = !why;
      c.distance = ap.distance;
      c.required = ap.required;
      place = c;
    }
    if (why) {
      // On a surface, where they pass on a part narrower than what they must keep, say so:
      // no separation that wide can be kept there, whatever the routing.
      std::string across;
      if (!planar) {
        const double width = width_where_they_pass(before[wi - first], before[wj - first], wap.t, wap.from, wap.to);
        if (width < wap.required)
          across = fmt::format(" on a part of the surface {:.3g} across (a cross-section where they pass)", width);
      }
      return fmt::format(
          "{}: {}: {} the paths of the {} from {} to {} and the {} from {} to {} come {:.3g} apart at t = {:.3g}{}, and "
          "{} keeps them {:.3g} apart, so the paths stay straight and the singularities meet; set a smaller "
          "solver.path_separation, link them differently (solver.links) or add a key frame between",
          scene.label(), where, interval, to_string(a.type), describe_point(a.p0, planar, unit),
          describe_point(a.p1, planar, unit), to_string(b.type), describe_point(b.p0, planar, unit),
          describe_point(b.p1, planar, unit), wap.distance, wap.t, across, why, wap.required);
    }
    return fmt::format(
        "{}: {}: {} the path of the {} from {} to {} comes {:.3g} from the saddle–node template at {} at t = {:.3g}, and "
        "no set of detours keeps it {:.3g} away, so the paths stay straight; set a smaller solver.path_separation, "
        "another solver.bifurcation_times or add a key frame between",
        scene.label(), where, interval, to_string(a.type), describe_point(a.p0, planar, unit),
        describe_point(a.p1, planar, unit), oap.distance, describe_point(b.p0, planar, unit), oap.t, oap.required);
  }

  // All the interval's paths at once: each track of [first, last) gets a joint detour
  // Σ_k c_k · wave_shape(k, s) (kWaves shapes; c_k in the tangent plane at the path's
  // middle), chosen by Levenberg–Marquardt to minimise the bending Σ k⁴ |c_k|² (weighted
  // 1e-3) plus the squared shortfall of every pair (tracks and obstacles, at 257 times of
  // the interval) from 1.03 × what it must keep, and of every path from 1.02 × its
  // boundary margin (as inside()). Started from each choice of side for the moving paths
  // (each bent by the separation to its left or right; all of them up to 5 moving, else
  // four patterns) and from no detour; of the results that keep every pair apart at 257
  // times of its common time (approach()) and stay inside (inside()), the one that adds
  // least length is kept. False, tracks unchanged, when none does.
  static constexpr int kWaves = 4;
  static constexpr int kJointSteps = 1200;
  bool joint(std::vector<Track>& tracks, size_t first, size_t last, const std::vector<Track>& obstacles) const {
    // The paths that move get detours; the settled ones (settled()) stand in the way with
    // the templates (the man's knot: 50 paths, 12 that move, 8 unknowns each).
    std::vector<size_t> order;
    for (size_t i = first; i < last; ++i)
      if (!settled(tracks[i])) order.push_back(i);
    const size_t n = order.size();
    if (n == 0) return false;
    for (size_t i = first; i < last; ++i)
      if (settled(tracks[i])) order.push_back(i);
    std::vector<Track> items;
    for (const size_t i : order) items.push_back(tracks[i]);
    for (Track& tr : items) tr.wave.clear();
    items.insert(items.end(), obstacles.begin(), obstacles.end());
    const size_t m = items.size();
    const int nv = 2 * kWaves;  // variables per moving track
    const int N = nv * static_cast<int>(n);
    // Tangent axes at each path's middle and the side each may be bent to.
    std::vector<Vec3> ax1(n), ax2(n), left(n, Vec3::Zero());
    for (size_t i = 0; i < n; ++i) {
      const Vec3 mid = at(items[i], 0.5 * (items[i].t0 + items[i].t1));
      const int f = space_.locate(mid).face;
      const Vec3 normal = space_.planar() ? Vec3::UnitZ() : space_.bundle().face_normal(f);
      ax1[i] = space_.planar() ? Vec3::UnitX() : space_.bundle().face_e1(f);
      ax2[i] = normal.cross(ax1[i]);
      // The path's direction at its middle (on a surface its curve's; planar the segment's).
      const Vec3 d = items[i].curve || items[i].bent_through() ? Vec3(items[i].base(0.51) - items[i].base(0.49))
                                                               : Vec3(items[i].p1 - items[i].p0);
      const Vec3 l = normal.cross(d);
      if (l.norm() > 1e-9 * space_.diameter()) left[i] = l.normalized();
    }
    // One time grid for the interval.
    double tmin = std::numeric_limits<double>::infinity(), tmax = -tmin;
    for (const Track& tr : items) tmin = std::min({tmin, tr.t0, tr.t1}), tmax = std::max({tmax, tr.t0, tr.t1});
    std::vector<double> grid(kSamples + 1);
    for (int g = 0; g <= kSamples; ++g) grid[static_cast<size_t>(g)] = tmin + (tmax - tmin) * g / kSamples;
    const Ease warp = interval_ease(keyframe_times_, tmin, tmax);
    auto present = [&](const Track& tr, double t) { return t >= std::min(tr.t0, tr.t1) && t <= std::max(tr.t0, tr.t1); };
    struct Sample {
      size_t i, j;
      int g;
      double required;
    };
    std::vector<Sample> samples;
    for (size_t i = 0; i < m; ++i)
      for (size_t j = i + 1; j < m; ++j) {
        if (i >= n && j >= n) continue;
        if (items[i].group >= 0 && items[i].group == items[j].group) continue;
        const double from = std::max(std::min(items[i].t0, items[i].t1), std::min(items[j].t0, items[j].t1));
        const double to = std::min(std::max(items[i].t0, items[i].t1), std::max(items[j].t0, items[j].t1));
        if (!(to > from)) continue;
        for (int g = 0; g <= kSamples; ++g) {
          const double t = grid[static_cast<size_t>(g)];
          if (t < from || t > to) continue;
          const double req = required(items[i], items[j], t, from, to);
          if (req > 0) samples.push_back({i, j, g, req});
        }
      }
    std::vector<double> margin(n, 0.5 * separation_);
    if (!boundary_.empty())
      for (size_t i = 0; i < n; ++i) {
        Track straight = items[i];
        straight.bends.clear();
        for (int k = 0; k <= kSamples; k += 4) {
          const Vec3 raw = straight.raw(static_cast<double>(k) / kSamples);
          margin[i] = std::min(margin[i], boundary_distance(surface_position(space_.mesh(), space_.locate(raw))));
        }
      }
    auto apply = [&](const Eigen::VectorXd& x, std::vector<Track>& out) {
      for (size_t i = 0; i < n; ++i) {
        out[i].wave.assign(kWaves, Vec3::Zero());
        for (int k = 0; k < kWaves; ++k)
          out[i].wave[static_cast<size_t>(k)] = x(static_cast<int>(i) * nv + 2 * k) * ax1[i] +
                                                x(static_cast<int>(i) * nv + 2 * k + 1) * ax2[i];
      }
    };
    const double lambda = 1e-3;
    const PhaseSet whole = whole_tracks(items, order.size(), tmin, tmax, true);  // the settled too
    std::vector<size_t> plus;
    for (const size_t i : whole)
      if (items[i].index > 0) plus.push_back(i);
    // Residuals and their Jacobian (sparse rows: the variables of at most two tracks).
    auto evaluate = [&](const Eigen::VectorXd& x, double target, Eigen::MatrixXd* jtj, Eigen::VectorXd* jtr) {
      if (checkpoint_) checkpoint_();
      std::vector<Track> cur = items;
      apply(x, cur);
      std::vector<std::vector<Vec3>> pos(m, std::vector<Vec3>(kSamples + 1, Vec3::Zero()));
      std::vector<std::vector<int>> faces(space_.planar() ? 0 : m, std::vector<int>(kSamples + 1, -1));
      for (size_t i = 0; i < m; ++i)
        for (int g = 0; g <= kSamples; ++g)
          if (present(cur[i], grid[static_cast<size_t>(g)]))
            pos[i][static_cast<size_t>(g)] = at(cur[i], grid[static_cast<size_t>(g)],
                                                faces.empty() ? nullptr : &faces[i][static_cast<size_t>(g)]);
      double cost = 0;
      if (jtj) jtj->setZero(N, N), jtr->setZero(N);
      auto add_row = [&](double r, const std::vector<std::pair<int, double>>& row) {
        cost += r * r;
        if (!jtj) return;
        for (const auto& [a, va] : row) {
          (*jtr)(a) += va * r;
          for (const auto& [b, vb] : row) (*jtj)(a, b) += va * vb;
        }
      };
      std::vector<std::pair<int, double>> row;
      auto grad = [&](size_t i, double s, const Vec3& dir, double sign) {
        if (i >= n) return;
        for (int k = 0; k < kWaves; ++k) {
          const double w = sign * wave_shape(k + 1, s);
          row.emplace_back(static_cast<int>(i) * nv + 2 * k, w * ax1[i].dot(dir));
          row.emplace_back(static_cast<int>(i) * nv + 2 * k + 1, w * ax2[i].dot(dir));
        }
      };
      for (const Sample& sm : samples) {
        const Vec3 d = pos[sm.i][static_cast<size_t>(sm.g)] - pos[sm.j][static_cast<size_t>(sm.g)];
        const double dist = d.norm();
        const double r = target * sm.required - dist;
        if (r <= 0) continue;
        row.clear();
        const Vec3 u = dist > 0 ? Vec3(d / dist) : left[std::min(sm.i, n - 1)];
        const double t = grid[static_cast<size_t>(sm.g)];
        grad(sm.i, cur[sm.i].param(t), u, -1.0);
        grad(sm.j, cur[sm.j].param(t), u, 1.0);
        add_row(r, row);
      }
      if (!boundary_.empty())
        for (size_t i = 0; i < n; ++i)
          for (int k = 0; k <= kSamples; k += 4) {
            const double s = static_cast<double>(k) / kSamples;
            const Vec3 raw = cur[i].raw(s);
            const Vec3 on = surface_position(space_.mesh(), space_.locate(raw));
            const auto [dist, near] = boundary_nearest(on);
            const bool out = space_.planar() && (on - raw).norm() > 1e-9 * space_.diameter();
            const double r = 1.02 * margin[i] - (out ? -(on - raw).norm() : dist);
            if (r <= 0) continue;
            Vec3 dir = out ? Vec3(on - raw) : Vec3(on - near);
            if (dir.norm() == 0) continue;
            dir.normalize();
            row.clear();
            grad(i, s, dir, -1.0);
            add_row(r, row);
          }
      if (plus.size() >= 2) {
        std::vector<std::vector<double>> phi;
        std::vector<std::vector<std::vector<Vec3>>> dphi;
        phases(cur, whole, pos, phi, jtj ? &dphi : nullptr, faces.empty() ? nullptr : &faces);
        const PhaseDrifts drift{phi, plus};
        const double wph = 0.05 * separation_;
        const std::vector<double> targets = drift.targets(kSamples);
        for (size_t q = 0; q < plus.size(); ++q) {
          const size_t i = plus[q];
          const double end_drift = targets[q];
          for (size_t g = 4; g < static_cast<size_t>(kSamples); g += 4) {
            const double r = wph * (drift(i, g) - warp(static_cast<double>(g) / kSamples) * end_drift);
            row.clear();
            if (jtj)
              for (size_t w = 0; w < whole.size(); ++w) {
                const size_t j = whole.tracks[w];
                Vec3 v = dphi[i][g][w];
                for (const size_t k : plus) v -= dphi[k][g][w] / static_cast<double>(plus.size());
                grad(j, cur[j].param(grid[g]), wph * v, 1.0);
              }
            add_row(r, row);
          }
        }
      }
      for (size_t i = 0; i < n; ++i)
        for (int k = 0; k < kWaves; ++k)
          for (int c = 0; c < 2; ++c) {
            const int v = static_cast<int>(i) * nv + 2 * k + c;
            const double w = std::sqrt(lambda) * (k + 1) * (k + 1);
            row.assign(1, {v, w});
            add_row(w * x(v), row);
          }
      return cost;
    };
    // Seeds: each moving path to one side (or none).
    std::vector<size_t> moving;
    for (size_t i = 0; i < n; ++i)
      if (left[i].norm() > 0) moving.push_back(i);
    std::vector<std::vector<double>> patterns;
    if (moving.size() <= 5) {
      for (unsigned bits = 0; bits < (1u << moving.size()); ++bits) {
        std::vector<double> p;
        for (size_t q = 0; q < moving.size(); ++q) p.push_back(bits >> q & 1u ? -1.0 : 1.0);
        patterns.push_back(p);
      }
    } else {
      for (int kind = 0; kind < 4; ++kind) {
        std::vector<double> p;
        for (size_t q = 0; q < moving.size(); ++q)
          p.push_back(kind == 0 ? 1.0 : kind == 1 ? -1.0 : (q % 2 == static_cast<size_t>(kind - 2)) ? 1.0 : -1.0);
        patterns.push_back(p);
      }
    }
    patterns.emplace_back();  // no detour to start from
    double best_cost = std::numeric_limits<double>::infinity();
    std::optional<std::vector<Track>> best;
    // The budget: kJointSteps Levenberg–Marquardt steps over all the starts (each step
    // places every path at 257 times, so the search's time grows with the number of paths
    // alone); a start begun when it is spent is not tried.
    int steps = 0;
    for (const double target : {1.03, 1.1}) {
      for (const std::vector<double>& pattern : patterns) {
        if (steps >= kJointSteps) break;
        Eigen::VectorXd x = Eigen::VectorXd::Zero(N);
        for (size_t q = 0; q < pattern.size(); ++q) {
          const size_t i = moving[q];
          x(static_cast<int>(i) * nv) = pattern[q] * separation_ * left[i].dot(ax1[i]);
          x(static_cast<int>(i) * nv + 1) = pattern[q] * separation_ * left[i].dot(ax2[i]);
        }
        Eigen::MatrixXd jtj(N, N);
        Eigen::VectorXd jtr(N);
        double cost = evaluate(x, target, &jtj, &jtr);
        double mu = 1e-3;
        for (int it = 0; it < 200 && mu < 1e12 && steps < kJointSteps; ++it, ++steps) {
          Eigen::MatrixXd a = jtj;
          for (int v = 0; v < N; ++v) a(v, v) += mu * (jtj(v, v) + 1e-9);
          const Eigen::VectorXd step = a.ldlt().solve(-jtr);
          const Eigen::VectorXd y = x + step;
          const double next = evaluate(y, target, nullptr, nullptr);
          if (next < cost) {
            const bool done = cost - next < 1e-12 * cost;
            x = y;
            cost = evaluate(x, target, &jtj, &jtr);
            mu = std::max(mu / 3, 1e-9);
            if (done) break;
          } else {
            mu *= 4;
          }
        }
        std::vector<Track> cand = items;
        apply(x, cand);
        bool ok = true;
        for (size_t i = 0; i < n && ok; ++i) ok = inside(cand[i], items[i]);
        for (size_t i = 0; i < n && ok; ++i)
          for (size_t j = i + 1; j < m && ok; ++j) {
            if (cand[i].group >= 0 && cand[i].group == cand[j].group) continue;
            const auto ap = approach(cand[i], cand[j]);
            ok = !ap || ap->ratio >= 1 - 1e-9;
          }
        if (!ok) continue;
        // The least bending and phase drift (the objective; the shortfall is within the margin).
        if (cost < best_cost) best_cost = cost, best = std::move(cand);
      }
      if (best) break;
    }
    if (!best) return false;
    for (size_t q = 0; q < order.size(); ++q) tracks[order[q]] = (*best)[q];
    return true;
  }

  // The tracks whose phases are modelled (whole_tracks(), below) and which pairs of them
  // enter each other's phase (m × m over the interval's items).
  struct PhaseSet {
    std::vector<size_t> tracks;
    std::vector<char> pairs;
    size_t m = 0;
    bool pair(size_t i, size_t j) const { return pairs[i * m + j] != 0; }
    std::vector<size_t>::const_iterator begin() const { return tracks.begin(); }
    std::vector<size_t>::const_iterator end() const { return tracks.end(); }
    size_t size() const { return tracks.size(); }
  };

  // The phases of an interval's tracks in the product model of a field with their
  // singularities, f(z) = c(t) Π_j g_j(z), g_j = z − p_j for index +1 and conj(z − p_j) for
  // −1 (only the tracks that span the whole interval, `whole`): at singularity i the field
  // is c · e^{iΦ_i} · g_i(z − p_i) with Φ_i = Σ_{j≠i} ind_j arg(p_i − p_j) (directions in
  // the tangent plane, in i's reference frame). A node, focus or center keeps its type only
  // if c e^{iΦ_i} keeps its argument; c is free (the far field may turn), so what matters is
  // each Φ_i's drift from the others' mean. `pos[i][g]`: track i at the grid's sample g.
  // Fills phi[i][g] (unwrapped along g) for the tracks of `whole`; with `dphi`, also
  // dphi[i][g][w] = ∂Φ_i/∂p_j, j = whole.tracks[w] (world vectors, tangent; indexed by the
  // place in `whole`, since on a surface with tens of settled paths few of them wind).
  // `faces[i][g]`: the face holding pos[i][g] on a surface, where the caller has it.
  void phases(const std::vector<Track>& items, const PhaseSet& whole,
              const std::vector<std::vector<Vec3>>& pos, std::vector<std::vector<double>>& phi,
              std::vector<std::vector<std::vector<Vec3>>>* dphi,
              const std::vector<std::vector<int>>* faces = nullptr) const {
    const size_t G = pos.empty() ? 0 : pos[0].size();
    phi.assign(items.size(), std::vector<double>(G, 0.0));
    if (dphi) {
      dphi->assign(items.size(), {});
      for (const size_t i : whole) (*dphi)[i].assign(G, std::vector<Vec3>(whole.size(), Vec3::Zero()));
    }
    const TangentBundle& bundle = space_.bundle();
    for (size_t wi = 0; wi < whole.size(); ++wi) {
      const size_t i = whole.tracks[wi];
      for (size_t g = 0; g < G; ++g) {
        // Directions in the tangent plane of the face holding p_i, from i's reference axis.
        int face = -1;
        cplx cu(1, 0);
        if (!space_.planar()) {
          face = faces ? (*faces)[i][g] : space_.locate(pos[i][g]).face;
          const cplx c = bundle.world_to_face(face, items[i].ref_e1);
          if (std::abs(c) > 0) cu = c / std::abs(c);
        }
        double sum = 0;
        for (size_t wj = 0; wj < whole.size(); ++wj) {
          const size_t j = whole.tracks[wj];
          if (j == i || !whole.pair(i, j)) continue;
          const Vec3 d = pos[i][g] - pos[j][g];
          if (d.norm() <= 1e-12 * space_.diameter()) continue;
          Vec3 gr;
          double arg = 0;
          if (face < 0) {
            gr = Vec3(-d.y(), d.x(), 0) / d.squaredNorm();
            arg = std::atan2(d.y(), d.x());
          } else {
            gr = bundle.face_normal(face).cross(d) / d.squaredNorm();
            arg = std::arg(bundle.world_to_face(face, d) * std::conj(cu));
          }
          sum += items[j].index * arg;
          if (dphi) {
            (*dphi)[i][g][wi] += items[j].index * gr;
            (*dphi)[i][g][wj] -= items[j].index * gr;
          }
        }
        phi[i][g] = g == 0 ? sum : phi[i][g - 1] + std::remainder(sum - phi[i][g - 1], 2 * std::numbers::pi);
      }
    }
  }
  // The tracks of items[0, n) that span the whole interval [tmin, tmax], and the pairs of
  // them whose directions enter each other's phase. On a planar domain every pair (the
  // product model). On a surface none, except for the joint search (`winding`): there the
  // directions to far singularities in one tangent plane do not make the product model (on
  // a closed surface a chord to the far side is nearly normal to it, and its direction
  // swings as either moves), but a node's type needs the phase's change alone, and a far
  // pair's direction hardly changes; so a pair counts where their relative position on their
  // paths before detours (base()) moves by more than they come close, i.e. where one can
  // wind round the other. CGAL's mushroom: a source and a center trading places round a
  // saddle, routed jointly without phases, the source wound a whole turn more than the
  // center; the surface guide then cannot keep their types (PhaseCheck::start) and the
  // center drifted into a focus and back, with limit cycles (2 Hopf events not asked for).
  // Not the other uses (the pass that sends paths already apart to the joint search when
  // their phases drift, the saddles' turns): on CGAL's blobby that pass bent a focus's
  // pairwise-routed path off the surface.
  PhaseSet whole_tracks(const std::vector<Track>& items, size_t n, double tmin, double tmax,
                        bool winding = false) const {
    PhaseSet out;
    out.m = items.size();
    out.pairs.assign(out.m * out.m, space_.planar() ? 1 : 0);
    if (!space_.planar() && !winding) return out;
    for (size_t i = 0; i < n; ++i)
      if (std::min(items[i].t0, items[i].t1) <= tmin && std::max(items[i].t0, items[i].t1) >= tmax) out.tracks.push_back(i);
    if (space_.planar()) return out;
    constexpr int kWinding = 32;
    auto base_at = [](const Track& tr, double t) { return tr.base(tr.param(t)); };
    for (const size_t i : out.tracks)
      for (const size_t j : out.tracks) {
        if (j <= i) continue;
        double closest = std::numeric_limits<double>::infinity(), moved = 0;
        const Vec3 d0 = base_at(items[i], tmin) - base_at(items[j], tmin);
        for (int k = 0; k <= kWinding; ++k) {
          const double t = tmin + (tmax - tmin) * k / kWinding;
          const Vec3 d = base_at(items[i], t) - base_at(items[j], t);
          closest = std::min(closest, d.norm());
          moved = std::max(moved, (d - d0).norm());
        }
        if (moved > closest) out.pairs[i * out.m + j] = out.pairs[j * out.m + i] = 1;
      }
    // A track that winds round none has no phase to keep against the others.
    std::vector<size_t> winds;
    for (const size_t i : out.tracks)
      if (std::any_of(out.tracks.begin(), out.tracks.end(), [&](size_t j) { return out.pair(i, j); }))
        winds.push_back(i);
    out.tracks = std::move(winds);
    return out;
  }
  // The drift of the +1 tracks' phases from their mean (D_i(g) = Φ_i(g) − Φ_i(0) −
  // mean_k(Φ_k(g) − Φ_k(0))) beyond what the key frames need (u(g) · T_i, T_i the
  // phase_targets() of the D_i(end), u the interval's warp of time, Ease): the largest over
  // the +1 tracks of `whole` and the samples.
  double phase_error(const std::vector<Track>& items, const PhaseSet& whole,
                     const std::vector<std::vector<Vec3>>& pos, const Ease& warp) const {
    std::vector<size_t> plus;
    for (const size_t i : whole)
      if (items[i].index > 0) plus.push_back(i);
    if (plus.size() < 2) return 0;
    std::vector<std::vector<double>> phi;
    phases(items, whole, pos, phi, nullptr);
    const size_t G = pos[0].size();
    const PhaseDrifts drift{phi, plus};
    double out = 0;
    const std::vector<double> targets = drift.targets(G - 1);
    for (size_t q = 0; q < plus.size(); ++q) {
      const size_t i = plus[q];
      const double target = targets[q];
      for (size_t g = 0; g < G; ++g)
        out = std::max(out, std::abs(drift(i, g) - warp(static_cast<double>(g) / static_cast<double>(G - 1)) * target));
    }
    return out;
  }
  // Positions of tracks [first, last) on the interval's grid of kSamples + 1 times.
  std::vector<std::vector<Vec3>> on_grid(const std::vector<Track>& items, double tmin, double tmax) const {
    std::vector<std::vector<Vec3>> pos(items.size(), std::vector<Vec3>(kSamples + 1, Vec3::Zero()));
    for (size_t i = 0; i < items.size(); ++i)
      for (int g = 0; g <= kSamples; ++g) {
        const double t = tmin + (tmax - tmin) * g / kSamples;
        if (t >= std::min(items[i].t0, items[i].t1) && t <= std::max(items[i].t0, items[i].t1))
          pos[i][static_cast<size_t>(g)] = at(items[i], t);
      }
    return pos;
  }
  static std::pair<double, double> span_of(const std::vector<Track>& items) {
    double tmin = std::numeric_limits<double>::infinity(), tmax = -tmin;
    for (const Track& tr : items) tmin = std::min({tmin, tr.t0, tr.t1}), tmax = std::max({tmax, tr.t0, tr.t1});
    return {tmin, tmax};
  }
  // The interval's phase error (phase_error) as routed now.
  double interval_phase_error(const std::vector<Track>& tracks, size_t first, size_t last) const {
    const std::vector<Track> items(tracks.begin() + static_cast<std::ptrdiff_t>(first),
                                   tracks.begin() + static_cast<std::ptrdiff_t>(last));
    if (items.empty()) return 0;
    const auto [tmin, tmax] = span_of(items);
    return phase_error(items, whole_tracks(items, items.size(), tmin, tmax), on_grid(items, tmin, tmax),
                       interval_ease(keyframe_times_, tmin, tmax));
  }

  // Fills the `turn` of each saddle that spans the whole interval: in the product model
  // its β is c · e^{iΦ_s}, so it turns by Φ_s's change plus c's, c's taken as minus the
  // mean change of the +1 tracks' Φ (which keeps their types). A saddle between two
  // neighbours that move round it keeps its axes towards them, instead of keeping the key
  // frames' axes.
  void turn_with_neighbours(std::vector<Track>& tracks, size_t first, size_t last) const {
    const std::vector<Track> items(tracks.begin() + static_cast<std::ptrdiff_t>(first),
                                   tracks.begin() + static_cast<std::ptrdiff_t>(last));
    if (items.size() < 2) return;
    const auto [tmin, tmax] = span_of(items);
    const PhaseSet whole = whole_tracks(items, items.size(), tmin, tmax);
    const std::vector<std::vector<Vec3>> pos = on_grid(items, tmin, tmax);
    std::vector<std::vector<double>> phi;
    phases(items, whole, pos, phi, nullptr);
    std::vector<size_t> plus;
    for (const size_t i : whole)
      if (items[i].index > 0) plus.push_back(i);
    for (const size_t i : whole) {
      if (items[i].index >= 0 || whole.size() < 2) continue;
      Track& tr = tracks[first + i];
      tr.turn.assign(kSamples + 1, 0.0);
      for (size_t g = 0; g <= static_cast<size_t>(kSamples); ++g) {
        double mean = 0;
        for (const size_t k : plus) mean += phi[k][g] - phi[k][0];
        if (!plus.empty()) mean /= static_cast<double>(plus.size());
        // Sampled from the track's first end (t0, the key frame it leaves).
        const size_t at_g = tr.t0 <= tr.t1 ? g : static_cast<size_t>(kSamples) - g;
        tr.turn[g] = phi[i][at_g] - phi[i][tr.t0 <= tr.t1 ? 0 : static_cast<size_t>(kSamples)] - mean;
      }
      if (tr.t0 > tr.t1) {
        // mean was taken at the grid's g, not at_g: redo in the track's direction.
        for (size_t g = 0; g <= static_cast<size_t>(kSamples); ++g) {
          const size_t at_g = static_cast<size_t>(kSamples) - g;
          double mean = 0;
          for (const size_t k : plus) mean += phi[k][at_g] - phi[k][static_cast<size_t>(kSamples)];
          if (!plus.empty()) mean /= static_cast<double>(plus.size());
          tr.turn[g] = phi[i][at_g] - phi[i][static_cast<size_t>(kSamples)] - mean;
        }
      }
    }
  }

  // Largest distance of a track's path from its path before detours (the straight segment,
  // on a surface its curve; 0 when not bent).
  double detour(const Track& tr) const {
    double out = 0;
    for (int k = 0; k <= kSamples; ++k) {
      const double s = static_cast<double>(k) / kSamples;
      out = std::max(out, (tr.raw(s) - tr.base(s)).norm());
    }
    return out;
  }

private:
  double length(const Track& tr) const {
    double out = 0;
    Vec3 prev = at(tr, tr.t0);
    for (int k = 1; k <= kSamples; ++k) {
      const Vec3 p = at(tr, tr.t0 + (tr.t1 - tr.t0) * k / kSamples);
      out += (p - prev).norm();
      prev = p;
    }
    return out;
  }

  // Across how wide a part of the surface the two paths pass each other at time t: the
  // widest chord of the surface's cross-section through their midpoint, in the plane normal
  // to their relative motion (its part along the surface there), walked face to face from
  // the midpoint's face. Infinity where that section does not close (it runs into the
  // boundary: an open sheet), or the two do not move relative to each other. Two
  // singularities that trade places along an arm are at some time on one such section,
  // where no two points are farther apart than its widest chord: no detour parts them
  // more (CGAL's man: a knot along an arm 0.045 across, the separation 0.113).
  double width_where_they_pass(const Track& a, const Track& b, double t, double from, double to) const {
    const double inf = std::numeric_limits<double>::infinity();
    const double dt = (to - from) / kSamples;
    const double t0 = std::max(from, t - dt), t1 = std::min(to, t + dt);
    const Vec3 mid = 0.5 * (at(a, t) + at(b, t));
    const SurfacePoint sp = space_.locate(mid);
    const Vec3 o = surface_position(space_.mesh(), sp);
    const Vec3 normal = space_.bundle().face_normal(sp.face);
    Vec3 d = (at(a, t1) - at(b, t1)) - (at(a, t0) - at(b, t0));
    d -= d.dot(normal) * normal;
    if (!(d.norm() > 1e-12 * space_.diameter())) return inf;
    d.normalize();
    const Mesh& mesh = space_.mesh();
    auto above = [&](int v) { return (mesh.position(v) - o).dot(d) > 0; };
    // A halfedge whose tail is above the plane and head is not (a face the plane crosses
    // has one), and where the plane crosses it.
    auto leaves = [&](int h) { return above(mesh.tail(h)) && !above(mesh.head(h)); };
    auto crossing = [&](int h) {
      const Vec3 x = mesh.position(mesh.tail(h)), y = mesh.position(mesh.head(h));
      const double hx = (x - o).dot(d), hy = (y - o).dot(d);
      return Vec3(x + hx / (hx - hy) * (y - x));
    };
    int start = -1;
    for (int k = 0; k < 3; ++k)
      if (leaves(3 * sp.face + k)) start = 3 * sp.face + k;
    if (start < 0) return inf;
    std::vector<Vec3> section;
    for (int h = start, steps = 0; steps < mesh.num_faces(); ++steps) {
      section.push_back(crossing(h));
      const int twin = mesh.twin(h);
      if (twin < 0) return inf;
      // The twin enters its face; the plane leaves it by the one other edge that leaves.
      h = leaves(Mesh::next(twin)) ? Mesh::next(twin) : leaves(Mesh::prev(twin)) ? Mesh::prev(twin) : -1;
      if (h < 0) return inf;
      if (h == start) {
        double widest = 0;
        for (size_t i = 0; i < section.size(); ++i)
          for (size_t j = i + 1; j < section.size(); ++j) widest = std::max(widest, (section[i] - section[j]).norm());
        return widest;
      }
    }
    return inf;
  }

  // Distance from p to the domain's boundary and its nearest point there.
  std::pair<double, Vec3> boundary_nearest(const Vec3& p) const {
    std::pair<double, Vec3> out{std::numeric_limits<double>::infinity(), p};
    for (const auto& [x, y] : boundary_) {
      const Vec3 e = y - x;
      const double u = std::clamp((p - x).dot(e) / e.squaredNorm(), 0.0, 1.0);
      const Vec3 q = x + u * e;
      if ((p - q).norm() < out.first) out = {(p - q).norm(), q};
    }
    return out;
  }

  // Distance from p to the domain's boundary (infinite on a closed surface).
  double boundary_distance(const Vec3& p) const {
    double out = std::numeric_limits<double>::infinity();
    for (const auto& [x, y] : boundary_) {
      const Vec3 e = y - x;
      const double u = std::clamp((p - x).dot(e) / e.squaredNorm(), 0.0, 1.0);
      out = std::min(out, (p - (x + u * e)).norm());
    }
    return out;
  }

  // A bent path stays in the domain, no nearer its boundary than half the separation (or
  // than the straight path already comes).
  // The largest world offset of a track's bends from its path (before the walk on a surface).
  static double offset_size(const Track& tr) {
    double out = 0;
    for (int k = 0; k <= kSamples; ++k) {
      const double s = static_cast<double>(k) / kSamples;
      Vec3 off = Vec3::Zero();
      for (const Track::Bend& b : tr.bends) off += b.amplitude * bump(s, b.rise, b.fall) * b.dir;
      out = std::max(out, off.norm());
    }
    return out;
  }
  bool inside(const Track& bent, const Track& before) const {
    if (boundary_.empty()) return true;
    Track straight = before;
    straight.bends.clear();
    double margin = 0.5 * separation_;
    for (int k = 0; k <= kSamples; ++k) {
      const Vec3 raw = straight.raw(static_cast<double>(k) / kSamples);
      margin = std::min(margin, boundary_distance(surface_position(space_.mesh(), space_.locate(raw))));
    }
    for (int k = 0; k <= kSamples; ++k) {
      const Vec3 raw = bent.raw(static_cast<double>(k) / kSamples);
      const Vec3 on = surface_position(space_.mesh(), space_.locate(raw));
      if (space_.planar() && (on - raw).norm() > 1e-9 * space_.diameter()) return false;
      if (boundary_distance(on) < margin * (1 - 1e-9)) return false;
    }
    return true;
  }

  const DesignSpace& space_;
  double separation_;
  std::vector<double> keyframe_times_;
  const std::function<void()>& checkpoint_;
  bool joint_search_;
  mutable std::vector<double> caps_;  // set_caps(): caps_[i * caps_n_ + j] for slots i, j
  mutable size_t caps_n_ = 0;
  std::vector<std::pair<Vec3, Vec3>> boundary_;
};

}  // namespace

KeyframeMatch match_keyframe_singularities(std::span<const Singularity> A, std::span<const Singularity> B,
                                           const KeyframeMatchRules& rules) {
  KeyframeMatch out;
  std::vector<int> ma(A.size(), -1), mb(B.size(), -1);
  std::vector<std::pair<size_t, size_t>>& pairs = out.matched;
  for (const auto& [a, b] : rules.links) {
    ma[a] = static_cast<int>(b);
    mb[b] = static_cast<int>(a);
    pairs.emplace_back(a, b);
  }
  // The same type, or else the same index and stability; the static solve's own
  // singularities (neither linked nor designed) within carry_reach: farther, the two key
  // frames' fields have each its own there (CGAL's bear: a saddle and a focus by the head in
  // one, by the body in the other, carried 0.9 and 1.2 across the others' paths, routed
  // round them by detours as long as the bear), cancelled and created in pairs below.
  auto same_type = [](const Singularity& x, const Singularity& y) { return x.type == y.type; };
  auto same_stability = [](const Singularity& x, const Singularity& y) {
    return x.index == y.index && stability(x.type) * stability(y.type) >= 0;
  };
  auto within = [&](const Singularity& x, const Singularity& y) {
    const auto a = static_cast<size_t>(&x - A.data()), b = static_cast<size_t>(&y - B.data());
    const bool designed = (a < rules.designed_a.size() && rules.designed_a[a]) ||
                          (b < rules.designed_b.size() && rules.designed_b[b]);
    return designed || (x.position - y.position).norm() <= rules.carry_reach;
  };
  auto near_type = [&](const Singularity& x, const Singularity& y) { return same_type(x, y) && within(x, y); };
  auto near_stability = [&](const Singularity& x, const Singularity& y) {
    return same_stability(x, y) && within(x, y);
  };
  match_nearest(A, B, ma, mb, near_type, pairs);
  match_nearest(A, B, ma, mb, near_stability, pairs);
  // Two of the static solve's own nodes that trade places (a repelling focus on one ear and
  // an attracting one on the other in the first key frame, the other way round in the
  // second: matching by type carries each across the surface) are matched in place instead
  // where their paths would cross and in place they would not, or else where that carries
  // less, a stability change counting turnover_cost more (passes over all pairs until
  // none swaps, at most 64: a swap can make a crossing with a third). Linked and designed
  // singularities keep their matches (the user named them: a source and a center trading
  // places are meant to).
  auto own = [&](size_t a, size_t b) {
    return A[a].index > 0 && !(a < rules.designed_a.size() && rules.designed_a[a]) &&
           !(b < rules.designed_b.size() && rules.designed_b[b]);
  };
  auto cost = [&](size_t a, size_t b) {
    return (A[a].position - B[b].position).norm() +
           (stability(A[a].type) * stability(B[b].type) < 0 ? rules.turnover_cost : 0.0);
  };
  // Whether a1 → b1 and a2 → b2, moving straight at the same pace, cross: their relative
  // position passes nearer than half of what either key frame holds them apart (two foci
  // 0.01 apart trading stability would pass through each other, where no detour parts
  // them; turning over in place they keep their distance).
  auto cross = [&](size_t a1, size_t b1, size_t a2, size_t b2) {
    const Vec3 r0 = A[a1].position - A[a2].position, r1 = B[b1].position - B[b2].position, d = r1 - r0;
    const double s = d.squaredNorm() > 0 ? std::clamp(-r0.dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
    return (r0 + s * d).norm() < 0.5 * std::min(r0.norm(), r1.norm());
  };
  for (int pass = 0, again = 1; again && pass < 64; ++pass) {
    again = 0;
    for (size_t i = rules.links.size(); i < pairs.size(); ++i)
      for (size_t j = i + 1; j < pairs.size(); ++j) {
        const auto [a1, b1] = pairs[i];
        const auto [a2, b2] = pairs[j];
        if (!own(a1, b1) || !own(a2, b2)) continue;
        const bool crossing = cross(a1, b1, a2, b2), other_crossing = cross(a1, b2, a2, b1);
        if ((crossing && !other_crossing) ||
            (crossing == other_crossing && cost(a1, b2) + cost(a2, b1) < cost(a1, b1) + cost(a2, b2))) {
          pairs[i].second = b2;
          pairs[j].second = b1;
          mb[b2] = static_cast<int>(a1);
          mb[b1] = static_cast<int>(a2);
          ma[a1] = static_cast<int>(b2);
          ma[a2] = static_cast<int>(b1);
          again = 1;
        }
      }
  }
  // The unmatched of each key frame in saddle–node pairs (cancelled or created).
  out.cancelled = pair_unmatched(A, ma);
  out.created = pair_unmatched(B, mb);
  // A node of the static solve's own carried far while one its key frame leaves to a pair
  // lies nearer its match: the near one is matched (turning over in place if it must) and
  // the far one takes its place in the pair, where that moves the singularities less in
  // all (the carry plus the pair's distance, each stability change counting turnover_cost).
  // CGAL's elephant: a sink carried 0.49 across the body to where a repelling focus of the
  // first key frame turns attracting in place, that focus cancelled with a saddle 0.47 away,
  // where the sink and a saddle 0.13 from it are the pair. Best exchange first, until none
  // lowers the sum (at most 64: each lowers it).
  auto free_node = [&](std::span<const Singularity> S, const std::vector<char>& designed, size_t n) {
    return S[n].index > 0 && !(n < designed.size() && designed[n]);
  };
  for (int pass = 0; pass < 64; ++pass) {
    double gain = 1e-12 * (1 + rules.turnover_cost);
    size_t best_pair = 0, best_match = 0;
    bool best_first = false;
    for (int side = 0; side < 2; ++side) {
      const bool first = side == 0;
      std::span<const Singularity> S = first ? A : B;
      const auto& side_pairs = first ? out.cancelled : out.created;
      for (size_t p = 0; p < side_pairs.size(); ++p) {
        const auto [sigma, n] = side_pairs[p];
        if (!free_node(S, first ? rules.designed_a : rules.designed_b, n)) continue;
        for (size_t i = rules.links.size(); i < pairs.size(); ++i) {
          const auto [a, b] = pairs[i];
          if (!own(a, b) || B[b].index <= 0) continue;
          const size_t far = first ? a : b;
          const double before = cost(a, b) + (S[n].position - S[sigma].position).norm();
          const double after = (first ? cost(n, b) : cost(a, n)) + (S[far].position - S[sigma].position).norm();
          if (before - after > gain) gain = before - after, best_pair = p, best_match = i, best_first = first;
        }
      }
    }
    if (gain <= 1e-12 * (1 + rules.turnover_cost)) break;
    auto& side_pairs = best_first ? out.cancelled : out.created;
    auto& [a, b] = pairs[best_match];
    size_t& n = side_pairs[best_pair].second;
    if (best_first) {
      ma[a] = -1, ma[n] = static_cast<int>(b), mb[b] = static_cast<int>(n);
      std::swap(a, n);
    } else {
      mb[b] = -1, mb[n] = static_cast<int>(a), ma[a] = static_cast<int>(n);
      std::swap(b, n);
    }
  }
  // The last resort, for what neither matched nor paired: a node of one stability in the
  // first key frame and one of the other in the second (the static solve's far foci turn
  // over), nearest first within stability_reach. Carried like any match, its α turns
  // through a center on the way (track_jacobian: |α| > |β| throughout, so det J > 0; a
  // Hopf-like passage, not a saddle–node pair).
  for (const auto& [si, ni] : out.cancelled) ma[si] = ma[ni] = static_cast<int>(B.size());
  for (const auto& [si, ni] : out.created) mb[si] = mb[ni] = static_cast<int>(A.size());
  match_nearest(A, B, ma, mb,
                [&](const Singularity& x, const Singularity& y) {
                  return x.index == y.index && (x.position - y.position).norm() <= rules.stability_reach;
                },
                pairs);
  // What is left (none to pair it with, nor to turn over): carried, however far.
  match_nearest(A, B, ma, mb, same_type, pairs);
  match_nearest(A, B, ma, mb, same_stability, pairs);
  return out;
}

KeyframeTopologyPlan::KeyframeTopologyPlan(const DesignSpace& space, const Scene& scene,
                                           const std::vector<std::vector<cplx>>& keyframe_fields,
                                           const std::function<void()>& checkpoint,
                                           const std::function<void(size_t k, size_t n)>& on_interval) {
  const TangentBundle& bundle = space.bundle();
  const Mesh& mesh = space.mesh();
  const double h = mesh.mean_edge_length();
  const size_t nk = scene.keyframes.size();
  TVF_CHECK(keyframe_fields.size() == nk, "one field per key frame");
  std::vector<std::vector<Singularity>> sing(nk);
  for (size_t k = 0; k < nk; ++k) sing[k] = find_singularities(bundle, keyframe_fields[k]);

  // A linked key-frame element's singularity: the nearest of its key frame's field.
  const double link_reach = std::max(scene.solver.region_radius, 3 * h);
  // The singularity of key frame `key`'s field that the element at `at` stands for: the
  // nearest within link_reach (−1: none).
  auto element_singularity = [&](size_t key, const Vec3& at) {
    const Vec3 p = surface_position(mesh, space.locate(at));
    int best = -1;
    double best_d = link_reach;
    for (size_t s = 0; s < sing[key].size(); ++s) {
      const double dist = (sing[key][s].position - p).norm();
      if (dist <= best_d) best = static_cast<int>(s), best_d = dist;
    }
    return best;
  };
  auto linked_singularity = [&](size_t link, int key, int element) {
    const int best = element_singularity(
        static_cast<size_t>(key), scene.keyframes[static_cast<size_t>(key)].elements[static_cast<size_t>(element)].at);
    if (best < 0)
      throw_input_error(scene.label(), fmt::format("solver.links[{}]", link),
                        fmt::format("keyframes[{}].elements[{}] has no singularity of the key frame's field within {:.3g} "
                                    "of it (its neighbours' regions overlap it); move it or the others apart",
                                    key, element, link_reach));
    return static_cast<size_t>(best);
  };

  // designed[k][s]: singularity s of key frame k is the one a singular element of that key
  // frame names (the nearest within link_reach, as a link would take it).
  std::vector<std::vector<char>> designed(nk);
  for (size_t k = 0; k < nk; ++k) {
    designed[k].assign(sing[k].size(), 0);
    for (const KeyframeElement& e : scene.keyframes[k].elements)
      if (const int s = e.kind == "singular" ? element_singularity(k, e.at) : -1; s >= 0) designed[k][static_cast<size_t>(s)] = 1;
  }

  // Shortest paths over the surface (surface_curve).
  std::optional<SurfacePaths> paths;
  if (!space.planar()) paths.emplace(space.bundle(), space.locator());
  // The key frames' times as the field has them: each is held at the nearest frame
  // (keyframe_frame), so the paths run between those frames' times; a path planned to the
  // key frame's own time between two frames would reach it half a frame early or late (the
  // sphere knot's middle key frame at t = 0.5 of 32 frames: the field's change 3.4 just
  // before it and 10.9 just after, against 6 to 8).
  std::vector<double> keyframe_times;
  const std::vector<double> scene_times = scene.time.times();
  for (const Keyframe& key : scene.keyframes)
    keyframe_times.push_back(scene_times[static_cast<size_t>(keyframe_frame(scene, key.t))]);
  auto add_track = [&](const Singularity& a, const Vec3& p1, double t0, double t1, const Linear& j1_in_face,
                       int face1, int group = -1) {
    Track tr;
    tr.type = a.type;
    tr.to_type = a.type;
    tr.index = a.index;
    tr.group = group;
    tr.p0 = a.position;
    tr.p1 = p1;
    tr.t0 = t0;
    tr.t1 = t1;
    tr.ease = interval_ease(keyframe_times, t0, t1);
    if (!space.planar()) tr.curve = surface_curve(space, *paths, tr.p0, tr.p1);
    tr.ref_e1 = bundle.face_e1(a.where.face);
    tr.j0 = to_linear(a.jacobian);
    tr.j1 = {j1_in_face.alpha, beta_in_frame(bundle, face1, tr.ref_e1, j1_in_face.beta)};
    tracks_.push_back(tr);
  };

  const double separation = scene.solver.path_separation.value_or(2 * scene.solver.region_radius);
  // How far a node that changes stability may be carried (the last resort below): a
  // quarter of the domain's diameter, at least the separation.
  const double stability_reach = std::max(0.25 * space.diameter(), separation);
  const PathRouter router(space, separation, keyframe_times, checkpoint);
  // The matching rules of the interval from key frame k to k + 1 (the links checked).
  auto interval_rules = [&](size_t k) {
    KeyframeMatchRules rules;
    const std::vector<Singularity>& A = sing[k];
    const std::vector<Singularity>& B = sing[k + 1];
    std::vector<int> ma(A.size(), -1), mb(B.size(), -1);
    for (size_t l = 0; l < scene.solver.links.size(); ++l) {
      const KeyframeLink& link = scene.solver.links[l];
      if (link.from_keyframe != static_cast<int>(k)) continue;
      const size_t a = linked_singularity(l, link.from_keyframe, link.from_element);
      const size_t b = linked_singularity(l, link.to_keyframe, link.to_element);
      if (ma[a] >= 0 || mb[b] >= 0)
        throw_input_error(scene.label(), fmt::format("solver.links[{}]", l),
                          "links a singularity of the key frames' fields that an earlier link already holds (the "
                          "two elements are too close to tell apart)");
      if (A[a].index != B[b].index)
        throw_input_error(scene.label(), fmt::format("solver.links[{}]", l),
                          fmt::format("the key frames' fields have singularities of index {} and {} at the linked "
                                      "elements; linked singularities must have the same index",
                                      A[a].index, B[b].index));
      ma[a] = static_cast<int>(b);
      mb[b] = static_cast<int>(a);
      rules.links.emplace_back(a, b);
    }
    rules.designed_a = designed[k];
    rules.designed_b = designed[k + 1];
    rules.turnover_cost = separation;
    rules.stability_reach = stability_reach;
    return rules;
  };
  // Where each singularity of a middle key frame goes next (its match in the next key
  // frame by the next interval's first try; −1: none, it is cancelled or turns over), so
  // that the path into the key frame ends in the direction the path out of it starts in.
  std::vector<std::vector<int>> next_of(nk);
  for (size_t k = 1; k + 1 < nk; ++k) {
    next_of[k].assign(sing[k].size(), -1);
    for (const auto& [a, b] : match_keyframe_singularities(sing[k], sing[k + 1], interval_rules(k)).matched)
      next_of[k][a] = static_cast<int>(b);
  }
  // A path's velocity at one of its ends in time, before the Hermite terms (the warp's
  // slope at a middle key frame is 1).
  auto leg_velocity = [&](const Vec3& p0, const Vec3& p1, const SurfaceCurve* curve, double dt, bool at_end) {
    const Vec3 n = space.planar() ? Vec3::UnitZ() : bundle.face_normal(space.locate(at_end ? p1 : p0).face);
    return Vec3(end_velocity(p0, p1, curve, at_end, n) / dt);
  };
  // Where the guide leaves a node turning a whole turn: the key frame that would hold it
  // (KeyframeIntervalReport::middle_keyframe), each singular element of key frame k where
  // its track is at the frame nearest the middle. The paths then stay near the plan's, and
  // each node is given its type half-way, so no interval's phases end a whole turn apart
  // (the sphere's knot: its source a source in every frame). Not offered for a node that
  // only swings past a center and back: no case of that has been seen held so.
  auto middle_keyframe = [&](size_t k, const KeyframeIntervalReport& rep,
                             const std::vector<std::pair<size_t, size_t>>& pairs,
                             size_t first_track) -> std::optional<KeyframeIntervalReport::MiddleKeyframe> {
    const bool turning = std::any_of(rep.matched.begin(), rep.matched.end(), [](const auto& m) {
      return m.phase_turns != 0;
    });
    if (!turning || !rep.created.empty() || !rep.cancelled.empty()) return std::nullopt;
    const Keyframe& first = scene.keyframes[k];
    const Keyframe& second = scene.keyframes[k + 1];
    for (const Keyframe* key : {&first, &second})
      if (!key->field.empty() || !key->streamlines.empty() || key->elements.empty() ||
          std::any_of(key->elements.begin(), key->elements.end(), [](const auto& e) { return e.kind != "singular"; }))
        return std::nullopt;
    // The frame nearest the middle, strictly inside the interval.
    double t_mid = 0, best = std::numeric_limits<double>::infinity();
    for (const double t : scene_times)
      if (t > rep.t0 && t < rep.t1 && std::abs(t - 0.5 * (rep.t0 + rep.t1)) < best)
        best = std::abs(t - 0.5 * (rep.t0 + rep.t1)), t_mid = t;
    if (!std::isfinite(best)) return std::nullopt;
    KeyframeIntervalReport::MiddleKeyframe out;
    out.keyframe.t = t_mid;
    for (size_t e = 0; e < first.elements.size(); ++e) {
      const int s = element_singularity(k, first.elements[e].at);
      const auto m = std::find_if(pairs.begin(), pairs.end(), [&](const auto& p) { return static_cast<int>(p.first) == s; });
      if (s < 0 || m == pairs.end()) return std::nullopt;  // an element not carried
      int to = -1;
      for (size_t f = 0; f < second.elements.size() && to < 0; ++f)
        if (element_singularity(k + 1, second.elements[f].at) == static_cast<int>(m->second)) to = static_cast<int>(f);
      const Track& tr = tracks_[first_track + static_cast<size_t>(m - pairs.begin())];
      KeyframeElement element = first.elements[e];
      element.at = space.planar() ? tr.raw(tr.param(t_mid)) : surface_position(mesh, space.locate(tr.raw(tr.param(t_mid))));
      out.keyframe.elements.push_back(element);
      out.from.push_back(static_cast<int>(e));
      out.to.push_back(to);
    }
    return out;
  };
  int groups = 0;
  size_t previous_first = 0;  // the previous interval's first track
  for (size_t k = 0; k + 1 < nk; ++k) {
    if (on_interval) on_interval(k, nk - 1);
    const size_t first_track = tracks_.size();
    const size_t first_template = templates_.size();
    const int first_group = groups;
    // Matched first however far the static solve's own singularities go; where that
    // interval is not guided and matching them within stability_reach alone pairs some
    // instead (a saddle and a focus by the head in one key frame and by the body in the
    // next: CGAL's bear, carried 0.9 and 1.2 across the knot's paths), planned again so.
    // A sphere's knot carries its static saddle 0.79 and focus 1.33 (diameter 2) and is
    // guided so: the reach is the second try, not the rule. When neither is guided the
    // first plan is kept (its report says why).
    struct Unguided {
      std::vector<Track> tracks;
      std::vector<Template> templates;
      KeyframeIntervalReport rep;
      int groups = 0;
    };
    std::optional<Unguided> unguided;
    for (int attempt = 0; attempt < 2; ++attempt) {
      if (checkpoint) checkpoint();
      Guide guide;
      std::vector<Track> obstacles;  // the interval's templates, for the router
      const std::vector<Singularity>& A = sing[k];
      const std::vector<Singularity>& B = sing[k + 1];
      KeyframeIntervalReport rep;
      rep.from_keyframe = static_cast<int>(k);
      rep.to_keyframe = static_cast<int>(k + 1);
      rep.t0 = keyframe_times[k];
      rep.t1 = keyframe_times[k + 1];
      // A bifurcation time given between the scene's key-frame times keeps its place
      // between the frames that hold them (the same time where those are on frames).
      const double key0 = scene.keyframes[k].t, key1 = scene.keyframes[k + 1].t;
      rep.bifurcation_t = k < scene.solver.bifurcation_times.size()
                              ? rep.t0 + (scene.solver.bifurcation_times[k] - key0) / (key1 - key0) * (rep.t1 - rep.t0)
                              : 0.5 * (rep.t0 + rep.t1);
      KeyframeMatchRules rules = interval_rules(k);
      if (attempt == 1) rules.carry_reach = stability_reach;
      const KeyframeMatch matching = match_keyframe_singularities(A, B, rules);
      const std::vector<std::pair<size_t, size_t>>& pairs = matching.matched;
      const size_t n_linked = rules.links.size();
      const std::array<std::vector<std::pair<size_t, size_t>>, 2> side_pairs{matching.cancelled, matching.created};
      std::vector<int> ma(A.size(), -1), mb(B.size(), -1);
      for (const auto& [a, b] : pairs) ma[a] = static_cast<int>(b), mb[b] = static_cast<int>(a);
      for (size_t m = 0; m < pairs.size(); ++m) {
        const Singularity& a = A[pairs[m].first];
        const Singularity& b = B[pairs[m].second];
        add_track(a, b.position, rep.t0, rep.t1, to_linear(b.jacobian), b.where.face);
        tracks_.back().to_type = b.type;
        rep.matched.push_back({a.type, a.position, b.position, m < n_linked, 0.0, b.type, 0, 0.0});
      }
      // Through a middle key frame each matched path goes on in one direction
      // (through_velocity): at the start, the one the previous interval's path arrives by;
      // at the end, the one the next interval's first matching carries it on by (the same
      // velocity both sides compute, so the two paths join C¹ unless that interval is
      // matched differently on its second try).
      for (size_t m = 0; m < pairs.size(); ++m) {
        Track& tr = tracks_[first_track + m];
        const double dt = tr.t1 - tr.t0;
        const Vec3 out0 = leg_velocity(tr.p0, tr.p1, tr.curve.get(), dt, false);
        const Vec3 in1 = leg_velocity(tr.p0, tr.p1, tr.curve.get(), dt, true);
        if (tr.ease.m0 > 0)
          for (size_t i = previous_first; i < first_track; ++i) {
            const Track& prev = tracks_[i];
            if (prev.group >= 0 || prev.t1 != tr.t0 || prev.p1 != tr.p0) continue;
            const Vec3 in = leg_velocity(prev.p0, prev.p1, prev.curve.get(), prev.t1 - prev.t0, true);
            tr.through0 = (through_velocity(in, out0, prev.t1 - prev.t0, dt) - out0) * dt;
            break;
          }
        if (const int next = tr.ease.m1 > 0 ? next_of[k + 1][pairs[m].second] : -1; next >= 0) {
          const Vec3& q = sing[k + 2][static_cast<size_t>(next)].position;
          const double dt2 = keyframe_times[k + 2] - keyframe_times[k + 1];
          const std::shared_ptr<const SurfaceCurve> on = space.planar() ? nullptr : surface_curve(space, *paths, tr.p1, q);
          const Vec3 out = leg_velocity(tr.p1, q, on.get(), dt2, false);
          tr.through1 = (through_velocity(in1, out, dt, dt2) - in1) * dt;
        }
        tr.set_through_frames();
      }

      // The unmatched, in pairs: cancelled before t_c, created after.
      const double tc = rep.bifurcation_t;
      const double tau = 0.25 * std::min(tc - rep.t0, rep.t1 - tc);
      const double diam = space.diameter();
      for (int side = 0; side < 2; ++side) {
        const std::vector<Singularity>& S = side == 0 ? A : B;
        const std::vector<int>& matched = side == 0 ? ma : mb;
        std::vector<char> paired(S.size(), 0);
        for (const auto& [si, ni] : side_pairs[static_cast<size_t>(side)]) {
          paired[si] = paired[ni] = 1;
          const Singularity& saddle = S[si];
          const Singularity& node = S[ni];
          // The template's middle and axis: on a surface the middle of the shortest path
          // from the saddle to the node (the curve the pair's tracks run along) and its
          // direction there; on the plane the segment's.
          const std::shared_ptr<const SurfaceCurve> between =
              space.planar() ? nullptr : surface_curve(space, *paths, saddle.position, node.position);
          const Vec3 mid = between ? surface_position(mesh, space.locate(between->at(0.5)))
                                   : surface_position(mesh, space.locate(0.5 * (saddle.position + node.position)));
          const int face = space.locate(mid).face;
          const double dist = (node.position - saddle.position).norm();
          const double s = std::max(1.5 * h, std::min(0.25 * dist, 0.1 * diam));
          cplx axis = bundle.world_to_face(face, between ? Vec3(between->at(0.55) - between->at(0.45))
                                                         : Vec3(node.position - saddle.position));
          axis = std::abs(axis) > 0 ? axis / std::abs(axis) : cplx(1, 0);
          const bool sink = stability(node.type) < 0;
          BifurcationElement b;
          using BT = BifurcationType;
          b.type = side == 0 ? (sink ? BT::saddle_sink_cancellation : BT::saddle_source_cancellation)
                             : (sink ? BT::saddle_sink_creation : BT::saddle_source_creation);
          b.at = {mid, tc};
          b.scale = s;
          b.time_scale = tau;
          b.angle = std::arg(axis);
          templates_.push_back({CompiledElement(b), tc - tau, tc + tau, std::max(scene.solver.region_radius, 2 * s)});
          {
            Track ob;
            ob.p0 = ob.p1 = mid;
            ob.t0 = tc - tau;
            ob.t1 = tc + tau;
            ob.type = saddle.type;
            ob.group = groups;
            obstacles.push_back(ob);
          }
          // The template's zeros at |t′| = 1 (node on +axis, saddle on −axis) and its
          // Jacobians there: R diag(±2, ±1) Rᵀ in the frame of `face`.
          const Vec3 off = s * bundle.face_to_world(face, axis);
          const Vec3 node_end = surface_position(mesh, space.locate(mid + off));
          const Vec3 saddle_end = surface_position(mesh, space.locate(mid - off));
          const double sign = sink ? -1.0 : 1.0;
          const cplx rot = axis * axis;
          const Linear j_node{cplx(sign * 1.5, 0), sign * 0.5 * rot};
          const Linear j_saddle{cplx(sign * -0.5, 0), sign * -1.5 * rot};
          KeyframeIntervalReport::Pair pr{saddle.type, node.type, saddle.position, node.position, mid, tc};
          if (side == 0) {
            add_track(saddle, saddle_end, rep.t0, tc - tau, j_saddle, face, groups);
            add_track(node, node_end, rep.t0, tc - tau, j_node, face, groups);
            rep.cancelled.push_back(pr);
            guide.pairs.push_back({tracks_.size() - 1, tracks_.size() - 2, cplx(mid.x(), mid.y()),
                                   cplx(bundle.face_to_world(face, axis).x(), bundle.face_to_world(face, axis).y()), s,
                                   tc, tau, true});
          } else {
            // Carried backwards in time: from the key frame at t1 to the template's zeros at t_c + τ.
            add_track(saddle, saddle_end, rep.t1, tc + tau, j_saddle, face, groups);
            add_track(node, node_end, rep.t1, tc + tau, j_node, face, groups);
            rep.created.push_back(pr);
            guide.pairs.push_back({tracks_.size() - 1, tracks_.size() - 2, cplx(mid.x(), mid.y()),
                                   cplx(bundle.face_to_world(face, axis).x(), bundle.face_to_world(face, axis).y()), s,
                                   tc, tau, false});
          }
          ++groups;
        }
        for (size_t i = 0; i < S.size(); ++i)
          if (matched[i] < 0 && !paired[i])
            (side == 0 ? rep.unpaired_first : rep.unpaired_second).push_back(S[i].position);
      }

      // On a surface, a path that is no curve on it (leaves_surface: its ends joined by no
      // edge path, so left the straight segment) cannot be guided; found before the router
      // spends its time on the interval (which then stays "straight" and falls back).
      auto leaving_surface = [&] {
        std::string why;
        if (!space.planar())
          for (size_t i = first_track; i < tracks_.size() && why.empty(); ++i) {
            std::vector<SurfacePoint> on(SurfaceGuide::kSamples + 1);
            for (int q = 0; q <= SurfaceGuide::kSamples; ++q)
              on[static_cast<size_t>(q)] = space.locate(tracks_[i].raw(static_cast<double>(q) / SurfaceGuide::kSamples));
            why = leaves_surface(space, tracks_[i], on);
          }
        return why;
      };
      std::string off_surface = leaving_surface();
      // The Hermite terms through a middle key frame are carried along the curve in its
      // frame (SurfaceCurve::walked_from); where a path bent so still leaves the surface (a
      // sideways term walked across a thin part) the interval's paths meet their key frames
      // with a corner, as before the terms, rather than fail for them.
      if (!off_surface.empty() &&
          std::any_of(tracks_.begin() + static_cast<std::ptrdiff_t>(first_track), tracks_.end(),
                      [](const Track& tr) { return tr.bent_through(); })) {
        for (size_t i = first_track; i < tracks_.size(); ++i) {
          tracks_[i].through0 = tracks_[i].through1 = Vec3::Zero();
          tracks_[i].set_through_frames();
        }
        off_surface = leaving_surface();
      }
      // Paths that would come closer than the separation are bent around each other.
      const std::string where =
          scene.solver.path_separation ? "solver.path_separation" : "solver.keyframe_topology";
      rep.separation = separation;
      // Whether no second try follows this one (the matching within reach is the same).
      const bool last_try = attempt == 1 || [&] {
        KeyframeMatchRules within = rules;
        within.carry_reach = stability_reach;
        auto sorted = [](std::vector<std::pair<size_t, size_t>> v) { return std::sort(v.begin(), v.end()), v; };
        return sorted(match_keyframe_singularities(A, B, within).matched) == sorted(matching.matched);
      }();
      if (off_surface.empty()) {
        const std::string interval = fmt::format("between keyframes[{}] and keyframes[{}]", k, k + 1);
        if (auto why = router.route(tracks_, first_track, tracks_.size(), obstacles, scene, where, interval,
                                    rep.routing, rep.collision_at)) {
          rep.collision = std::move(*why);
          // The default separation (twice region_radius, no solver.path_separation) is not
          // the user's: where it cannot be kept, three quarters of it, then of that, are
          // tried by pairwise detours alone before the interval falls back, on its last try
          // (a first try that a second, matched within reach, may replace keeps the
          // default: CGAL's bear is guided so, its far singularities paired, where the
          // lowered first try carried one 0.52 of the diagonal; and the joint search, which
          // the held rule spares a pair a key frame holds too close, took 16 s on the
          // elephant). CGAL's camel knot: two static saddles could not keep 0.143 between
          // them; at 0.107 every path is routed and the interval guided, no event not
          // asked for (docs/benchmarks.md).
          if (!scene.solver.path_separation && last_try)
            for (const double f : {0.75, 0.75 * 0.75}) {
              const PathRouter lower(space, f * separation, keyframe_times, checkpoint, false);
              std::string how;
              std::optional<KeyframeIntervalReport::Collision> place;
              if (lower.route(tracks_, first_track, tracks_.size(), obstacles, scene, where, interval, how, place))
                continue;
              rep.lowered_from = separation;
              rep.lowered_because = std::move(rep.collision);
              rep.collision.clear();
              rep.collision_at.reset();
              rep.routing = how;
              rep.separation = f * separation;
              break;
            }
        }
      }
      // Where paths were bent, each Jacobian turns with its neighbourhood.
      if (rep.routing != "straight") router.turn_with_neighbours(tracks_, first_track, tracks_.size());
      for (size_t m = 0; m < rep.matched.size(); ++m) rep.matched[m].detour = router.detour(tracks_[first_track + m]);
      for (size_t i = first_track; i < tracks_.size(); ++i)
        for (size_t j = i + 1; j < tracks_.size(); ++j)
          if (tracks_[i].group < 0 || tracks_[i].group != tracks_[j].group)
            rep.closest_approach = std::min(rep.closest_approach, router.closest(tracks_[i], tracks_[j]));
      // Planar domains: the frames in between are the interval's guide field (Guide), whose
      // zeros are the plan's alone; not with singularities left unpaired (the guide would
      // need their zeros too) or nothing carried.
      guide.first = first_track;
      guide.last = tracks_.size();
      guide.t0 = rep.t0;
      guide.t1 = rep.t1;
      guide.ease = interval_ease(keyframe_times, rep.t0, rep.t1);
      guide.radius = scene.solver.region_radius;
      const Guide unbuilt = guide;
      if (space.planar() && rep.collision.empty() && rep.unpaired_first.empty() && rep.unpaired_second.empty() &&
          guide.last > guide.first &&
          build_guide(space, tracks_, keyframe_fields[k], keyframe_fields[k + 1], guide)) {
        // A node changing stability turns through one center or the other: the shorter arc
        // of α, unless the nodes' phases then end whole turns apart (λ_j ends at 2πk_j),
        // which Λ's Shepard blend cannot take out between them (the frames before the second
        // key frame were half a turn off it there); then the other way round, kept where the
        // nodes' ends come closer (its own λ is G's without it: the others' move a turn).
        auto spread = [&](const Guide& g) {
          double lo = 0, hi = 0;
          bool any = false;
          for (size_t i = g.first; i < g.last; ++i) {
            if (tracks_[i].index <= 0 || g.lambda[i - g.first].empty()) continue;
            const double e = g.lambda[i - g.first].back().imag();
            lo = any ? std::min(lo, e) : e;
            hi = any ? std::max(hi, e) : e;
            any = true;
          }
          return hi - lo;
        };
        for (size_t i = guide.first; i < guide.last; ++i) {
          if (stability(tracks_[i].type) * stability(tracks_[i].to_type) >= 0 || spread(guide) < std::numbers::pi)
            continue;
          tracks_[i].other_way = true;
          Guide other = unbuilt;
          if (build_guide(space, tracks_, keyframe_fields[k], keyframe_fields[k + 1], other) &&
              spread(other) < spread(guide))
            guide = std::move(other);
          else
            tracks_[i].other_way = false;
        }
        keep_pair_phase_if_resolved(space, tracks_, guide);
        for (size_t i = guide.first; i < guide.last; ++i) tracks_[i].guided = true;
        for (size_t i = first_template; i < templates_.size(); ++i) templates_[i].guided = true;
        rep.guided = true;
        guides_.push_back(std::move(guide));
      }
      // Surfaces: the first key frame's field carried along the paths (SurfaceGuide), where
      // every singularity of both key frames is matched or in a created or cancelled pair.
      // Where its frames hold extra zeros, the guide is built again with the weights' ramp
      // twice as wide (a long path's log R changes by ~|log R| across it, which two edge
      // lengths did not resolve beside the knot with a pair; the wider tube does not fit
      // every coarse mesh, so it is the second try), then with the shaped ratio at both
      // ramps (SurfaceGuide::Path::a: the key frames' own linear parts in R, which a very
      // anisotropic focus needs at its path's ends, CGAL's bunny; the sphere 3 knot with a
      // pair is not guided with it, so it comes after the plain ratio): the first with no
      // wrong frame is kept (PhaseCheck; the key frames' |β|/|α| does not tell beforehand
      // which scenes need the shaped ratio, docs/benchmarks.md, so the order stays).
      std::string unbuilt_why = off_surface;  // why the guide could not be built, when it was tried
      if (space.planar() && rep.collision.empty() && rep.unpaired_first.empty() && rep.unpaired_second.empty() &&
          guide.last > guide.first && !rep.guided)
        unbuilt_why = "the guide field has two zeros on one point";
      if (!space.planar() && off_surface.empty() && rep.collision.empty() && rep.unpaired_first.empty() &&
          rep.unpaired_second.empty() && tracks_.size() > first_track) {
        std::optional<SurfaceGuide> best;
        // The frames the guide will be checked at: the scene's, strictly between the key frames.
        std::vector<double> frame_times;
        for (const double t : scene.time.times())
          if (t > rep.t0 && t < rep.t1) frame_times.push_back(t);
        const size_t inner_frames = frame_times.size();
        const PhaseCheck check(space, tracks_, rep.matched.size(), frame_times, checkpoint);
        std::vector<PhaseCheck::Trial> failed;  // counted on only when no guide is kept
        TubeCache tubes;
        for (const auto& [ramp, shaped] :
             {std::pair{1.0, false}, std::pair{2.0, false}, std::pair{1.0, true}, std::pair{2.0, true}}) {
          if (checkpoint) checkpoint();
          SurfaceGuide sg;
          sg.t0 = rep.t0;
          sg.t1 = rep.t1;
          sg.ease = interval_ease(keyframe_times, rep.t0, rep.t1);
          std::string why;
          if (!build_surface_guide(space, tracks_, first_track, tracks_.size(), guide.pairs, scene.solver.region_radius,
                                   ramp, shaped, keyframe_fields[k], keyframe_fields[k + 1], tubes, sg, why)) {
            // The wider ramp widens the same tubes: a path or pair that fits no chart at the
            // first does not at the second either, so no second try (on the bunny ~0.5 s).
            if (unbuilt_why.empty()) unbuilt_why = why;
            break;
          }
          PhaseCheck::Trial trial = check.start(std::move(sg));
          if (check.accept(trial)) {
            best = std::move(trial.g);
            break;
          }
          failed.push_back(std::move(trial));
        }
        int fewest_wrong = -1;
        const PhaseCheck::Trial* fewest_trial = nullptr;
        for (PhaseCheck::Trial& trial : best ? std::span<PhaseCheck::Trial>() : std::span(failed)) {
          const int wrong = check.fewest(trial);
          if (fewest_wrong < 0 || wrong < fewest_wrong) fewest_wrong = wrong, fewest_trial = &trial;
        }
        int unplanned = 0;
        for (const PhaseCheck::Trial& trial : failed) unplanned = std::max(unplanned, trial.unplanned);
        if (!best && fewest_wrong >= 0 && fewest_wrong < std::numeric_limits<int>::max()) {
          unbuilt_why = fmt::format("the surface guide's frames hold other singularities than the plan's at {} of the "
                                    "{} frames between the key frames",
                                    fewest_wrong, inner_frames);
          // Where, so that a user knows where a link, a key frame or a smaller region helps.
          rep.first_wrong = check.first_wrong(*fewest_trial);
          if (rep.first_wrong) unbuilt_why += " (" + wrong_frame_sentence(*rep.first_wrong) + ")";
        } else if (!best && unplanned > 0)
          unbuilt_why = fmt::format("the surface guide's singularities jump from frame to frame where the plan carries "
                                    "them smoothly: {} saddle–node events the plan does not have",
                                    unplanned);
        else if (!best && unbuilt_why.empty())
          unbuilt_why = "the surface guide could not be built";
        if (best) {
          // A pair's event happens where its template's zeros meet in the pair's chart: the
          // middle of the two ends there, which on a curved chart is not the surface middle the
          // plan first reported (CGAL's bunny: 0.029 apart for ends 0.18 apart). The report
          // (keyframe_topology.json, the design check) says where the guide puts it.
          for (const SurfaceGuide::Path& path : best->paths) {
            if (!path.pair) continue;
            const std::optional<SurfacePoint> at = chart_locate(mesh, path.coords, path.mid);
            if (!at) continue;
            for (KeyframeIntervalReport::Pair& pr : path.cancel ? rep.cancelled : rep.created)
              if (pr.t == path.tc && pr.saddle == tracks_[path.saddle].p0 && pr.node == tracks_[path.track].p0)
                pr.at = surface_position(mesh, *at);
          }
          // The nodes the guide leaves turning (their type going round, or passing a center).
          for (const SurfaceGuide::Turning& turn : best->turning)
            if (turn.track >= first_track && turn.track - first_track < rep.matched.size()) {
              KeyframeIntervalReport::Match& m = rep.matched[turn.track - first_track];
              m.phase_turns = static_cast<int>(std::lround(turn.end / (2 * std::numbers::pi)));
              m.phase_swing = turn.swing;
            }
          for (size_t i = first_track; i < tracks_.size(); ++i) tracks_[i].guided = true;
          for (size_t i = first_template; i < templates_.size(); ++i) templates_[i].guided = true;
          rep.guided = true;
          surface_guides_.push_back(std::move(*best));
        }
      }
      // An interval that could not be guided falls back to "free" (key frames only): carrying
      // the matched singularities' regions alone leaves the band between them to the solve's
      // blend of the two key frames, which made far more bifurcations than no constraint at
      // all (CGAL's elephant: 122 against 8). Its report says so, and why.
      if (!rep.guided) {
        const size_t unpaired = rep.unpaired_first.size() + rep.unpaired_second.size();
        if (tracks_.size() == first_track)
          rep.unguided_reason = "the key frames have no singularity to carry";
        else if (!rep.collision.empty())
          rep.unguided_reason = "two of its paths could not be kept apart (see collision)";
        else if (unpaired > 0)
          rep.unguided_reason =
              fmt::format("{} singularit{} of the key frames left unpaired (the guide would need {} zero{})", unpaired,
                          unpaired == 1 ? "y" : "ies", unpaired == 1 ? "its" : "their", unpaired == 1 ? "" : "s");
        else
          rep.unguided_reason = unbuilt_why.empty() ? std::string("the guide could not be built") : unbuilt_why;
        rep.fallback = true;
        for (size_t i = first_track; i < tracks_.size(); ++i) tracks_[i].free = true;
        for (size_t i = first_template; i < templates_.size(); ++i) templates_[i].free = true;
      }
      // Not guided, and the second try matches otherwise (last_try, above): planned again.
      if (!rep.guided && !last_try && tracks_.size() > first_track) {
        unguided = Unguided{{tracks_.begin() + static_cast<std::ptrdiff_t>(first_track), tracks_.end()},
                            {templates_.begin() + static_cast<std::ptrdiff_t>(first_template), templates_.end()},
                            std::move(rep), groups};
        tracks_.resize(first_track);
        templates_.erase(templates_.begin() + static_cast<std::ptrdiff_t>(first_template), templates_.end());
        groups = first_group;
        continue;
      }
      if (!rep.guided && unguided) {
        tracks_.resize(first_track);
        tracks_.insert(tracks_.end(), unguided->tracks.begin(), unguided->tracks.end());
        templates_.erase(templates_.begin() + static_cast<std::ptrdiff_t>(first_template), templates_.end());
        templates_.insert(templates_.end(), unguided->templates.begin(), unguided->templates.end());
        rep = std::move(unguided->rep);
        groups = unguided->groups;
      }
      if (rep.guided) rep.middle_keyframe = middle_keyframe(k, rep, pairs, first_track);
      intervals_.push_back(std::move(rep));
      break;
    }
    previous_first = first_track;
  }
}

void KeyframeTopologyPlan::constrain(const DesignSpace& space, const Scene& scene, double t, double d,
                                     std::span<char> fixed, std::span<cplx> values) const {
  LocalChart chart;
  detail::ElementOnDomain placed;
  for (const Track& tr : tracks_) {
    const double lo = std::min(tr.t0, tr.t1), hi = std::max(tr.t0, tr.t1);
    if (tr.guided || tr.free || !(t > lo && t < hi)) continue;
    const double s = tr.param(t);
    ElementState st;
    st.active = true;
    st.position = tr.raw(s);
    const SurfacePoint at = space.locate(st.position);
    const Linear j = track_jacobian(space.bundle(), tr, t, at.face);
    st.field.kind = LocalField::Kind::linear;
    st.field.matrix = to_matrix(j);
    detail::place_state(space, st, d, chart, placed);
    detail::constrain_region(space.mesh(), placed, scene.solver.region_radius, fixed, values);
  }
  for (const Template& tp : templates_) {
    if (tp.guided || tp.free || t < tp.t0 || t > tp.t1) continue;
    detail::place_element(space, tp.element, t, d, chart, placed);
    detail::constrain_region(space.mesh(), placed, tp.radius, fixed, values);
  }
  for (const Guide& g : guides_)
    if (t > g.t0 && t < g.t1) apply_guide(space, tracks_, g, t, fixed, values);
  for (const SurfaceGuide& g : surface_guides_) {
    if (!(t > g.t0 && t < g.t1)) continue;
    // A scene frame's log factors were made with the guide (keep_frame_logs).
    const std::vector<double> none;
    const std::vector<double>& logged = g.logs ? g.logs->t : none;
    const auto it = std::lower_bound(logged.begin(), logged.end(), t);
    if (it == logged.end() || *it != t) {
      apply_surface_guide(space, tracks_, g, t, fixed, values);
      continue;
    }
    std::vector<cplx> l;
    frame_logs(g, static_cast<size_t>(it - logged.begin()), static_cast<size_t>(space.mesh().num_vertices()), l);
    apply_surface_guide(space, tracks_, g, t, l, fixed, values);
  }
}

std::vector<Vec3> KeyframeTopologyPlan::carried(double t) const {
  std::vector<Vec3> out;
  for (const Track& tr : tracks_)
    if (!tr.free && t > std::min(tr.t0, tr.t1) && t < std::max(tr.t0, tr.t1)) out.push_back(tr.raw(tr.param(t)));
  return out;
}

nlohmann::json wrong_frame_json(const KeyframeIntervalReport::WrongFrame& w) {
  nlohmann::json out = {{"t", w.t},
                        {"found", w.found},
                        {"planned", w.planned},
                        {"extra", w.extra},
                        {"type", to_string(w.type)},
                        {"at", {w.at.x(), w.at.y(), w.at.z()}},
                        {"face_edges", w.face_edges}};
  if (std::isfinite(w.distance)) out["distance"] = w.distance, out["nearest_type"] = to_string(w.nearest_type);
  return out;
}

nlohmann::json collision_json(const KeyframeIntervalReport::Collision& c) {
  auto xyz = [](const Vec3& p) { return nlohmann::json::array({p.x(), p.y(), p.z()}); };
  return {{"t", c.t},
          {"points", {xyz(c.points[0]), xyz(c.points[1])}},
          {"types", {to_string(c.types[0]), to_string(c.types[1])}},
          {"template", c.template_},
          {"distance", c.distance},
          {"required", c.required}};
}

nlohmann::json middle_keyframe_json(const KeyframeIntervalReport::MiddleKeyframe& m) {
  return {{"keyframe", keyframe_to_json(m.keyframe, false)}, {"from", m.from}, {"to", m.to}};
}

nlohmann::json keyframe_intervals_json(const std::vector<KeyframeIntervalReport>& intervals) {
  using nlohmann::json;
  auto xyz = [](const Vec3& p) { return json::array({p.x(), p.y(), p.z()}); };
  json out = json::array();
  for (const KeyframeIntervalReport& r : intervals) {
    json j;
    j["interval"] = {r.t0, r.t1};
    j["keyframes"] = {r.from_keyframe, r.to_keyframe};
    j["bifurcation_t"] = r.bifurcation_t;
    j["matched"] = json::array();
    for (const auto& m : r.matched)
      j["matched"].push_back({{"type", to_string(m.type)},
                              {"from", xyz(m.from)},
                              {"to", xyz(m.to)},
                              {"linked", m.linked},
                              {"detour", m.detour},
                              {"to_type", to_string(m.to_type)}});
    if (r.guided)
      for (size_t m = 0; m < r.matched.size(); ++m) {
        j["matched"][m]["phase_turns"] = r.matched[m].phase_turns;
        j["matched"][m]["phase_swing"] = r.matched[m].phase_swing;
      }
    for (const char* key : {"created", "cancelled"}) {
      j[key] = json::array();
      for (const auto& p : std::string(key) == "created" ? r.created : r.cancelled)
        j[key].push_back({{"t", p.t},
                          {"at", xyz(p.at)},
                          {"saddle", xyz(p.saddle)},
                          {"node", xyz(p.node)},
                          {"node_type", to_string(p.node_type)}});
    }
    j["separation"] = r.separation;
    if (r.lowered_from > 0) j["lowered_from"] = r.lowered_from, j["lowered_because"] = r.lowered_because;
    if (std::isfinite(r.closest_approach)) j["closest_approach"] = r.closest_approach;
    if (!r.collision.empty()) j["collision"] = r.collision;
    if (r.collision_at) j["collision_at"] = collision_json(*r.collision_at);
    j["routing"] = r.routing;
    j["guided"] = r.guided;
    j["fallback"] = r.fallback;
    if (!r.unguided_reason.empty()) j["unguided_reason"] = r.unguided_reason;
    if (r.first_wrong) j["first_wrong"] = wrong_frame_json(*r.first_wrong);
    if (r.middle_keyframe) j["middle_keyframe"] = middle_keyframe_json(*r.middle_keyframe);
    j["unpaired"] = json::array();
    for (const auto& p : r.unpaired_first) j["unpaired"].push_back(xyz(p));
    for (const auto& p : r.unpaired_second) j["unpaired"].push_back(xyz(p));
    out.push_back(j);
  }
  return out;
}

std::optional<std::vector<KeyframeIntervalReport>> keyframe_intervals_from_json(const nlohmann::json& file) {
  using nlohmann::json;
  auto type = [](const json& name) {
    for (const SingularityType t : {SingularityType::source, SingularityType::sink, SingularityType::saddle,
                                    SingularityType::center, SingularityType::attracting_focus,
                                    SingularityType::repelling_focus})
      if (name.get<std::string>() == to_string(t)) return t;
    throw std::invalid_argument("unknown singularity type");
  };
  auto xyz = [](const json& p) {
    if (!p.is_array() || p.size() != 3) throw std::invalid_argument("not a point");
    return Vec3(p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
  };
  try {
    std::vector<KeyframeIntervalReport> out;
    for (const json& j : file.at("intervals")) {
      KeyframeIntervalReport r;
      r.t0 = j.at("interval").at(0).get<double>();
      r.t1 = j.at("interval").at(1).get<double>();
      r.from_keyframe = j.at("keyframes").at(0).get<int>();
      r.to_keyframe = j.at("keyframes").at(1).get<int>();
      r.bifurcation_t = j.at("bifurcation_t").get<double>();
      for (const json& m : j.at("matched"))
        r.matched.push_back({type(m.at("type")), xyz(m.at("from")), xyz(m.at("to")), m.at("linked").get<bool>(),
                             m.at("detour").get<double>(), type(m.at("to_type")), m.value("phase_turns", 0),
                             m.value("phase_swing", 0.0)});
      for (const char* key : {"created", "cancelled"})
        for (const json& p : j.at(key)) {
          KeyframeIntervalReport::Pair pair;
          pair.t = p.at("t").get<double>();
          pair.at = xyz(p.at("at"));
          pair.saddle = xyz(p.at("saddle"));
          pair.node = xyz(p.at("node"));
          pair.node_type = type(p.at("node_type"));
          (std::string(key) == "created" ? r.created : r.cancelled).push_back(pair);
        }
      r.separation = j.at("separation").get<double>();
      r.lowered_from = j.value("lowered_from", 0.0);
      r.lowered_because = j.value("lowered_because", std::string());
      if (j.contains("closest_approach")) r.closest_approach = j.at("closest_approach").get<double>();
      r.collision = j.value("collision", std::string());
      if (j.contains("collision_at")) {
        const json& ca = j.at("collision_at");
        KeyframeIntervalReport::Collision col;
        col.t = ca.at("t").get<double>();
        col.points = {xyz(ca.at("points").at(0)), xyz(ca.at("points").at(1))};
        col.types = {type(ca.at("types").at(0)), type(ca.at("types").at(1))};
        col.template_ = ca.at("template").get<bool>();
        col.distance = ca.at("distance").get<double>();
        col.required = ca.at("required").get<double>();
        r.collision_at = col;
      }
      r.routing = j.at("routing").get<std::string>();
      r.guided = j.at("guided").get<bool>();
      r.fallback = j.value("fallback", false);
      r.unguided_reason = j.value("unguided_reason", std::string());
      if (j.contains("first_wrong")) {
        const json& fw = j.at("first_wrong");
        KeyframeIntervalReport::WrongFrame w;
        w.t = fw.at("t").get<double>();
        w.found = fw.at("found").get<int>();
        w.planned = fw.at("planned").get<int>();
        w.extra = fw.at("extra").get<bool>();
        w.type = type(fw.at("type"));
        w.at = xyz(fw.at("at"));
        if (fw.contains("distance")) {
          w.distance = fw.at("distance").get<double>();
          w.nearest_type = type(fw.at("nearest_type"));
        }
        w.face_edges = fw.at("face_edges").get<double>();
        r.first_wrong = w;
      }
      if (j.contains("middle_keyframe")) {
        const json& mk = j.at("middle_keyframe");
        KeyframeIntervalReport::MiddleKeyframe m;
        m.keyframe.t = mk.at("keyframe").at("t").get<double>();
        for (const json& e : mk.at("keyframe").at("elements")) {
          KeyframeElement element;
          element.kind = e.at("kind").get<std::string>();
          if (e.contains("type")) {
            element.type = singular_type_from_string(e.at("type").get<std::string>());
            if (!element.type) throw std::invalid_argument("unknown singular type");
            element.jacobian = jacobian_of(*element.type);
          } else {
            const json& a = e.at("jacobian");
            element.jacobian << a.at(0).at(0).get<double>(), a.at(0).at(1).get<double>(), a.at(1).at(0).get<double>(),
                a.at(1).at(1).get<double>();
          }
          element.at = xyz(e.at("at"));
          m.keyframe.elements.push_back(element);
        }
        m.from = mk.at("from").get<std::vector<int>>();
        m.to = mk.at("to").get<std::vector<int>>();
        r.middle_keyframe = std::move(m);
      }
      for (const json& p : j.at("unpaired")) r.unpaired_first.push_back(xyz(p));
      out.push_back(std::move(r));
    }
    return out;
  } catch (const std::exception&) {
    return std::nullopt;  // not such a file: the caller plans again
  }
}

}  // namespace tvf
