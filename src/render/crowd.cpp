#include "tvf/render/crowd.h"

#include "crowd_file_reader.h"

#include "planar_view.h"

#include "tvf/core/atomic_output.h"
#include "tvf/core/error.h"
#include "tvf/core/json_text.h"
#include "tvf/integrate/pathline.h"
#include "tvf/render/frame_output.h"

#include <cairo.h>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <functional>
#include <unordered_map>
#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <optional>
#include <queue>
#include <sstream>

namespace tvf {

using nlohmann::json;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

void check_spec(bool ok, const std::string& what) {
  if (!ok) throw Error(fmt::format("crowd: {}", what));
}

// --- Reading the crowd file -------------------------------------------------------------

struct Reader : CrowdFileReader {
  Vec2 point(const json& j, const std::string& path) const {
    if (!j.is_array() || j.size() != 2) fail(path, "expected a point [x, y]");
    return {number(j[0], path + "[0]", -1e12, 1e12), number(j[1], path + "[1]", -1e12, 1e12)};
  }
  CrowdShape shape(const json& j, const std::string& path) const {
    if (j.is_object() && j.contains("circle")) {
      keys(j, path, {"circle"});
      const json& c = j["circle"];
      keys(c, path + ".circle", {"center", "radius"});
      if (!c.contains("center") || !c.contains("radius")) fail(path + ".circle", "needs center and radius");
      return CrowdShape::circle(point(c["center"], path + ".circle.center"),
                                number(c["radius"], path + ".circle.radius", 1e-12, 1e12));
    }
    if (j.is_object() && j.contains("rectangle")) {
      keys(j, path, {"rectangle"});
      const json& r = j["rectangle"];
      keys(r, path + ".rectangle", {"min", "max"});
      if (!r.contains("min") || !r.contains("max")) fail(path + ".rectangle", "needs min and max");
      const Vec2 lo = point(r["min"], path + ".rectangle.min"), hi = point(r["max"], path + ".rectangle.max");
      if (!(hi.x() > lo.x() && hi.y() > lo.y())) fail(path + ".rectangle", "max must be above min in x and y");
      return CrowdShape::rectangle(lo, hi);
    }
    fail(path, "expected {\"circle\": {...}} or {\"rectangle\": {...}}");
  }
  std::vector<CrowdShape> shapes(const json& j, const std::string& path) const {
    if (!j.is_array()) fail(path, "expected a list of shapes");
    std::vector<CrowdShape> out;
    for (size_t i = 0; i < j.size(); ++i) out.push_back(shape(j[i], fmt::format("{}[{}]", path, i)));
    return out;
  }
};

}  // namespace

// --- Shapes ---------------------------------------------------------------------------------

CrowdShape CrowdShape::circle(const Vec2& c, double r) {
  CrowdShape s;
  s.kind = Kind::circle;
  s.center = c;
  s.radius = r;
  return s;
}

CrowdShape CrowdShape::rectangle(const Vec2& lo, const Vec2& hi) {
  CrowdShape s;
  s.kind = Kind::rectangle;
  s.min = lo;
  s.max = hi;
  s.center = 0.5 * (lo + hi);
  return s;
}

double CrowdShape::distance(const Vec2& x) const {
  if (kind == Kind::circle) return (x - center).norm() - radius;
  const Vec2 half = 0.5 * (max - min);
  const Vec2 d = (x - center).cwiseAbs() - half;
  return d.cwiseMax(0.0).norm() + std::min(std::max(d.x(), d.y()), 0.0);
}

Vec2 CrowdShape::push_out(const Vec2& x, double margin) const {
  if (kind == Kind::circle) {
    const Vec2 d = x - center;
    const double n = d.norm();
    const Vec2 u = n > 0 ? Vec2(d / n) : Vec2(1, 0);
    return center + (radius + margin) * u;
  }
  Vec2 p = x;
  const double to[4] = {x.x() - (min.x() - margin), (max.x() + margin) - x.x(), x.y() - (min.y() - margin),
                        (max.y() + margin) - x.y()};
  const int k = static_cast<int>(std::min_element(to, to + 4) - to);
  if (k == 0) p.x() = min.x() - margin;
  if (k == 1) p.x() = max.x() + margin;
  if (k == 2) p.y() = min.y() - margin;
  if (k == 3) p.y() = max.y() + margin;
  return p;
}

bool CrowdShape::crosses(const Vec2& a, const Vec2& b) const {
  const Vec2 d = b - a;
  if (kind == Kind::circle) {
    // The point of the segment nearest the centre.
    const double len2 = d.squaredNorm();
    const double t = len2 > 0 ? std::clamp((center - a).dot(d) / len2, 0.0, 1.0) : 0.0;
    return (a + t * d - center).norm() < radius;
  }
  // Liang–Barsky clipping against the open rectangle: the parameters t in [0, 1] where the
  // segment is strictly inside on both axes form an interval; it crosses when that is not empty.
  double t0 = 0, t1 = 1;
  for (int i = 0; i < 2; ++i) {
    if (d[i] == 0) {
      if (!(a[i] > min[i] && a[i] < max[i])) return false;
      continue;
    }
    double ta = (min[i] - a[i]) / d[i], tb = (max[i] - a[i]) / d[i];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 >= t1) return false;
  }
  return true;
}

