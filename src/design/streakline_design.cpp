#include "tvf/design/streakline_design.h"

#include "tvf/core/error.h"
#include "tvf/field/field_sampler.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace tvf {

StreaklineConstraints::StreaklineConstraints(const DesignSpace& space, const Scene& scene) {
  const Mesh& mesh = space.mesh();
  const TangentBundle& bundle = space.bundle();
  vertices_ = mesh.num_vertices();
  frame_dt_ = scene.time.frames > 1 ? (scene.time.t1 - scene.time.t0) / (scene.time.frames - 1) : 0.0;
  const double h = mesh.mean_edge_length();
  lead_ = 2 * h;
  const double step = 0.25 * h;
  for (const Element& e : scene.elements) {
    const auto* sl = std::get_if<StreaklineElement>(&e);
    if (!sl) continue;
    TVF_CHECK(sl->points.size() >= 2 && sl->from < sl->t, "a streakline needs 2 points and from < t");
    // The polyline on the domain (snapped to a surface).
    std::vector<Vec3> p;
    for (const Vec3& x : sl->points) p.push_back(surface_position(mesh, space.locate(x)));
    Line line;
    line.from = sl->from;
    line.t = sl->t;
    for (size_t i = 0; i + 1 < p.size(); ++i) line.length += (p[i + 1] - p[i]).norm();
    line.speed = line.length / (sl->t - sl->from);
    // The segments (zero-length ones dropped) and the rounding of each corner: the tangent
    // turns from one segment's direction to the next over ±ρ of arc about the corner, ρ =
    // one frame's travel plus an edge length (at most half of either segment), so the dye
    // front never meets a tangent that jumps (a corner switched on at once turned its
    // vertices by up to the corner's angle in one frame).
    struct Segment {
      Vec3 a, b, dir;
      double len, s0;
    };
    std::vector<Segment> segs;
    for (size_t i = 0; i + 1 < p.size(); ++i) {
      const double len = (p[i + 1] - p[i]).norm();
      if (len == 0) continue;
      segs.push_back({p[i], p[i + 1], (p[i + 1] - p[i]) / len, len, segs.empty() ? 0.0 : segs.back().s0 + segs.back().len});
    }
    const double reach = line.speed * frame_dt_ + h;
    auto tangent = [&](size_t i, double s) {
      Vec3 dir = segs[i].dir;
      auto blend = [&](size_t k, double from_start) {  // corner k between segs[k-1] and segs[k]
        const double rho = std::min({reach, 0.5 * segs[k - 1].len, 0.5 * segs[k].len});
        if (rho <= 0 || std::abs(from_start) >= rho) return;
        const double x = (from_start + rho) / (2 * rho), w = x * x * (3 - 2 * x);
        const Vec3 d = (1 - w) * segs[k - 1].dir + w * segs[k].dir;
        if (d.norm() > 1e-9) dir = d.normalized();
      };
      if (i > 0) blend(i, s - segs[i].s0);
      if (i + 1 < segs.size()) blend(i + 1, s - segs[i + 1].s0);
      return dir;
    };
    for (size_t i = 0; i < segs.size(); ++i) {
      const Vec3 a = segs[i].a, b = segs[i].b;
      const double len = segs[i].len, s0 = segs[i].s0;
      const int steps = std::max(1, static_cast<int>(std::ceil(len / step)));
      for (int q = 0; q < steps; ++q) {
        const double u = (q + 0.5) / steps;
        const Vec3 x = a + (b - a) * u;
        Sample sample;
        sample.s = s0 + u * len;
        const Vec3 dir = tangent(i, sample.s);
        const SurfacePoint where = space.locate(x);
        const Vec3 on = surface_position(mesh, where);
        const Face& f = mesh.face(where.face);
        for (int k = 0; k < 3; ++k) {
          const int c = f[static_cast<size_t>(k)];
          sample.corners[k] = c;
          // u·(T − c·y′·n): the tangent, and the pull onto the polyline across it.
          const Vec3 n = bundle.vertex_normal(c).cross(dir);
          const double offset = (mesh.position(c) - on).dot(n);
          const Vec3 w = line.speed * (dir - sl->attach * offset * n);
          sample.value[k] = bundle.world_to_vertex(c, w);
        }
        line.samples.push_back(sample);
      }
    }
    lines_.push_back(std::move(line));
  }
}

