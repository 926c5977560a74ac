#include "tvf/integrate/periodic_orbits.h"

#include "tvf/core/error.h"
#include "tvf/integrate/streamline.h"
#include "tvf/integrate/surface_walk.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

namespace tvf {

const char* to_string(OrbitStability s) {
  return s == OrbitStability::attracting ? "attracting" : "repelling";
}

namespace {

constexpr double kTwoPi = 6.283185307179586;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr size_t kMaxPoints = 96;  // points kept per orbit (the JSON stays small)

bool searched(SingularityType type, bool include_nodes) {
  switch (type) {
    case SingularityType::center:
    case SingularityType::attracting_focus:
    case SingularityType::repelling_focus: return true;
    case SingularityType::source:
    case SingularityType::sink: return include_nodes;
    case SingularityType::saddle: return false;
  }
  return false;
}

// What every section of a frame shares, found once a frame (each is a pass over the whole
// mesh or frame; issue 15): the mean edge length, the bounding-box diagonal and the
// frame's largest |V| (StreamlineOptions::max_speed).
struct FrameScales {
  double edge = 0, diameter = 0, max_speed = 0;
  std::vector<std::pair<Vec3, Vec3>> boundary;  // the domain's boundary edges
};

FrameScales frame_scales(const Mesh& mesh, std::span<const cplx> values) {
  FrameScales s{mesh.mean_edge_length(), mesh.diameter(), max_speed(values), {}};
  for (int h = 0; h < mesh.num_halfedges(); ++h)
    if (mesh.is_boundary_halfedge(h)) s.boundary.emplace_back(mesh.position(mesh.tail(h)), mesh.position(mesh.head(h)));
  return s;
}

// The closest any point of `pts` comes to the boundary edges (infinity on a closed mesh).
double boundary_distance(const std::vector<Vec3>& pts, const std::vector<std::pair<Vec3, Vec3>>& boundary) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& [a, b] : boundary) {
    const Vec3 e = b - a;
    const double n2 = e.squaredNorm();
    for (const Vec3& x : pts) {
      const double u = n2 > 0 ? std::clamp((x - a).dot(e) / n2, 0.0, 1.0) : 0.0;
      best = std::min(best, (x - a - u * e).norm());
    }
  }
  return best;
}

// The Poincaré section of one focus: a ray in the plane of its face.
class Section {
public:
  Section(const TangentBundle& bundle, std::span<const cplx> values, const Singularity& focus,
          const std::vector<Singularity>& others, const PeriodicOrbitOptions& options, const FrameScales& scales)
      : bundle_(bundle), values_(values), focus_(focus), max_speed_(scales.max_speed) {
    edge_ = scales.edge;
    const int f = focus.where.face;
    const Vec3 n = bundle.face_normal(f);
    // The ray points away from the nearest other singularity (the most room), else along e1.
    Vec3 dir = bundle.face_e1(f);
    double nearest = kInf;
    for (const Singularity& s : others) {
      if (&s == &focus) continue;
      const Vec3 d = s.position - focus.position;
      const double dist = d.norm();
      if (dist < nearest) {
        nearest = dist;
        const Vec3 away = -(d - d.dot(n) * n);
        if (away.norm() > 1e-12 * dist) dir = away.normalized();
      }
    }
    u_ = dir;
    v_ = n.cross(u_);
    ray_ = bundle.world_to_face(f, u_);
    ray_ /= std::abs(ray_);
    r_min_ = options.min_radius * edge_;
    r_max_ = std::min(0.9 * nearest, options.max_radius * scales.diameter);
    // The domain boundary along the ray.
    if (std::isfinite(r_max_) && r_max_ > r_min_) {
      const SurfaceWalk w = walk_surface(bundle, focus.where, r_max_ * ray_);
      if (w.hit_boundary) r_max_ = 0.9 * w.travelled * r_max_;
    }
    r_out_ = std::isfinite(nearest) ? std::min(1.5 * r_max_, 0.95 * nearest) : 1.5 * r_max_;
  }

  double r_min() const { return r_min_; }
  double r_max() const { return r_max_; }