CrowdSpec parse_crowd_spec(const json& j, const std::string& file) {
  const Reader r{{file}};
  r.keys(j, "", {"agents", "speed", "weights", "grid", "agent_radius", "steps_per_frame", "avoidance", "start",
                 "goals", "obstacles"});
  CrowdSpec s;
  r.shared_keys(j, s, {"distance", "weight"});
  if (j.contains("grid")) s.grid = r.integer(j["grid"], "grid", 8, 4096);
  if (j.contains("agent_radius")) s.agent_radius = r.number(j["agent_radius"], "agent_radius", 0, 1e12);
  if (j.contains("avoidance") && j["avoidance"].contains("weight"))
    s.avoidance_weight = r.number(j["avoidance"]["weight"], "avoidance.weight", 0, 1e6);
  if (!j.contains("start")) r.fail("start", "missing: give the shapes the agents start in");
  if (!j.contains("goals")) r.fail("goals", "missing: give at least one goal shape");
  s.starts = r.shapes(j["start"], "start");
  s.goals = r.shapes(j["goals"], "goals");
  if (j.contains("obstacles")) s.obstacles = r.shapes(j["obstacles"], "obstacles");
  if (s.starts.empty()) r.fail("start", "give at least one shape");
  if (s.goals.empty()) r.fail("goals", "give at least one shape");
  return s;
}

CrowdSpec load_crowd_spec(const std::string& path) {
  return read_crowd_file(path, [&](const json& j) { return parse_crowd_spec(j, path); });
}

// --- Fast marching -----------------------------------------------------------------------

std::vector<double> fast_marching(int nx, int ny, double h, std::span<const double> cost,
                                  std::span<const char> source) {
  const size_t n = static_cast<size_t>(nx) * static_cast<size_t>(ny);
  if (nx < 1 || ny < 1 || !(h > 0) || cost.size() != n || source.size() != n)
    throw Error("fast marching: grid sizes do not match");
  std::vector<double> phi(n, kInf);
  std::vector<char> known(n, 0);
  using Item = std::pair<double, size_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> heap;
  for (size_t k = 0; k < n; ++k)
    if (source[k] && std::isfinite(cost[k])) {
      phi[k] = 0;
      heap.push({0.0, k});
    }
  auto value = [&](int i, int j) {
    return i < 0 || j < 0 || i >= nx || j >= ny ? kInf : [&] {
      const size_t k = static_cast<size_t>(j) * static_cast<size_t>(nx) + static_cast<size_t>(i);
      return known[k] ? phi[k] : kInf;
    }();
  };
  while (!heap.empty()) {
    const auto [d, k] = heap.top();
    heap.pop();
    if (known[k] || d > phi[k]) continue;
    known[k] = 1;
    const int i = static_cast<int>(k % static_cast<size_t>(nx)), j = static_cast<int>(k / static_cast<size_t>(nx));
    const int di[4] = {1, -1, 0, 0}, dj[4] = {0, 0, 1, -1};
    for (int q = 0; q < 4; ++q) {
      const int a = i + di[q], b = j + dj[q];
      if (a < 0 || b < 0 || a >= nx || b >= ny) continue;
      const size_t m = static_cast<size_t>(b) * static_cast<size_t>(nx) + static_cast<size_t>(a);
      if (known[m] || !std::isfinite(cost[m])) continue;
      // First-order upwind update from the known neighbours.
      const double ux = std::min(value(a - 1, b), value(a + 1, b));
      const double uy = std::min(value(a, b - 1), value(a, b + 1));
      const double f = cost[m] * h;
      double u;
      if (!std::isfinite(ux) || !std::isfinite(uy) || std::abs(ux - uy) >= f) {
        u = std::min(ux, uy) + f;
      } else {
        u = 0.5 * (ux + uy + std::sqrt(2 * f * f - (ux - uy) * (ux - uy)));
      }
      if (u < phi[m]) {
        phi[m] = u;
        heap.push({u, m});
      }
    }
  }
  return phi;
}

// --- Simulation ----------------------------------------------------------------------------

namespace {

struct Potential {
  int nx = 0, ny = 0;
  double h = 0;
  Vec2 origin;
  std::vector<double> phi;
  std::vector<Vec2> descent;  // unit direction down φ per node (0 where none)
  // The same without growing the obstacles by the agents' radius: where agents pushed
  // by others stand inside that margin (φ = ∞ there), they go on down this one.
  std::vector<Vec2> descent_margin;

  Vec2 node(int i, int j) const { return origin + Vec2(i * h, j * h); }