namespace {

// How much faster than the dye the constraints let go after t (see constrain).
constexpr double kLetGo = 4.0;

double distance_to_polyline(const Vec3& x, std::span<const Vec3> line) {
  double best = (x - line.front()).norm();
  for (size_t i = 0; i + 1 < line.size(); ++i) {
    const Vec3 a = line[i], b = line[i + 1];
    const double len2 = (b - a).squaredNorm();
    const double u = len2 > 0 ? std::clamp((x - a).dot(b - a) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, (a + u * (b - a) - x).norm());
  }
  return best;
}

}  // namespace

namespace {

// The closest points of segments ab and cd (the clamped least-squares parameters, as in
// Ericson's Real-Time Collision Detection §5.1.9).
std::pair<Vec3, Vec3> closest_points(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const Vec3 d1 = b - a, d2 = d - c, r = a - c;
  const double A = d1.squaredNorm(), E = d2.squaredNorm(), F = d2.dot(r);
  double u = 0, v = 0;
  if (A <= 0 && E <= 0) return {a, c};
  if (A <= 0) {
    v = std::clamp(F / E, 0.0, 1.0);
  } else {
    const double C = d1.dot(r);
    if (E <= 0) {
      u = std::clamp(-C / A, 0.0, 1.0);
    } else {
      const double B = d1.dot(d2), denom = A * E - B * B;
      u = denom > 0 ? std::clamp((B * F - C * E) / denom, 0.0, 1.0) : 0.0;
      v = (B * u + F) / E;
      if (v < 0) {
        v = 0;
        u = std::clamp(-C / A, 0.0, 1.0);
      } else if (v > 1) {
        v = 1;
        u = std::clamp((B - C) / A, 0.0, 1.0);
      }
    }
  }
  return {a + u * d1, c + v * d2};
}

// Whether segments ab and cd, projected onto the plane normal to n, cross or touch; a point
// within tol of the other's line counts as on it.
bool meet_in_plane(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, const Vec3& n, double tol) {
  const Vec3 e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  auto at = [&](const Vec3& x) { return Eigen::Vector2d((x - a).dot(e1), (x - a).dot(e2)); };
  const Eigen::Vector2d A = at(a), B = at(b), C = at(c), D = at(d);
  auto side = [&](const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Eigen::Vector2d& x) {
    const Eigen::Vector2d u = q - p;
    const double len = u.norm();
    if (!(len > 0)) return 0;
    const double o = (u.x() * (x - p).y() - u.y() * (x - p).x()) / len;  // signed distance
    return std::abs(o) <= tol ? 0 : (o > 0 ? 1 : -1);
  };
  auto within = [&](const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Eigen::Vector2d& x) {
    const Eigen::Vector2d u = q - p;
    const double len = u.norm();
    return len > 0 && (x - p).dot(u) >= -tol * len && (x - q).dot(-u) >= -tol * len;
  };
  const int s1 = side(A, B, C), s2 = side(A, B, D), s3 = side(C, D, A), s4 = side(C, D, B);
  if (s1 * s2 < 0 && s3 * s4 < 0) return true;
  return (s1 == 0 && within(A, B, C)) || (s2 == 0 && within(A, B, D)) || (s3 == 0 && within(C, D, A)) ||
         (s4 == 0 && within(C, D, B));
}

}  // namespace