  // Radius and winding angle of a point in the focus's tangent plane.
  double radius(const Vec3& x) const {
    const Vec3 d = x - focus_.position;
    return std::hypot(d.dot(u_), d.dot(v_));
  }
  // The radius squared (each step's tests against the section's inner and outer radii,
  // without a hypot call).
  double radius2(const Vec3& x) const {
    const Vec3 d = x - focus_.position;
    const double a = d.dot(u_), b = d.dot(v_);
    return a * a + b * b;
  }
  double angle(const Vec3& x) const {
    const Vec3 d = x - focus_.position;
    return std::atan2(d.dot(v_), d.dot(u_));
  }

  SurfacePoint seed(double r) const { return walk_surface(bundle_, focus_.where, r * ray_).end; }

  struct Turn {
    double value = kInf;  // P(r) − r; +inf: went out; −r: went into the focus; NaN: lost
    std::vector<Vec3> points;
    std::vector<double> speeds;
    std::vector<int> faces;  // the face of each point
  };

  // One turn from the seed at radius r, with (sign +1) or against the flow.
  Turn turn(double r, double sign, bool keep) const {
    const SurfacePoint s = seed(r);
    const Vec3 x0 = surface_position(bundle_.mesh(), s);
    const double r0 = radius(x0);
    double winding = 0, last_angle = angle(x0);
    Vec3 last = x0;
    std::optional<double> crossing;  // P(r)
    enum class End { none, in, out } end = End::none;
    Vec3 cross_point = x0;
    StreamlineOptions o;
    o.both_directions = false;
    o.backward_only = sign < 0;
    o.stop_when_closed = false;
    o.stop_at_singular_faces = false;
    o.step = std::min(0.5 * edge_, kTwoPi * std::max(r, r_min_) / 48);
    o.max_length = 3 * kTwoPi * r_out_;
    o.max_speed = max_speed_;
    const double in2 = (0.3 * r_min_) * (0.3 * r_min_), out2 = r_out_ * r_out_;
    o.accept = [&](const Vec3& x) {
      const double rx2 = radius2(x);
      if (rx2 < in2) {
        end = End::in;
        return false;
      }
      if (rx2 > out2) {
        end = End::out;
        return false;
      }
      const double a = angle(x);
      double da = a - last_angle;
      if (da > kTwoPi / 2) da -= kTwoPi;
      if (da < -kTwoPi / 2) da += kTwoPi;
      const double w = winding + da;
      if (std::abs(w) >= kTwoPi) {
        // Crossed the ray: interpolate linearly in the winding angle.
        const double s_frac = (kTwoPi - std::abs(winding)) / std::abs(da);
        cross_point = last + s_frac * (x - last);
        crossing = radius(cross_point);
        return false;
      }
      winding = w;
      last_angle = a;
      last = x;
      return true;
    };
    const Streamline line = trace_streamline(bundle_, values_, s, o);
    Turn t;
    if (crossing) {
      t.value = *crossing - r0;
      if (keep) {
        t.points.assign(line.points.begin() + static_cast<std::ptrdiff_t>(line.seed), line.points.end());
        t.speeds.assign(line.speeds.begin() + static_cast<std::ptrdiff_t>(line.seed), line.speeds.end());
        for (size_t k = line.seed; k < line.where.size(); ++k) t.faces.push_back(line.where[k].face);
        // The crossing closes the loop: the seed's point is its start.
      }
    } else if (end == End::in || line.stop_forward == StopReason::singularity) {
      t.value = radius(line.points.back()) < r0 ? -r0 : kInf;
    } else if (end == End::out || line.stop_forward == StopReason::boundary) {
      t.value = kInf;
    } else {
      t.value = std::numeric_limits<double>::quiet_NaN();
    }
    return t;
  }

  double edge() const { return edge_; }

private:
  const TangentBundle& bundle_;
  std::span<const cplx> values_;
  const Singularity& focus_;
  double max_speed_ = 0;
  double edge_ = 0;
  Vec3 u_, v_;
  cplx ray_{1, 0};
  double r_min_ = 0, r_max_ = 0, r_out_ = 0;
};