  // The unit direction down the potential at x (bilinear over the cell's usable nodes).
  Vec2 direction(const Vec2& x) const {
    const Vec2 g = (x - origin) / h;
    const int i = std::clamp(static_cast<int>(std::floor(g.x())), 0, nx - 2);
    const int j = std::clamp(static_cast<int>(std::floor(g.y())), 0, ny - 2);
    const double fx = std::clamp(g.x() - i, 0.0, 1.0), fy = std::clamp(g.y() - j, 0.0, 1.0);
    for (const auto* field : {&descent, &descent_margin}) {
      if (field->empty()) continue;
      Vec2 sum(0, 0);
      for (int q = 0; q < 4; ++q) {
        const int a = i + (q & 1), b = j + (q >> 1);
        const double w = ((q & 1) ? fx : 1 - fx) * ((q >> 1) ? fy : 1 - fy);
        sum += w * (*field)[static_cast<size_t>(b) * static_cast<size_t>(nx) + static_cast<size_t>(a)];
      }
      const double n = sum.norm();
      if (n > 1e-12) return sum / n;
    }
    return {0, 0};
  }
};

Potential make_potential(const Mesh& mesh, const CrowdSpec& spec) {
  Potential p;
  const Vec2 lo = mesh.bbox_min().head<2>(), hi = mesh.bbox_max().head<2>();
  const double ext = std::max(hi.x() - lo.x(), hi.y() - lo.y());
  p.h = ext / (spec.grid - 1);
  p.nx = std::max(2, static_cast<int>(std::ceil((hi.x() - lo.x()) / p.h - 1e-9)) + 1);
  p.ny = std::max(2, static_cast<int>(std::ceil((hi.y() - lo.y()) / p.h - 1e-9)) + 1);
  p.origin = lo;
  const double radius = spec.agent_radius > 0 ? spec.agent_radius : 1.5 * p.h;
  const size_t n = static_cast<size_t>(p.nx) * static_cast<size_t>(p.ny);
  std::vector<double> cost(n, 1.0);
  std::vector<char> source(n, 0);
  size_t sources = 0;
  for (int j = 0; j < p.ny; ++j)
    for (int i = 0; i < p.nx; ++i) {
      const size_t k = static_cast<size_t>(j) * static_cast<size_t>(p.nx) + static_cast<size_t>(i);
      const Vec2 x = p.node(i, j);
      for (const auto& o : spec.obstacles)
        if (o.distance(x) < radius) cost[k] = kInf;
      for (const auto& g : spec.goals)
        if (g.distance(x) < 0 && std::isfinite(cost[k])) source[k] = 1;  // nodes inside a goal
      sources += source[k] ? 1 : 0;
    }
  check_spec(sources > 0, "no goal covers a free cell of the fast-marching grid (goals too small, outside the domain, "
                          "or inside obstacles)");
  p.phi = fast_marching(p.nx, p.ny, p.h, cost, source);
  auto descent_of = [&](const std::vector<double>& phi) {
    std::vector<Vec2> descent(n, Vec2(0, 0));
    auto at = [&](int i, int j) {
      return i < 0 || j < 0 || i >= p.nx || j >= p.ny
                 ? kInf
                 : phi[static_cast<size_t>(j) * static_cast<size_t>(p.nx) + static_cast<size_t>(i)];
    };
    for (int j = 0; j < p.ny; ++j)
      for (int i = 0; i < p.nx; ++i) {
        const double c = at(i, j);
        if (!std::isfinite(c)) continue;
        auto slope = [&](double lo_v, double hi_v) {  // upwind ∂φ: towards the smaller neighbour
          if (std::min(lo_v, hi_v) >= c) return 0.0;
          return lo_v < hi_v ? (c - lo_v) / p.h : (hi_v - c) / p.h;
        };
        const Vec2 grad(slope(at(i - 1, j), at(i + 1, j)), slope(at(i, j - 1), at(i, j + 1)));
        const double nrm = grad.norm();
        if (nrm > 0) descent[static_cast<size_t>(j) * static_cast<size_t>(p.nx) + static_cast<size_t>(i)] = -grad / nrm;
      }
    return descent;
  };
  p.descent = descent_of(p.phi);
  if (!spec.obstacles.empty()) {
    // The margin's own potential: only the obstacles themselves blocked.
    std::vector<double> tight(n, 1.0);
    std::vector<char> tight_source(n, 0);
    for (int j = 0; j < p.ny; ++j)
      for (int i = 0; i < p.nx; ++i) {
        const size_t k = static_cast<size_t>(j) * static_cast<size_t>(p.nx) + static_cast<size_t>(i);
        const Vec2 x = p.node(i, j);
        for (const auto& o : spec.obstacles)
          if (o.distance(x) < 0) tight[k] = kInf;
        for (const auto& g : spec.goals)
          if (g.distance(x) < 0 && std::isfinite(tight[k])) tight_source[k] = 1;
      }
    p.descent_margin = descent_of(fast_marching(p.nx, p.ny, p.h, tight, tight_source));
  }
  return p;
}

// Agents by cells of a uniform grid, for the neighbours within a distance.
class NeighbourGrid {
public:
  explicit NeighbourGrid(double cell) : cell_(cell) {}
  void insert(const Vec2& p, int id) { cells_[key(index(p.x()), index(p.y()))].push_back(id); }
  // Calls f(id) for every id in the cells within r of p (a superset of those within r).
  template <class F>
  void for_each_near(const Vec2& p, double r, F&& f) const {
    for (long j = index(p.y() - r); j <= index(p.y() + r); ++j)
      for (long i = index(p.x() - r); i <= index(p.x() + r); ++i) {
        const auto it = cells_.find(key(i, j));
        if (it != cells_.end())
          for (int id : it->second) f(id);
      }
  }
  // The distance from p to the nearest of points[id] within r (+∞ if none).
  double nearest(const std::vector<Vec2>& points, const Vec2& p, double r) const {
    double best = kInf;
    for_each_near(p, r, [&](int id) { best = std::min(best, (points[static_cast<size_t>(id)] - p).norm()); });
    return best;
  }

private:
  long index(double v) const { return static_cast<long>(std::floor(v / cell_)); }
  static std::uint64_t key(long i, long j) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(i)) << 32) | static_cast<std::uint32_t>(j);
  }
  double cell_;
  std::unordered_map<std::uint64_t, std::vector<int>> cells_;
};