std::optional<std::pair<size_t, size_t>> surface_sketch_crossing(const DesignSpace& space,
                                                                 std::span<const Vec3> points) {
  const Mesh& mesh = space.mesh();
  const double h = mesh.mean_edge_length();
  const double tol = 1e-6 * h;
  // The pieces: ends snapped onto the surface, each with the sketch segment it belongs to
  // and the surface normal at its start.
  struct Piece {
    Vec3 a, b, n;
    size_t segment;
  };
  std::vector<Piece> pieces;
  auto on_surface = [&](const Vec3& x, Vec3& n) {
    const SurfacePoint p = space.locate(x);
    n = mesh.face_normal(p.face);
    return surface_position(mesh, p);
  };
  double length = 0;
  for (size_t i = 0; i + 1 < points.size(); ++i) length += (points[i + 1] - points[i]).norm();
  const double step = std::max(0.25 * h, length / 4000);  // at most ~4000 pieces in all
  // Where a chord leaves the surface (round a corner, off-surface points) several of its
  // points snap to nearly one place: pieces shorter than `join` are joined to the next, or
  // the two pieces either side of them would read as touching.
  const double join = 0.01 * h;
  Vec3 from = Vec3::Zero(), from_n = Vec3::Zero(), last = Vec3::Zero();
  bool started = false;
  for (size_t i = 0; i + 1 < points.size(); ++i) {
    const double len = (points[i + 1] - points[i]).norm();
    if (!(len > 0)) continue;
    const int count = std::max(1, static_cast<int>(std::ceil(len / step)));
    if (!started) from = last = on_surface(points[i], from_n), started = true;
    for (int q = 1; q <= count; ++q) {
      Vec3 n;
      last = on_surface(points[i] + (points[i + 1] - points[i]) * (static_cast<double>(q) / count), n);
      if ((last - from).norm() <= join) continue;
      pieces.push_back({from, last, from_n, i});
      from = last;
      from_n = n;
    }
  }
  if (!pieces.empty()) pieces.back().b = last;  // the sketch's end, however close
  if (pieces.size() < 2) return std::nullopt;
  const bool closed = (points.front() - points.back()).norm() <= tol;
  // Neighbours that fold back: in the plane normal to both pieces' faces the second runs back
  // along the first. (A projection keeps a fold a fold; projecting onto one face's plane
  // would also fold a path that turns round a crease, as round a cube's corner.)
  for (size_t k = 0; k + 1 < pieces.size(); ++k) {
    const Piece& p = pieces[k];
    const Piece& q = pieces[k + 1];
    const Vec3 both = p.n + q.n;
    const Vec3 n = both.norm() > 1e-6 ? Vec3(both.normalized()) : q.n;
    const Vec3 u = (p.b - p.a) - n * n.dot(p.b - p.a), v = (q.b - q.a) - n * n.dot(q.b - q.a);
    if (u.cross(v).norm() <= 1e-9 * u.norm() * v.norm() && u.dot(v) < 0)
      return std::pair{p.segment, q.segment};
  }
  // Pieces that are not neighbours, near each other on the same side of the surface.
  for (size_t k = 0; k + 2 < pieces.size(); ++k)
    for (size_t l = k + 2; l < pieces.size(); ++l) {
      if (closed && k == 0 && l + 1 == pieces.size()) continue;
      const Piece& p = pieces[k];
      const Piece& q = pieces[l];
      if ((p.a - q.a).norm() > 0.5 * h + (p.b - p.a).norm() + (q.b - q.a).norm()) continue;
      const auto [x, y] = closest_points(p.a, p.b, q.a, q.b);
      if ((x - y).norm() > 0.5 * h || p.n.dot(q.n) < 0.5) continue;
      if (meet_in_plane(p.a, p.b, q.a, q.b, (p.n + q.n).normalized(), tol)) return std::pair{p.segment, q.segment};
    }
  return std::nullopt;
}