// ∮ ds/|V| over a closed polyline with speeds at its points (trapezoid rule).
double period_of(const std::vector<Vec3>& pts, const std::vector<double>& speeds) {
  double T = 0;
  for (size_t k = 0; k < pts.size(); ++k) {
    const size_t l = (k + 1) % pts.size();
    const double ds = (pts[l] - pts[k]).norm();
    const double a = speeds[k], b = speeds[l];
    if (a > 0 && b > 0) T += 0.5 * ds * (1 / a + 1 / b);
  }
  return T;
}

// ln P′(r*) of the forward return map: for a flow on a surface the Poincaré map's slope at a
// periodic orbit is exp(∮ div V dt) (Liouville's formula for the linearised flow; dt =
// ds/|V| along it), whatever the section; div V on each face is the trace of the field's
// linear interpolant's Jacobian there (the covariant divergence on surfaces). Exact for the
// template (r′ = μr − r³ at r² = μ: div V = 2μ − 4r² = −2μ over a period of 2π, ln P′ =
// −4πμ), and, unlike the slope of D by differences, resolved however strongly the cycle
// attracts: where P′ < 1e-2 the differences of D over ±¼ edge length were the integrator's
// noise (P′ of the μ = 1 cycle of example 23 came out −0.005, e^{−4π} = 3.5e-6).
double log_multiplier(const TangentBundle& bundle, std::span<const cplx> values, const std::vector<Vec3>& pts,
                      const std::vector<double>& speeds, const std::vector<int>& faces) {
  std::vector<double> rate(pts.size());  // div V / |V| at each point
  for (size_t k = 0; k < pts.size(); ++k)
    rate[k] = speeds[k] > 0 ? face_jacobian(bundle, values, faces[k]).trace() / speeds[k] : 0.0;
  double sum = 0;
  for (size_t k = 0; k < pts.size(); ++k) {
    const size_t l = (k + 1) % pts.size();
    sum += 0.5 * (pts[l] - pts[k]).norm() * (rate[k] + rate[l]);
  }
  return sum;
}

}  // namespace