// Agent–agent separation after a step: pairs of active agents closer than `sep` are
// pushed apart along the line joining them, half the overlap each (Jacobi iterations of
// position-based dynamics), each move kept in the box and slid along obstacles by `fix`
// and refused when the whole step from `old` is not `free` (it would pass through an
// obstacle). Pairs still too close after the iterations go back to their positions `old`
// (one agent of a pair at a time, the later first), which kept the distance: so no two
// active agents are ever closer than sep.
void separate(std::vector<Vec2>& x, const std::vector<Vec2>& old, const std::vector<char>& active, double sep,
              const std::function<Vec2(const Vec2& from, const Vec2& to)>& fix,
              const std::function<bool(const Vec2& from, const Vec2& to)>& free) {
  const size_t n = x.size();
  const double tolerance = sep * (1 - 1e-9);
  std::vector<Vec2> correction(n, Vec2(0, 0));
  for (int iteration = 0; iteration < 50; ++iteration) {
    NeighbourGrid grid(sep);
    for (size_t a = 0; a < n; ++a)
      if (active[a]) grid.insert(x[a], static_cast<int>(a));
    std::atomic<bool> overlap = false;
    tbb::parallel_for(size_t{0}, n, [&](size_t a) {
      correction[a] = Vec2(0, 0);
      if (!active[a]) return;
      grid.for_each_near(x[a], sep, [&](int b) {
        if (static_cast<size_t>(b) == a) return;
        const Vec2 d = x[a] - x[static_cast<size_t>(b)];
        const double r = d.norm();
        if (r >= tolerance) return;
        overlap = true;
        // Coincident agents part along x, the lower index to the left.
        const Vec2 u = r > 0 ? Vec2(d / r) : Vec2(a < static_cast<size_t>(b) ? -1.0 : 1.0, 0.0);
        correction[a] += 0.5 * 1.001 * (sep - r) * u;
      });
    });
    if (!overlap) return;
    for (size_t a = 0; a < n; ++a)
      if (active[a] && correction[a].squaredNorm() > 0) {
        // The correction slides along obstacles from where the agent is; where the whole
        // step from old[a] to there would cut an obstacle's corner, it slides from old[a]
        // instead; a correction still not clear is refused.
        Vec2 p = fix(x[a], x[a] + correction[a]);
        if (!free(old[a], p)) p = fix(old[a], p);
        if (free(old[a], p)) x[a] = p;
      }
  }
  // The guarantee: revert both agents of any pair still too close, until none is.
  for (bool again = true; again;) {
    again = false;
    NeighbourGrid grid(sep);
    for (size_t a = 0; a < n; ++a)
      if (active[a]) grid.insert(x[a], static_cast<int>(a));
    for (size_t a = 0; a < n; ++a) {
      if (!active[a]) continue;
      grid.for_each_near(x[a], sep, [&](int b) {
        const size_t bb = static_cast<size_t>(b);
        if (bb == a || (x[a] - x[bb]).norm() >= tolerance) return;
        // One of the two goes back, the later one first (old positions kept the distance,
        // so a pair with both back is apart): reverting both made a dense crowd at a gap
        // lock into the same state step after step.
        const size_t later = std::max(a, bb), earlier = std::min(a, bb);
        const size_t back = x[later] != old[later] ? later : earlier;
        x[back] = old[back];
        again = true;
      });
    }
  }
}

// Where a move from `from` (outside o) to `to` that enters o ends instead: on the face of a
// rectangle it enters through, `margin` outside, keeping the motion along that face (the
// agent slides along a wall and round its corner, never across it); a circle's point
// nearest `to` on its boundary grown by `margin`.
Vec2 slide(const CrowdShape& o, const Vec2& from, const Vec2& to, double margin) {
  if (o.kind == CrowdShape::Kind::circle) return o.push_out(to, margin);
  const Vec2 d = to - from;
  int axis = -1;
  double entry = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < 2; ++i) {
    if (d[i] == 0) continue;
    const double t = std::min((o.min[i] - from[i]) / d[i], (o.max[i] - from[i]) / d[i]);
    if (t > entry) {
      entry = t;
      axis = i;
    }
  }
  if (axis < 0) return o.push_out(to, margin);
  Vec2 q = to;
  q[axis] = d[axis] > 0 ? o.min[axis] - margin : o.max[axis] + margin;
  return q;
}