void check_surface_sketches(const DesignSpace& space, const Scene& scene, const std::string& label) {
  if (space.planar()) return;
  const Mesh& mesh = space.mesh();
  for (size_t i = 0; i < scene.elements.size(); ++i) {
    const auto* sl = std::get_if<StreaklineElement>(&scene.elements[i]);
    if (!sl) continue;
    // As the reader refuses a planar sketch of no length: here once snapped (points far off
    // a convex corner all land on it).
    double length = 0;
    for (size_t k = 0; k + 1 < sl->points.size(); ++k)
      length += (surface_position(mesh, space.locate(sl->points[k + 1])) -
                 surface_position(mesh, space.locate(sl->points[k])))
                    .norm();
    if (!(length > 1e-9 * mesh.mean_edge_length()))
      throw_input_error(label.empty() ? scene.label() : label, fmt::format("elements[{}].points", i),
                        "must have a length > 0 on the surface (its points all land on one point of it)");
    if (const auto crossing = surface_sketch_crossing(space, sl->points))
      throw_input_error(label.empty() ? scene.label() : label, fmt::format("elements[{}].points", i),
                        fmt::format("the sketch crosses or folds back onto itself on the surface (its segments "
                                    "from points[{}] and points[{}]): two parts of the dye cannot be at one point "
                                    "at t; sketch a streakline that does not meet itself",
                                    crossing->first, crossing->second));
  }
}

SketchSelfApproach sketch_self_approach(std::span<const Vec3> points, double h) {
  SketchSelfApproach out;
  double length = 0;
  for (size_t i = 0; i + 1 < points.size(); ++i) length += (points[i + 1] - points[i]).norm();
  if (!(length > 0) || !(h > 0)) return out;
  const double step = std::max(0.25 * h, length / 4000);
  std::vector<Vec3> x;
  std::vector<double> s;
  double s0 = 0;
  for (size_t i = 0; i + 1 < points.size(); ++i) {
    const double len = (points[i + 1] - points[i]).norm();
    const int pieces = std::max(1, static_cast<int>(std::ceil(len / step)));
    for (int q = 0; q < pieces; ++q) {
      x.push_back(points[i] + (points[i + 1] - points[i]) * (static_cast<double>(q) / pieces));
      s.push_back(s0 + len * q / pieces);
    }
    s0 += len;
  }
  x.push_back(points.back());
  s.push_back(length);
  // A closed sketch (its last point on the seed, as the readers take it) is one stretch of
  // curve round its closing point: distances along it are taken round the loop, the
  // shorter way, so the seed and the oldest dye beside it are not two parts that meet.
  const bool closed = (points.front() - points.back()).norm() <= 1e-6 * h;
  for (size_t i = 0; i < x.size(); ++i)
    for (size_t j = i + 1; j < x.size(); ++j) {
      const double along = closed ? std::min(s[j] - s[i], length - (s[j] - s[i])) : s[j] - s[i];
      if (along <= 8 * h) continue;
      const double d = (x[j] - x[i]).norm();
      if (along > 8 * d && d < out.distance) out = {d, along, x[i], x[j]};
    }
  return out;
}