std::vector<PeriodicOrbit> find_frame_orbits(const TangentBundle& bundle, std::span<const cplx> values,
                                             const std::vector<Singularity>& singularities,
                                             const PeriodicOrbitOptions& options) {
  std::vector<PeriodicOrbit> out;
  std::optional<FrameScales> scales;  // found at the frame's first section
  for (size_t k = 0; k < singularities.size(); ++k) {
    const Singularity& focus = singularities[k];
    if (focus.index != 1 || !searched(focus.type, options.include_nodes)) continue;
    if (!scales) scales = frame_scales(bundle.mesh(), values);
    const Section section(bundle, values, focus, singularities, options, *scales);
    const double r0 = section.r_min(), r1 = section.r_max();
    if (!(r1 > r0)) continue;
    const int n = std::clamp(static_cast<int>(std::ceil((r1 - r0) / section.edge())) + 1, 4,
                             std::max(4, options.radius_samples));
    std::vector<double> rs(static_cast<size_t>(n)), ds(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) {
      rs[static_cast<size_t>(i)] = r0 + (r1 - r0) * i / (n - 1);
      ds[static_cast<size_t>(i)] = section.turn(rs[static_cast<size_t>(i)], 1.0, false).value;
    }
    for (int i = 0; i + 1 < n; ++i) {
      double a = rs[static_cast<size_t>(i)], b = rs[static_cast<size_t>(i) + 1];
      double da = ds[static_cast<size_t>(i)], db = ds[static_cast<size_t>(i) + 1];
      if (std::isnan(da) || std::isnan(db) || !((da > 0 && db < 0) || (da < 0 && db > 0))) continue;
      // Illinois regula falsi on D (bisection while an end is infinite: went out).
      int side = 0;
      for (int it = 0; it < 60 && b - a > 1e-6 * section.edge(); ++it) {
        double r = std::isfinite(da) && std::isfinite(db) ? (a * db - b * da) / (db - da) : 0.5 * (a + b);
        if (!(r > a && r < b)) r = 0.5 * (a + b);
        const double dr = section.turn(r, 1.0, false).value;
        if (std::isnan(dr)) break;
        if (dr == 0) {
          a = b = r;
          break;
        }
        if ((dr > 0) == (da > 0)) {
          a = r, da = dr;
          if (side == -1) db *= 0.5;
          side = -1;
        } else {
          b = r, db = dr;
          if (side == 1) da *= 0.5;
          side = 1;
        }
      }
      const double r = 0.5 * (a + b);
      PeriodicOrbit orbit;
      // D falls through zero (the forward map contracts onto r*): attracting.
      orbit.stability = ds[static_cast<size_t>(i)] > 0 ? OrbitStability::attracting : OrbitStability::repelling;
      // The orbit itself and its multiplier, traced the way it attracts (the map that
      // contracts; a repelling cycle's forward multiplier is the inverse of its backward one).
      const double sign = orbit.stability == OrbitStability::attracting ? 1.0 : -1.0;
      Section::Turn turn = section.turn(r, sign, true);
      if (!std::isfinite(turn.value) || turn.points.size() < 8 || std::abs(turn.value) > 0.25 * section.edge())
        continue;
      const double delta = std::min(0.25 * section.edge(), 0.25 * r);
      const double lo = section.turn(r - delta, sign, false).value, hi = section.turn(r + delta, sign, false).value;
      if (!std::isfinite(lo) || !std::isfinite(hi)) continue;
      const double contraction = 1 + (hi - lo) / (2 * delta);  // P′ of the contracting map
      // Hyperbolic on both sides: the edge of a center's ring of closed orbits (neutral
      // inside, spiralling outside) contracts on one side only.
      const double inner = 1 + (turn.value - lo) / delta, outer = 1 + (hi - turn.value) / delta;
      const double most = 1 - options.min_multiplier_gap;
      if (!(contraction < most && inner < most && outer < most)) continue;  // neutral or not a cycle
      // The multiplier itself from the divergence along the orbit (log_multiplier); the
      // differences above only decide that the cycle is hyperbolic. Both must agree on the
      // side it contracts (a cycle whose divergence says otherwise is not resolved).
      const double log_p = log_multiplier(bundle, values, turn.points, turn.speeds, turn.faces);
      if ((orbit.stability == OrbitStability::attracting) != (log_p < 0)) continue;
      // Nor a loop within half an edge length of the domain's boundary: there the wall, a
      // streamline of the design, and the corners' saddles make a polycycle that the
      // piecewise-linear field closes into "cycles" of either stability (the double gyre's
      // cells: repelling loops 0.008 from the walls, multiplier 1.15, in single frames).
      if (boundary_distance(turn.points, scales->boundary) < 0.5 * scales->edge) continue;
      // Nor, on a surface, a loop that runs through the fold of the focus's plane: radius and
      // winding are measured in that plane, which sees the surface one to one only until it
      // has turned by 90°; past it, points 30° and 150° round a sphere project to one radius,
      // and a sphere's Hopf cycle was found a second time from the antipodal focus as a
      // "cycle" of radius 1.66. Measured by the points' elevation over the plane seen from
      // the focus: those loops reached 74–82° (past 140° round the sphere), true cycles 18°
      // on the sphere and up to 60° on CGAL's cow and elephant, where the focus face's
      // normal is a scan's (one face normal facing away had dropped the cow's cycle).
      const Vec3 up = bundle.face_normal(focus.where.face);
      const double steep = std::tan(70 * std::numbers::pi / 180);
      if (std::any_of(turn.points.begin(), turn.points.end(), [&](const Vec3& x) {
            const Vec3 d = x - focus.position;
            const double h = d.dot(up);
            return std::abs(h) > steep * (d - h * up).norm();
          }))
        continue;
      orbit.multiplier = std::exp(log_p);  // +inf past e^709: JSON null
      if (sign < 0) {
        std::reverse(turn.points.begin(), turn.points.end());
        std::reverse(turn.speeds.begin(), turn.speeds.end());
      }
      orbit.frame = focus.frame;
      orbit.t = focus.t;
      orbit.center = focus.position;
      orbit.singularity = static_cast<int>(k);
      double sum = 0;
      for (const Vec3& x : turn.points) sum += (x - focus.position).norm();
      orbit.radius = sum / static_cast<double>(turn.points.size());
      orbit.period = period_of(turn.points, turn.speeds);
      // At most kMaxPoints points in the result (every k-th of the traced ones).
      const size_t stride = (turn.points.size() + kMaxPoints - 1) / kMaxPoints;
      for (size_t q = 0; q < turn.points.size(); q += stride) orbit.points.push_back(turn.points[q]);
      out.push_back(std::move(orbit));
    }
  }
  return out;
}

