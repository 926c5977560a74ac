#pragma once
// The flow map's fast path on planar regular grids (flow_map.h; internal to the integrate
// module). On a grid made by make_grid (grid.h: vertex iy·nx + ix, cells split along the
// (ix, iy)–(ix+1, iy+1) diagonal, tangent bases world x and y) the surface walk is not
// needed: a point is located by dividing by the spacing, the field is interpolated
// barycentrically in the cell's triangle exactly as FieldSampler::in_face does, and the
// boundary is the grid's box. The same RK4 steps, stages and boundary rules as the walk
// (a displacement that meets a wall slides along it when its outward part is rounding,
// under 1e-6 of its length, and leaves the domain otherwise), so both paths agree to
// rounding; only the cost differs (tens of nanoseconds per sample instead of a walk).
#include "tvf/field/field.h"
#include "tvf/field/field_sampler.h"
#include "tvf/mesh/tangent_bundle.h"

#include <array>
#include <optional>

namespace tvf::detail {

struct GridLayout {
  int nx = 0, ny = 0;
  double x0 = 0.0, y0 = 0.0;  // the box's lower corner
  double hx = 0.0, hy = 0.0;  // spacing
  double x1() const { return x0 + hx * (nx - 1); }
  double y1() const { return y0 + hy * (ny - 1); }
};

// The grid the bundle's mesh is, when it is exactly one made by make_grid (positions to
// 1e-9 of the spacing, the triangulation, world-aligned planar frames); nullopt otherwise.
std::optional<GridLayout> detect_grid(const TangentBundle& bundle);

class GridFlow {
public:
  GridFlow(const GridLayout& grid, const Field& field)
      : g_(grid), field_(field), inv_hx_(1.0 / grid.hx), inv_hy_(1.0 / grid.hy) {}

  struct Move {
    Vec2 end;
    bool left = false;  // the displacement pointed out of the box at a wall
  };
  // The particle at p moved by d, sliding along the walls (see the header comment).
  Move move(const Vec2& p, const Vec2& d) const;
  // The field at p at the time located as (frame j, weight w of frame j + 1).
  Vec2 velocity(const Vec2& p, int j, double w) const;
  // RK4 from p through the knots (the same steps as FlowMap); `left` and `t_left` as in
  // FlowMapResult, p the end (or where it left).
  bool advect(Vec2& p, const std::vector<double>& knots, double dt, double& t_left) const;

  SurfacePoint to_surface(const Vec2& p) const;
  // The corners (vertex indices) of the triangle holding p and their weights there.
  void corners(const Vec2& p, std::array<int, 3>& v, Vec3& w) const;
  const GridLayout& layout() const { return g_; }

private:
  // Cell and fractions of p (clamped into the box).
  void locate(const Vec2& p, int& ix, int& iy, double& fx, double& fy) const;

  GridLayout g_;
  const Field& field_;
  double inv_hx_, inv_hy_;
};

}  // namespace tvf::detail