StreaklineMatch compare_streakline(std::span<const Vec3> sketch, std::span<const Vec3> traced) {
  StreaklineMatch m;
  if (sketch.empty() || traced.size() < 2) {
    m.hausdorff = m.mean = m.frechet = std::numeric_limits<double>::infinity();
    return m;
  }
  double sum = 0;
  size_t count = 0;
  auto add = [&](double d) {
    m.hausdorff = std::max(m.hausdorff, d);
    sum += d;
    ++count;
  };
  for (const Vec3& x : traced) add(distance_to_polyline(x, sketch));
  for (size_t i = 0; i + 1 < sketch.size(); ++i)
    for (int q = 0; q < 12; ++q) add(distance_to_polyline(sketch[i] + (sketch[i + 1] - sketch[i]) * (q / 12.0), traced));
  add(distance_to_polyline(sketch.back(), traced));
  m.mean = sum / static_cast<double>(count);
  // The Fréchet distance, the sketch from its seed against the traced dye from its
  // youngest particle (traced is oldest first): both resampled into pieces of at most
  // a 1/kPieces of the longer one's length, and the discrete Fréchet distance of those
  // points (Eiter & Mannila 1994), one row of the table at a time.
  constexpr double kPieces = 2000;
  auto length = [](std::span<const Vec3> line) {
    double l = 0;
    for (size_t i = 0; i + 1 < line.size(); ++i) l += (line[i + 1] - line[i]).norm();
    return l;
  };
  const double step = std::max(length(sketch), length(traced)) / kPieces;
  auto resample = [&](std::span<const Vec3> line, bool reverse) {
    std::vector<Vec3> p(line.begin(), line.end());
    if (reverse) std::reverse(p.begin(), p.end());
    std::vector<Vec3> out{p.front()};
    for (size_t i = 0; i + 1 < p.size(); ++i) {
      const int pieces = step > 0 ? std::max(1, static_cast<int>(std::ceil((p[i + 1] - p[i]).norm() / step))) : 1;
      for (int q = 1; q <= pieces; ++q) out.push_back(p[i] + (p[i + 1] - p[i]) * (static_cast<double>(q) / pieces));
    }
    return out;
  };
  const std::vector<Vec3> a = resample(sketch, false), b = resample(traced, true);
  std::vector<double> row(b.size()), next(b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    for (size_t j = 0; j < b.size(); ++j) {
      const double d = (a[i] - b[j]).norm();
      double reach;
      if (i == 0 && j == 0) reach = d;
      else if (i == 0) reach = next[j - 1];
      else if (j == 0) reach = row[0];
      else reach = std::min({row[j], row[j - 1], next[j - 1]});
      next[j] = std::max(reach, d);
    }
    std::swap(row, next);
  }
  m.frechet = row.back();
  return m;
}

void StreaklineConstraints::constrain(double t, std::span<char> fixed, std::span<cplx> values) const {
  if (lines_.empty()) return;
  TVF_CHECK(fixed.size() == static_cast<size_t>(vertices_) && values.size() == fixed.size(),
            "a frame's constraints have one entry per vertex");
  const double slack = 1e-9 * std::max(frame_dt_, 1e-300);
  std::vector<cplx> sum;
  std::vector<int> count;
  for (const Line& line : lines_) {
    // The frames whose interval reaches into [from, t] (frame_dt_ = 0: only [from, t]).
    if (!(t > line.from - frame_dt_ + slack || t >= line.from)) continue;
    // After t (and the frame that reaches past it), the constraints let go from the seed
    // end at kLetGo·u, so the field relaxes over (t − from)/kLetGo instead of at one frame.
    const double after = t - line.t - frame_dt_;
    const double tail = after > slack ? kLetGo * line.speed * after : -1.0;
    if (tail > line.length) continue;
    const double released = std::clamp(t, line.from, line.t) - line.from;
    const double front = line.speed * (released + frame_dt_) + lead_;
    if (sum.empty()) {
      sum.assign(fixed.size(), cplx(0, 0));
      count.assign(fixed.size(), 0);
    }
    for (const Sample& sample : line.samples) {
      if (sample.s > front) break;
      if (sample.s < tail) continue;
      for (int k = 0; k < 3; ++k) {
        const auto v = static_cast<size_t>(sample.corners[k]);
        sum[v] += sample.value[k];
        ++count[v];
      }
    }
  }
  for (size_t v = 0; v < count.size(); ++v) {
    if (count[v] == 0) continue;
    if (!fixed[v]) values[v] = cplx(0, 0);
    values[v] += sum[v] / static_cast<double>(count[v]);
    fixed[v] = 1;
  }
}

}  // namespace tvf