// Halton sequence value of index k in base b.
double halton(int k, int b) {
  double f = 1, r = 0;
  for (int i = k; i > 0; i /= b) {
    f /= b;
    r += f * (i % b);
  }
  return r;
}

double typical_speed(const Field& field) {
  std::vector<double> s;
  s.reserve(field.data().size());
  for (const cplx& v : field.data()) s.push_back(std::abs(v));
  if (s.empty()) return 0;
  const size_t k = static_cast<size_t>(0.9 * static_cast<double>(s.size() - 1));
  std::nth_element(s.begin(), s.begin() + static_cast<std::ptrdiff_t>(k), s.end());
  return s[k];
}

}  // namespace

CrowdResult simulate_crowd(const TangentBundle& bundle, const Field& field, const CrowdSpec& spec, int frames) {
  detail::require_planar(bundle, "crowd");
  const Mesh& mesh = bundle.mesh();
  check_spec(field.num_vertices() == mesh.num_vertices() && field.frames() >= 1, "the field does not belong to this domain");
  check_spec(spec.agents >= 1 && spec.agents <= 100000, fmt::format("agents {} is outside [1, 100000]", spec.agents));
  check_spec(spec.grid >= 8 && spec.grid <= 4096, fmt::format("grid {} is outside [8, 4096]", spec.grid));
  check_spec(std::isfinite(spec.weight_goal) && std::isfinite(spec.weight_field) && spec.weight_goal >= 0 &&
                 spec.weight_field >= 0,
             "weights must be finite and not negative");
  check_spec(spec.steps_per_frame >= 1 && spec.steps_per_frame <= 1000, "steps_per_frame is outside [1, 1000]");
  check_spec(!spec.starts.empty() && !spec.goals.empty(), "give start and goal shapes");
  check_spec(std::isfinite(spec.separation) && spec.separation >= 0, "avoidance distance must be finite and not negative");
  check_spec(std::isfinite(spec.avoidance_weight) && spec.avoidance_weight >= 0,
             "avoidance weight must be finite and not negative");
  const int total = frames > 0 ? frames : field.frames();
  check_spec(total >= 1 && total <= 1'000'000, fmt::format("frames {} is outside [1, 1000000]", total));

  CrowdResult result;
  const Potential pot = make_potential(mesh, spec);
  result.nx = pot.nx;
  result.ny = pot.ny;
  result.h = pot.h;
  result.grid_origin = pot.origin;
  result.potential = pot.phi;

  const detail::PlanarLocator locator(mesh);
  const FieldSampler sampler(bundle, field);
  const double diag = mesh.diameter();
  const double fscale = typical_speed(field);
  const TimeSampling& ts = field.time();
  const double span = std::abs(ts.t1 - ts.t0) > 0 ? std::abs(ts.t1 - ts.t0) : 1.0;
  // G moves at the field's local speed, but at least at `speed` (by default a quarter of
  // the field's typical speed; 1.5 diagonals over the time range for a zero field): ω_G and ω_F weigh
  // terms of the same size, and where the field is weak the goal still draws agents on.
  const double speed = spec.speed > 0 ? spec.speed : fscale > 0 ? 0.25 * fscale : 1.5 * diag / span;
  const Vec2 lo = mesh.bbox_min().head<2>(), hi = mesh.bbox_max().head<2>();
  auto clear_of_obstacles = [&](const Vec2& from, const Vec2& to) {
    for (const auto& o : spec.obstacles)
      if (o.crosses(from, to)) return false;
    return true;
  };
  // A move from `from` to `to`, clamped to the domain and slid along every obstacle it
  // would enter (`touched` set then); the caller checks that the result is clear.
  auto move_clear = [&](const Vec2& from, const Vec2& to, bool& touched) {
    Vec2 q = to.cwiseMax(lo).cwiseMin(hi);
    for (int pass = 0; pass < 2; ++pass)  // a slide along one obstacle may enter another
      for (const auto& o : spec.obstacles)
        if (o.distance(q) <= 0 || o.crosses(from, q)) {
          q = slide(o, from, q, 1e-9 * diag).cwiseMax(lo).cwiseMin(hi);
          touched = true;
        }
    return q;
  };
  auto blocked = [&](const Vec2& x) {
    for (const auto& o : spec.obstacles)
      if (o.contains(x)) return true;
    return !locator.locate(x).has_value();
  };

  // Starting positions: a Halton sequence over each start shape's box, inside the shape,
  // in the domain and outside obstacles; agents go round the start shapes in turn.
  const bool avoid = spec.separation > 0;
  const double sep = spec.separation;
  NeighbourGrid placed_grid(avoid ? sep : 1.0);
  std::vector<Vec2> start;
  std::vector<int> tried(spec.starts.size(), 0);
  for (int a = 0; a < spec.agents; ++a) {
    const size_t s = static_cast<size_t>(a) % spec.starts.size();
    const CrowdShape& shape = spec.starts[s];
    const Vec2 blo = shape.kind == CrowdShape::Kind::circle ? Vec2(shape.center.array() - shape.radius) : shape.min;
    const Vec2 bhi = shape.kind == CrowdShape::Kind::circle ? Vec2(shape.center.array() + shape.radius) : shape.max;
    bool placed = false;
    for (int attempt = 0; attempt < 10000 && !placed; ++attempt) {
      const int k = ++tried[s];
      const Vec2 x(blo.x() + (bhi.x() - blo.x()) * halton(k, 2), blo.y() + (bhi.y() - blo.y()) * halton(k, 3));
      if (shape.contains(x) && !blocked(x) && (!avoid || placed_grid.nearest(start, x, sep) >= sep)) {
        if (avoid) placed_grid.insert(x, static_cast<int>(start.size()));
        start.push_back(x);
        placed = true;
      }
    }
    check_spec(placed, avoid ? fmt::format("start[{}] has no free place in the domain outside the obstacles at least "
                                           "avoidance.distance {} from the other agents (fewer agents, or larger start "
                                           "shapes)", s, sep)
                             : fmt::format("start[{}] has no free place in the domain outside the obstacles", s));
  }

  auto time_of = [&](int k) { return total > 1 ? ts.t0 + (ts.t1 - ts.t0) * k / (total - 1) : ts.t0; };
  result.times.resize(static_cast<size_t>(total));
  for (int k = 0; k < total; ++k) result.times[static_cast<size_t>(k)] = time_of(k);
  const size_t na = static_cast<size_t>(spec.agents);
  result.positions.assign(na, {});
  result.arrived.assign(na, -1);
  result.reference.assign(na, {});
  std::vector<long> contacts(na, 0);
  auto at_goal = [&](const Vec2& x) {
    for (const auto& g : spec.goals)
      if (g.contains(x)) return true;
    return false;
  };

  // All agents step together (avoidance needs everyone's positions): per step, each
  // active agent's midpoint step of ω_G·G + ω_F·F (+ the separation term), obstacles
  // pushed out, then the separation constraint projected (avoidance on).
  std::vector<Vec2> x = start, moved(na);
  std::vector<char> active(na, 1);
  for (size_t a = 0; a < na; ++a) {
    result.positions[a].push_back(x[a]);
    if (at_goal(x[a])) {
      result.arrived[a] = 0;
      active[a] = 0;
    }
  }
  const double range = 2.0 * sep;  // the separation term acts within this distance
  // Substep length: under half the thinnest obstacle (a rectangle's shorter side, a
  // circle's diameter), so a substep cannot cross one.
  double substep = std::numeric_limits<double>::infinity();
  for (const auto& o : spec.obstacles)
    substep = std::min(substep, 0.45 * (o.kind == CrowdShape::Kind::circle ? 2 * o.radius
                                                                           : (o.max - o.min).minCoeff()));
  for (int k = 1; k < total; ++k) {
    for (int s = 0; s < spec.steps_per_frame; ++s) {
      const double t0 = time_of(k - 1) + (time_of(k) - time_of(k - 1)) * s / spec.steps_per_frame;
      const double dt = std::abs(time_of(k) - time_of(k - 1)) / spec.steps_per_frame;
      const double dir = time_of(k) >= time_of(k - 1) ? 1.0 : -1.0;
      NeighbourGrid grid(avoid ? range : 1.0);
      if (avoid)
        for (size_t a = 0; a < na; ++a)
          if (active[a]) grid.insert(x[a], static_cast<int>(a));
      tbb::parallel_for(size_t{0}, na, [&](size_t a) {
        moved[a] = x[a];
        if (!active[a]) return;
        const Vec2 g0 = pot.direction(x[a]);
        auto field_at = [&](const Vec2& p, double t) {
          if (const auto sp = locator.locate(p)) return Vec2(sampler.world(*sp, t).head<2>());
          return Vec2(0, 0);
        };
        auto velocity = [&](const Vec2& p, double t) {
          // Inside a goal (φ = 0, no descent) the midpoint keeps the direction of the step's start.
          const Vec2 g = pot.direction(p);
          const Vec2 f = field_at(p, t);
          return Vec2(spec.weight_goal * std::max(speed, f.norm()) * (g.squaredNorm() > 0 ? g : g0) +
                      spec.weight_field * f);
        };
        // The separation term (a social force): away from every agent closer than
        // `range`, growing linearly from 0 at `range` to the agent's own speed at `sep`.
        Vec2 push(0, 0);
        if (avoid) {
          const double own = std::max(speed, field_at(x[a], t0).norm());
          grid.for_each_near(x[a], range, [&](int b) {
            if (static_cast<size_t>(b) == a) return;
            const Vec2 d = x[a] - x[static_cast<size_t>(b)];
            const double r = d.norm();
            if (r >= range || r <= 0) return;
            push += spec.avoidance_weight * own * std::min(1.0, (range - r) / (range - sep)) * (d / r);
          });
        }
        const Vec2 mid = (x[a] + 0.5 * dt * (velocity(x[a], t0) + push)).cwiseMax(lo).cwiseMin(hi);
        Vec2 next = x[a] + dt * (velocity(mid, t0 + 0.5 * dir * dt) + push);
        next = next.cwiseMax(lo).cwiseMin(hi);
        // The whole step is checked as a segment, not only where it ends: a long step (the
        // separation push adds to it) could otherwise jump a thin wall, and clamping to the
        // domain could walk it along the edge under a wall that reaches the edge. It is
        // walked in substeps shorter than half the thinnest obstacle, each slid along the
        // face of an obstacle it would enter (docs/architecture.md#crowd-obstacles).
        {
          const Vec2 move = next - x[a];
          const int substeps = std::clamp(static_cast<int>(std::ceil(move.norm() / substep)), 1, 4096);
          Vec2 p = x[a], reached = x[a];
          bool touched = false;
          // One substep from `from` by `d`: clamped to the domain and pushed out of any
          // obstacle it enters; empty when it ends on an obstacle still (a wall that meets
          // the domain's edge: the box put it back) or passes through one on the way (an
          // agent on the domain's edge walking under a wall that meets it, or a push out
          // of the face nearest a corner).
          auto substep_to = [&](const Vec2& from, const Vec2& d) -> std::optional<Vec2> {
            const Vec2 q = move_clear(from, from + d, touched);
            for (const auto& o : spec.obstacles)
              if (o.distance(q) <= 0) return std::nullopt;
            if (!clear_of_obstacles(from, q)) return std::nullopt;
            return q;
          };
          for (int step = 0; step < substeps; ++step) {
            const Vec2 d = move / substeps;
            // The pushed substep, and its parts along x and along y (an agent slides along a
            // wall's face and round its corner that way): the one that gets farthest along d.
            std::optional<Vec2> q;
            for (const Vec2& part : {d, Vec2(d.x(), 0), Vec2(0, d.y())})
              if (const auto c = substep_to(p, part); c && (!q || (*c - p).dot(d) > (*q - p).dot(d))) q = c;
            if (!q || (*q - p).dot(d) <= 0) break;
            p = *q;
            // The step taken is a straight segment from x[a]: it ends at the farthest point
            // of the walk that segment reaches without crossing an obstacle (a walk that
            // slid round a corner would otherwise cut it).
            if (clear_of_obstacles(x[a], p)) reached = p;
          }
          next = reached;
          if (touched) ++contacts[a];
        }
        if (!locator.locate(next)) next = x[a];  // a step off a non-rectangular domain is refused
        moved[a] = next;
      });
      if (avoid) separate(moved, x, active, sep, [&](const Vec2& from, const Vec2& p) {
        bool touched = false;
        return move_clear(from, p, touched);
      }, [&](const Vec2& from, const Vec2& p) {
        // The agent's whole step of this round, from where it stood (`from`) to where the
        // separation put it, must stay clear of the obstacles: `fix` clamps to the domain
        // and pushes out of obstacles, which could otherwise carry it across a wall's end
        // on the domain's edge. One left on an obstacle's boundary is refused too.
        for (const auto& o : spec.obstacles)
          if (o.distance(p) <= 0) return false;
        return clear_of_obstacles(from, p) && !blocked(p);
      });
      x.swap(moved);
      for (size_t a = 0; a < na; ++a)
        if (active[a] && at_goal(x[a])) {
          result.arrived[a] = k;
          active[a] = 0;  // it leaves the crowd through the goal
        }
    }
    for (size_t a = 0; a < na; ++a) result.positions[a].push_back(x[a]);
  }
  tbb::parallel_for(size_t{0}, na, [&](size_t a) {
    // The reference pathline: where the field alone carries the agent's start.
    if (const auto sp = locator.locate(start[a])) {
      PathlineOptions po;
      po.t_start = ts.t0;
      po.t_end = ts.t1;
      po.stop_at_singular_faces = false;
      po.stop_speed = 0;
      const Pathline pl = trace_pathline(bundle, field, *sp, po);
      for (const auto& p : pl.points) result.reference[a].push_back(p.head<2>());
    }
  });
  for (long c : contacts) result.contacts += c;
  return result;
}

