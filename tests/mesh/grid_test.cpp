#include "tvf/mesh/grid.h"

#include "tvf/core/error.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <limits>
#include <new>
#include <string>

// The largest single allocation made while `tracking` is on, so that a test can show
// that a refused grid size never reaches the allocator. The replacement operators
// forward to malloc/free (the array and sized forms route here by default).
namespace {
std::atomic<bool> tracking{false};
std::atomic<std::size_t> largest_allocation{0};
}  // namespace

void* operator new(std::size_t size) {
  if (tracking.load(std::memory_order_relaxed)) {
    std::size_t seen = largest_allocation.load(std::memory_order_relaxed);
    while (size > seen && !largest_allocation.compare_exchange_weak(seen, size)) {
    }
  }
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
// Not inlined: GCC 12 would otherwise pair an inlined `new` with this `free` and warn
// (-Wmismatched-new-delete), though both sides are this file's malloc/free.
[[gnu::noinline]] void operator delete(void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace tvf {
namespace {

// Message of the tvf::Error thrown by make_grid, or "" when none (test failure).
std::string grid_error(const GridSpec& spec, const std::string& where = "scene.json: domain.grid") {
  try {
    make_grid(spec, where);
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no tvf::Error for a " << spec.nx << " × " << spec.ny << " grid";
  return "";
}

TEST(Grid, VertexOrderAndPositionsAreExact) {
  const GridSpec spec{7, 5, {-1.0, -0.5}, {2.0, 1.0}};
  const Mesh m = make_grid(spec);
  ASSERT_EQ(m.num_vertices(), 35);
  for (int iy = 0; iy < spec.ny; ++iy) {
    for (int ix = 0; ix < spec.nx; ++ix) {
      const Vec3& p = m.position(iy * spec.nx + ix);
      // The formula of DESIGN §11, evaluated the same way: bit-identical.
      EXPECT_EQ(p.x(), -1.0 + (static_cast<double>(ix) / 6.0) * 3.0);
      EXPECT_EQ(p.y(), -0.5 + (static_cast<double>(iy) / 4.0) * 1.5);
      EXPECT_EQ(p.z(), 0.0);
      EXPECT_FALSE(std::signbit(p.z()));
    }
  }
  EXPECT_EQ(m.position(0), Vec3(-1.0, -0.5, 0.0));
  EXPECT_EQ(m.position(34), Vec3(2.0, 1.0, 0.0));
  EXPECT_EQ(m.position(6), Vec3(2.0, -0.5, 0.0));
  EXPECT_EQ(m.position(28), Vec3(-1.0, 1.0, 0.0));
  EXPECT_TRUE(m.is_planar_xy());
  EXPECT_EQ(m.source(), "grid");
  EXPECT_EQ(m.bbox_min(), Vec3(-1.0, -0.5, 0.0));
  EXPECT_EQ(m.bbox_max(), Vec3(2.0, 1.0, 0.0));
}

TEST(Grid, FacesSplitAlongTheRisingDiagonalCounterClockwise) {
  const GridSpec spec{4, 3, {0.0, 0.0}, {3.0, 2.0}};
  const Mesh m = make_grid(spec);
  ASSERT_EQ(m.num_faces(), 2 * 3 * 2);
  for (int iy = 0; iy + 1 < spec.ny; ++iy) {
    for (int ix = 0; ix + 1 < spec.nx; ++ix) {
      const int cell = iy * (spec.nx - 1) + ix;
      const int v00 = iy * spec.nx + ix;
      const int v10 = v00 + 1, v01 = v00 + spec.nx, v11 = v01 + 1;
      EXPECT_EQ(m.face(2 * cell), (Face{v00, v10, v11}));
      EXPECT_EQ(m.face(2 * cell + 1), (Face{v00, v11, v01}));
    }
  }
  for (int f = 0; f < m.num_faces(); ++f) {
    EXPECT_EQ(m.face_normal(f), Vec3(0, 0, 1)) << "face " << f;
    EXPECT_EQ(m.face_area(f), 0.5);
  }
}

TEST(Grid, CountsEulerCharacteristicAndBoundary) {
  for (const auto& [nx, ny] :
       {std::pair{2, 2}, std::pair{2, 9}, std::pair{17, 13}, std::pair{65, 65}}) {
    SCOPED_TRACE(::testing::Message() << nx << " × " << ny);
    const Mesh m = make_grid(GridSpec{nx, ny, {-1, -1}, {1, 1}});
    EXPECT_EQ(m.num_vertices(), nx * ny);
    EXPECT_EQ(m.num_faces(), 2 * (nx - 1) * (ny - 1));
    EXPECT_EQ(m.num_edges(), (nx - 1) * ny + nx * (ny - 1) + (nx - 1) * (ny - 1));
    EXPECT_EQ(m.euler_characteristic(), 1);
    EXPECT_FALSE(m.is_closed());
    EXPECT_EQ(m.num_boundary_edges(), 2 * (nx - 1) + 2 * (ny - 1));
    int boundary = 0;
    for (int iy = 0; iy < ny; ++iy) {
      for (int ix = 0; ix < nx; ++ix) {
        const bool expected = ix == 0 || iy == 0 || ix == nx - 1 || iy == ny - 1;
        EXPECT_EQ(m.is_boundary_vertex(iy * nx + ix), expected) << ix << ", " << iy;
        boundary += expected ? 1 : 0;
      }
    }
    EXPECT_EQ(boundary, 2 * (nx + ny) - 4);
  }
}

TEST(Grid, DefaultSpecIsThePapersGrid) {
  const Mesh m = make_grid(GridSpec{});
  EXPECT_EQ(m.num_vertices(), 65 * 65);
  EXPECT_EQ(m.position(0), Vec3(-1, -1, 0));
  EXPECT_EQ(m.position(65 * 65 - 1), Vec3(1, 1, 0));
}

TEST(Grid, RejectsSizesBelowTwo) {
  for (const auto& [nx, ny] :
       {std::pair{1, 5}, std::pair{5, 1}, std::pair{0, 0}, std::pair{-3, 4}}) {
    const std::string msg = grid_error(GridSpec{nx, ny, {-1, -1}, {1, 1}});
    EXPECT_EQ(msg.rfind("scene.json: domain.grid: ", 0), 0u) << msg;
    EXPECT_NE(msg.find(std::to_string(nx) + " × " + std::to_string(ny)), std::string::npos) << msg;
    EXPECT_NE(msg.find("at least 2 × 2"), std::string::npos) << msg;
  }
}

TEST(Grid, RejectsBadBoxes) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // Empty or inverted on either axis.
  for (const auto& [lo, hi] :
       {std::pair{Vec2(0, 0), Vec2(0, 1)}, std::pair{Vec2(0, 0), Vec2(1, 0)},
        std::pair{Vec2(1, 0), Vec2(0, 1)}, std::pair{Vec2(0, 2), Vec2(1, 1)}}) {
    const std::string msg = grid_error(GridSpec{3, 3, lo, hi});
    EXPECT_EQ(msg.rfind("scene.json: domain.grid: ", 0), 0u) << msg;
    EXPECT_NE(msg.find("empty or inverted"), std::string::npos) << msg;
  }
  for (const auto& [lo, hi] :
       {std::pair{Vec2(nan, 0), Vec2(1, 1)}, std::pair{Vec2(0, 0), Vec2(1, inf)},
        std::pair{Vec2(-inf, 0), Vec2(1, 1)}}) {
    const std::string msg = grid_error(GridSpec{3, 3, lo, hi});
    EXPECT_NE(msg.find("non-finite"), std::string::npos) << msg;
  }
  const double big = std::numeric_limits<double>::max();
  EXPECT_NE(grid_error(GridSpec{3, 3, {-big, 0}, {big, 1}}).find("too large"), std::string::npos);
  // Issue 17: [-1, 1e200] × [-1, 1] reached the planar transport check (NaN frames) from
  // the library (the scene reader refuses it first); 1e15 is the limit, as for scenes.
  const std::string msg = grid_error(GridSpec{3, 3, {-1, -1}, {1e200, 1}});
  EXPECT_NE(msg.find("magnitude above 1e+15"), std::string::npos) << msg;
  EXPECT_NO_THROW(make_grid(GridSpec{3, 3, {-1e15, -1e15}, {1e15, 1e15}}));
}

TEST(Grid, RejectsTooManyVerticesWithoutAllocating) {
  // Just over the limit, a product that overflows 32 bits, and one that overflows to
  // exactly 1 in 32-bit arithmetic (INT_MAX² ≡ 1 mod 2³²).
  const int int_max = std::numeric_limits<int>::max();
  const long long over = kMaxGridVertices + 1;
  for (const auto& [nx, ny] : {std::pair{10'000, static_cast<int>(over / 10'000 + 1)},
                               std::pair{46'341, 46'341}, std::pair{int_max, int_max}}) {
    largest_allocation = 0;
    tracking = true;
    const std::string msg = grid_error(GridSpec{nx, ny, {-1, -1}, {1, 1}}, "g.json");
    tracking = false;
    EXPECT_EQ(msg.rfind("g.json: ", 0), 0u) << msg;
    EXPECT_NE(msg.find(std::to_string(static_cast<long long>(nx) * ny)), std::string::npos) << msg;
    EXPECT_NE(msg.find(std::to_string(kMaxGridVertices)), std::string::npos) << msg;
    EXPECT_LT(largest_allocation.load(), 1u << 16) << "a refused grid allocated memory";
  }
  // The tracker does see the arrays of a grid that is accepted.
  largest_allocation = 0;
  tracking = true;
  const Mesh m = make_grid(GridSpec{100, 100, {-1, -1}, {1, 1}});
  tracking = false;
  EXPECT_GE(largest_allocation.load(), 100u * 100u * sizeof(Vec3));
}

TEST(Grid, WhereDefaultsToGrid) {
  try {
    make_grid(GridSpec{1, 1, {0, 0}, {1, 1}});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("grid: ", 0), 0u) << e.what();
  }
}

}  // namespace
}  // namespace tvf