namespace {

// Orbit tracks: ids by nearest continuation from frame to frame.
void track_orbits(std::vector<std::vector<PeriodicOrbit>>& frames, double distance) {
  int next = 0;
  for (size_t j = 0; j < frames.size(); ++j) {
    std::vector<char> taken(j > 0 ? frames[j - 1].size() : 0, 0);
    for (PeriodicOrbit& o : frames[j]) {
      int best = -1;
      double best_score = kInf;
      if (j > 0)
        for (size_t k = 0; k < frames[j - 1].size(); ++k) {
          const PeriodicOrbit& p = frames[j - 1][k];
          if (taken[k] || p.stability != o.stability) continue;
          const double dc = (p.center - o.center).norm();
          const double dr = std::abs(p.radius - o.radius);
          if (dc > distance || dr > std::max(distance, 0.3 * std::max(p.radius, o.radius))) continue;
          const double score = dc + dr;
          if (score < best_score) best_score = score, best = static_cast<int>(k);
        }
      if (best >= 0) {
        taken[static_cast<size_t>(best)] = 1;
        o.id = frames[j - 1][static_cast<size_t>(best)].id;
      } else {
        o.id = next++;
      }
    }
  }
}

// Hopf events: trace sign changes of a focus, confirmed by an orbit track ending there.
// `least_rate`: the smallest |Re λ / Im λ| of a focus on each side (see below).
std::vector<HopfEvent> find_hopf_events(const Topology& topo, const std::vector<std::vector<PeriodicOrbit>>& frames,
                                        double distance, int hopf_frames, double least_rate) {
  std::vector<HopfEvent> out;
  const size_t N = topo.singularities.size();
  // First and last frame of each orbit track.
  struct Track {
    int first = -1, last = -1;
    Vec3 first_center, last_center;
    OrbitStability stability = OrbitStability::attracting;
  };
  std::vector<Track> tracks;
  for (const auto& f : frames)
    for (const PeriodicOrbit& o : f) {
      if (o.id >= static_cast<int>(tracks.size())) tracks.resize(static_cast<size_t>(o.id) + 1);
      Track& tr = tracks[static_cast<size_t>(o.id)];
      if (tr.first < 0) tr.first = o.frame, tr.first_center = o.center;
      tr.last = o.frame, tr.last_center = o.center;
      tr.stability = o.stability;
    }
  auto complex_eigen = [](const Mat2& J) {
    const double tr = J.trace(), det = J.determinant();
    return det > 0.25 * tr * tr;
  };
  // |Re λ| / Im λ of a focus's linear part (its growth per radian turned).
  auto rate = [](const Mat2& J) {
    const double half = 0.5 * J.trace();
    return half / std::sqrt(std::max(J.determinant() - half * half, 1e-300));
  };
  // The nearest index-+1 singularity of frame f within `distance` of x (of those with
  // complex eigenvalues, if asked), or −1.
  auto nearest_plus_one = [&](size_t f, const Vec3& x, bool complex_only) {
    int m = -1;
    double dm = distance;
    for (size_t l = 0; l < topo.singularities[f].size(); ++l) {
      const Singularity& c = topo.singularities[f][l];
      if (c.index != 1 || (complex_only && !complex_eigen(c.jacobian))) continue;
      const double d = (c.position - x).norm();
      if (d <= dm) dm = d, m = static_cast<int>(l);
    }
    return m;
  };
  // Along the focus from singularity k of frame j, frame by frame in direction `dir` (the
  // nearest +1 with complex eigenvalues within `distance`) while its trace keeps the sign
  // `sign`, for `hopf_frames` frames and then while |rate| still grows (a slow ramp of μ
  // crosses the center band in many frames; a center that wavers does not grow): the
  // largest |rate| it reaches there.
  auto reach = [&](size_t j, size_t k, int dir, double sign) {
    double most = 0, last = 0;
    for (int step = 0;; ++step) {
      const Singularity& s = topo.singularities[j][k];
      const double r = rate(s.jacobian);
      if (r * sign < 0 || (step > hopf_frames && std::abs(r) <= last)) break;
      last = std::abs(r);
      most = std::max(most, last);
      if ((dir < 0 && j == 0) || (dir > 0 && j + 1 >= N)) break;
      const size_t next = dir < 0 ? j - 1 : j + 1;
      const int m = nearest_plus_one(next, s.position, true);
      if (m < 0) break;
      j = next;
      k = static_cast<size_t>(m);
    }
    return most;
  };
  std::vector<char> used(tracks.size(), 0);
  for (size_t j = 0; j + 1 < N; ++j) {
    const auto& a = topo.singularities[j];
    const auto& b = topo.singularities[j + 1];
    for (size_t k = 0; k < a.size(); ++k) {
      if (a[k].index != 1 || !complex_eigen(a[k].jacobian)) continue;
      const int m = nearest_plus_one(j + 1, a[k].position, false);
      if (m < 0) continue;
      const Singularity& s = b[static_cast<size_t>(m)];
      if (!complex_eigen(s.jacobian)) continue;
      const double ta = a[k].jacobian.trace(), tb = s.jacobian.trace();
      if (!((ta < 0 && tb >= 0) || (ta > 0 && tb <= 0))) continue;
      // A change of stability, not a center's trace wavering about zero: on each side,
      // before its trace turns back, the focus must spiral as fast as a hyperbolic cycle
      // contracts (`least_rate`), and from one side to the other its rate must cross the
      // whole center band (|Re λ| ≤ kCenterTolerance·|Im λ|, where the analysis calls it a
      // center): the sum of the two sides' largest rates over 2·kCenterTolerance (one side
      // may be cut short by the end of the time range: CGAL's elephant, −0.29 → +0.064 at
      // its last frame). (A center the key-frame guide carries as an exact rotation, |Re λ /
      // Im λ| < 1e-4, flipped its trace's sign at the last frame of the knot at 33², the
      // moving vortex of examples/05, a center at ±0.009, at t = 0.25, and a vortex of
      // examples/12's scene_sun at −0.025 → +0.053 → −0.051: each beside a cycle of the
      // field's nonlinear part, all were reported as Hopf events. A Hopf template's focus
      // reaches ±0.35.)
      const double before = reach(j, k, -1, ta < 0 ? -1.0 : 1.0);
      const double after = reach(j + 1, static_cast<size_t>(m), +1, ta < 0 ? 1.0 : -1.0);
      if (std::min(before, after) < least_rate || before + after <= 2 * kCenterTolerance) continue;
      const double w = ta / (ta - tb);
      HopfEvent e;
      e.t = (1 - w) * topo.times[j] + w * topo.times[j + 1];
      e.position = (1 - w) * a[k].position + w * s.position;
      // The cycle surrounds the focus on the side where the focus repels (supercritical,
      // an attracting cycle) or attracts (subcritical, a repelling cycle).
      int best = -1;
      double best_gap = kInf;
      for (size_t id = 0; id < tracks.size(); ++id) {
        const Track& tr = tracks[id];
        if (tr.first < 0 || used[id] || tr.last == tr.first) continue;  // one frame: too weak a sign
        // Born after t* (first frame ≥ j + 1) or ended before it (last frame ≤ j), with one
        // frame of slack: the focus's stability is read from one face's linear Jacobian,
        // the cycle from streamlines across many faces, and near t* the two may disagree by a
        // frame (a focus at a vertex on CGAL's elephant: trace −0.01 at the frame where a
        // cycle of radius 1.8 edges is first found).
        const bool born = tr.first >= static_cast<int>(j) && tr.first <= static_cast<int>(j) + hopf_frames &&
                          (tr.first_center - e.position).norm() <= distance;
        const bool ended = tr.last <= static_cast<int>(j) + 1 && tr.last + hopf_frames > static_cast<int>(j) &&
                           (tr.last_center - e.position).norm() <= distance;
        if (!born && !ended) continue;
        // The focus inside an attracting cycle repels, inside a repelling one attracts.
        const double inside_trace = born ? tb : ta;
        if ((tr.stability == OrbitStability::attracting) != (inside_trace > 0)) continue;
        const double gap = born ? std::abs(tr.first - (static_cast<double>(j) + 1))
                                : std::abs(static_cast<double>(j) - tr.last);
        if (gap < best_gap) best_gap = gap, best = static_cast<int>(id);
      }
      if (best < 0) continue;
      used[static_cast<size_t>(best)] = 1;
      e.orbit = best;
      e.supercritical = tracks[static_cast<size_t>(best)].stability == OrbitStability::attracting;
      const int pa = topo.singularity_path.size() > j ? topo.singularity_path[j][k] : -1;
      const int pb = topo.singularity_path.size() > j + 1 ? topo.singularity_path[j + 1][static_cast<size_t>(m)] : -1;
      if (pa >= 0) e.paths.push_back(pa);
      if (pb >= 0 && pb != pa) e.paths.push_back(pb);
      out.push_back(std::move(e));
    }
  }
  std::sort(out.begin(), out.end(), [](const HopfEvent& x, const HopfEvent& y) { return x.t < y.t; });
  return out;
}

}  // namespace