// --- Pictures and files -------------------------------------------------------------------

Image draw_crowd(const TangentBundle& bundle, const CrowdSpec& spec, const CrowdResult& result, int k, int size) {
  const detail::PlanarView view = detail::PlanarView::fit(bundle.mesh(), size);
  Image image(view.width, view.height);
  std::fill(image.pixels.begin(), image.pixels.end(), 0x00FFFFFFu);
  cairo_surface_t* surface = cairo_image_surface_create_for_data(
      reinterpret_cast<unsigned char*>(image.pixels.data()), CAIRO_FORMAT_RGB24, image.width, image.height,
      image.width * 4);
  cairo_t* cr = cairo_create(surface);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  auto shape_path = [&](const CrowdShape& s) {
    cairo_new_path(cr);
    if (s.kind == CrowdShape::Kind::circle) {
      const Vec2 c = view.to_pixel(s.center);
      cairo_save(cr);
      cairo_translate(cr, c.x(), c.y());
      cairo_scale(cr, s.radius * view.sx(), s.radius * view.sy());
      cairo_arc(cr, 0, 0, 1, 0, 2 * kPi);
      cairo_restore(cr);
    } else {
      const Vec2 a = view.to_pixel(Vec2(s.min.x(), s.max.y())), b = view.to_pixel(Vec2(s.max.x(), s.min.y()));
      cairo_rectangle(cr, a.x(), a.y(), b.x() - a.x(), b.y() - a.y());
    }
  };
  for (const auto& g : spec.goals) {
    shape_path(g);
    cairo_set_source_rgb(cr, 0.78, 0.92, 0.74);
    cairo_fill(cr);
  }
  for (const auto& o : spec.obstacles) {
    shape_path(o);
    cairo_set_source_rgb(cr, 0.55, 0.55, 0.58);
    cairo_fill(cr);
  }
  const double lw = std::max(1.0, size / 500.0);
  auto polyline = [&](const std::vector<Vec2>& pts, size_t n) {
    cairo_new_path(cr);
    for (size_t q = 0; q < std::min(n, pts.size()); ++q) {
      const Vec2 p = view.to_pixel(pts[q]);
      if (q == 0) cairo_move_to(cr, p.x(), p.y());
      else cairo_line_to(cr, p.x(), p.y());
    }
    cairo_stroke(cr);
  };
  // Reference pathlines (cyan) in full, the agents' paths so far (brown), the agents.
  cairo_set_line_width(cr, lw);
  cairo_set_source_rgb(cr, 0.0, 0.78, 0.86);
  for (const auto& r : result.reference) polyline(r, r.size());
  cairo_set_line_width(cr, 1.3 * lw);
  cairo_set_source_rgb(cr, 0.6, 0.36, 0.14);
  for (const auto& p : result.positions) polyline(p, static_cast<size_t>(k) + 1);
  for (size_t a = 0; a < result.positions.size(); ++a) {
    const auto& p = result.positions[a];
    if (p.empty()) continue;
    const Vec2 c = view.to_pixel(p[std::min(static_cast<size_t>(k), p.size() - 1)]);
    cairo_new_path(cr);
    cairo_arc(cr, c.x(), c.y(), 2.5 * lw, 0, 2 * kPi);
    const bool arrived = result.arrived[a] >= 0 && result.arrived[a] <= k;
    if (arrived) cairo_set_source_rgb(cr, 0.15, 0.5, 0.15);
    else cairo_set_source_rgb(cr, 0.35, 0.15, 0.05);
    cairo_fill(cr);
  }
  cairo_destroy(cr);
  cairo_surface_flush(surface);
  cairo_surface_destroy(surface);
  return image;
}

