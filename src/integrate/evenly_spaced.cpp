#include "tvf/integrate/evenly_spaced.h"

#include "tvf/core/error.h"
#include "tvf/integrate/surface_walk.h"

#include <algorithm>
#include <cmath>
#include <deque>

namespace tvf {

namespace {

// Points of the placed lines bucketed in square cells.
class PointGrid {
public:
  PointGrid(const Vec3& lo, const Vec3& hi, double cell) : lo_(lo.head<2>()), cell_(cell) {
    nx_ = std::max(1, static_cast<int>(std::ceil((hi.x() - lo.x()) / cell)) + 1);
    ny_ = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) / cell)) + 1);
    cells_.resize(static_cast<size_t>(nx_) * static_cast<size_t>(ny_));
  }
  void add(const Vec3& x) { cells_[index(cx(x), cy(x))].push_back(x.head<2>()); }
  // True when some stored point is closer than r (r ≤ cell).
  bool near(const Vec3& x, double r) const {
    const int ix = cx(x), iy = cy(x);
    const double r2 = r * r;
    for (int j = std::max(0, iy - 1); j <= std::min(ny_ - 1, iy + 1); ++j)
      for (int i = std::max(0, ix - 1); i <= std::min(nx_ - 1, ix + 1); ++i)
        for (const Vec2& p : cells_[index(i, j)])
          if ((p - x.head<2>()).squaredNorm() < r2) return true;
    return false;
  }

private:
  int cx(const Vec3& x) const { return std::clamp(static_cast<int>((x.x() - lo_.x()) / cell_), 0, nx_ - 1); }
  int cy(const Vec3& x) const { return std::clamp(static_cast<int>((x.y() - lo_.y()) / cell_), 0, ny_ - 1); }
  size_t index(int i, int j) const { return static_cast<size_t>(j) * static_cast<size_t>(nx_) + static_cast<size_t>(i); }
  Vec2 lo_;
  double cell_;
  int nx_ = 1, ny_ = 1;
  std::vector<std::vector<Vec2>> cells_;
};

}  // namespace

std::vector<Streamline> evenly_spaced_streamlines(const TangentBundle& bundle, std::span<const cplx> values,
                                                  const EvenlySpacedOptions& options) {
  const Mesh& mesh = bundle.mesh();
  if (!bundle.is_flat())
    throw_input_error(mesh.source(), "", "evenly spaced streamlines are placed on planar domains only");
  const double sep = options.separation > 0 ? options.separation : 0.03 * mesh.diameter();
  const double test = options.test_ratio * sep;
  const double step = options.step > 0 ? options.step : std::min(0.25 * sep, 0.5 * mesh.mean_edge_length());
  const double min_len = options.min_length > 0 ? options.min_length : 2.0 * sep;
  PointGrid grid(mesh.bbox_min(), mesh.bbox_max(), sep);

  StreamlineOptions so;
  so.step = step;
  so.max_length = mesh.diameter() * 4;
  so.accept = [&](const Vec3& x) { return !grid.near(x, test); };

  std::vector<Streamline> lines;
  std::deque<size_t> queue;
  auto try_seed = [&](const SurfacePoint& p) {
    const Vec3 x = surface_position(mesh, p);
    // (A hair under `sep`, so that a seed placed at exactly `sep` is not lost to rounding.)
    if (grid.near(x, sep * (1 - 1e-9))) return;
    Streamline s = trace_streamline(bundle, values, p, so);
    if (s.points.size() < 2 || s.length() < min_len) return;
    for (const Vec3& q : s.points) grid.add(q);
    queue.push_back(lines.size());
    lines.push_back(std::move(s));
  };
  // First seed: the domain's centre (or the closest point of the domain to it).
  try_seed(closest_point(mesh, 0.5 * (mesh.bbox_min() + mesh.bbox_max())));
  // When the centre is a singularity, seed on a coarse lattice until a line takes.
  for (int k = 0; lines.empty() && k < 64; ++k) {
    const Vec3 lo = mesh.bbox_min(), hi = mesh.bbox_max();
    const Vec3 x(lo.x() + (hi.x() - lo.x()) * ((k % 8) + 0.5) / 8, lo.y() + (hi.y() - lo.y()) * ((k / 8) + 0.5) / 8, 0);
    try_seed(closest_point(mesh, x));
  }
  while (!queue.empty() && lines.size() < options.max_lines) {
    const size_t i = queue.front();
    queue.pop_front();
    // Candidate seeds at `sep` on both sides of every point of line i.
    const std::vector<SurfacePoint> where = lines[i].where;  // copy: lines grows
    for (const SurfacePoint& p : where) {
      const cplx v = interpolate_in_face(bundle, values, p);
      if (std::abs(v) == 0) continue;
      const cplx n = cplx(0, 1) * v / std::abs(v);
      for (const double side : {1.0, -1.0}) {
        const SurfaceWalk w = walk_surface(bundle, p, side * sep * n);
        if (w.hit_boundary) continue;
        try_seed(w.end);
        if (lines.size() >= options.max_lines) break;
      }
    }
  }
  return lines;
}

}  // namespace tvf