PeriodicOrbits find_periodic_orbits(const TangentBundle& bundle, const Field& field, const Topology& topology,
                                    const PeriodicOrbitOptions& options) {
  const int N = field.frames();
  TVF_CHECK(static_cast<int>(topology.singularities.size()) == N, "topology of {} frames for a field of {}",
            topology.singularities.size(), N);
  std::vector<std::vector<PeriodicOrbit>> frames(static_cast<size_t>(N));
  auto one = [&](int j) {
    check_analysis_cancel(options.cancel);
    frames[static_cast<size_t>(j)] =
        find_frame_orbits(bundle, field.frame(j), topology.singularities[static_cast<size_t>(j)], options);
  };
  if (options.parallel)
    tbb::parallel_for(0, N, one);
  else
    for (int j = 0; j < N; ++j) one(j);
  check_analysis_cancel(options.cancel);
  const double distance = options.track_distance * bundle.mesh().mean_edge_length();
  track_orbits(frames, distance);
  PeriodicOrbits out;
  // A focus's linear part turns its radius by e^{2π rate} per turn: hyperbolic by the
  // cycles' standard when that differs from 1 by min_multiplier_gap.
  const double least_rate = -std::log1p(-options.min_multiplier_gap) / (2 * std::numbers::pi);
  out.hopf = find_hopf_events(topology, frames, distance, options.hopf_frames, least_rate);
  for (auto& f : frames)
    for (auto& o : f) out.orbits.push_back(std::move(o));
  return out;
}

void add_periodic_orbits_to_json(nlohmann::json& analysis, const PeriodicOrbits& orbits) {
  using json = nlohmann::json;
  auto vec = [](const Vec3& x) { return json::array({x.x(), x.y(), x.z()}); };
  json list = json::array();
  for (const PeriodicOrbit& o : orbits.orbits) {
    json pts = json::array();
    for (const Vec3& x : o.points) pts.push_back(vec(x));
    list.push_back({{"frame", o.frame},
                    {"t", o.t},
                    {"center", vec(o.center)},
                    {"radius", o.radius},
                    {"stability", to_string(o.stability)},
                    {"points", std::move(pts)},
                    {"id", o.id},
                    {"period", o.period},
                    {"multiplier", o.multiplier}});
  }
  analysis["periodic_orbits"] = std::move(list);
  json& bifs = analysis["bifurcations"];
  if (!bifs.is_array()) bifs = json::array();
  for (const HopfEvent& e : orbits.hopf)
    bifs.push_back({{"t", e.t},
                    {"position", vec(e.position)},
                    {"kind", "hopf"},
                    {"paths", e.paths},
                    {"orbit", e.orbit},
                    {"criticality", e.supercritical ? "supercritical" : "subcritical"}});
}

}  // namespace tvf