void write_crowd_csv(const std::string& path, const CrowdResult& result) {
  std::string text = "agent,frame,t,x,y,arrived\n";
  for (size_t a = 0; a < result.positions.size(); ++a)
    for (size_t k = 0; k < result.positions[a].size(); ++k) {
      const Vec2& p = result.positions[a][k];
      const bool arrived = result.arrived[a] >= 0 && static_cast<size_t>(result.arrived[a]) <= k;
      text += fmt::format("{},{},{:.17g},{:.17g},{:.17g},{}\n", a, k, result.times[k], p.x(), p.y(), arrived ? 1 : 0);
    }
  write_file_atomically(path, text);
}

AnimationReport write_crowd_animation(const TangentBundle& bundle, const Field& field, const CrowdSpec& spec,
                                      const CrowdAnimationOptions& options, CrowdResult* out_result) {
  const auto start = std::chrono::steady_clock::now();
  check_spec(options.size >= 16 && options.size <= 16384, fmt::format("size {} is outside [16, 16384]", options.size));
  if (options.frames_dir.empty() && options.video.empty() && options.csv.empty())
    throw Error("crowd: give a folder for the PNG frames, an MP4 file or a CSV file to write");
  CrowdResult result = simulate_crowd(bundle, field, spec, options.frames);
  AnimationReport report;
  const int total = static_cast<int>(result.times.size());
  // The CSV first: if it cannot be written, no frames or video appear either.
  if (!options.csv.empty()) write_crowd_csv(options.csv, result);
  if (!options.frames_dir.empty() || !options.video.empty()) {
    const Image first = draw_crowd(bundle, spec, result, 0, options.size);
    FrameOutput out(options.frames_dir, options.video, first.width, first.height, options.fps);
    for (int k = 0; k < total; ++k) {
      out.add(k == 0 ? first : draw_crowd(bundle, spec, result, k, options.size));
      if (options.progress) options.progress(k + 1, total);
    }
    report.files = out.finish();
    report.width = first.width;
    report.height = first.height;
  }
  if (!options.csv.empty()) report.files.push_back(options.csv);
  report.frames = total;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (out_result) *out_result = std::move(result);
  return report;
}

}  // namespace tvf
