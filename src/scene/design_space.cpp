#include "tvf/scene/design_space.h"

#include "tvf/core/error.h"
#include "tvf/field/field_sampler.h"
#include "tvf/mesh/edge_paths.h"
#include "tvf/mesh/grid.h"
#include "tvf/mesh/mesh_io.h"
#include "tvf/mesh/primitives.h"

#include <fmt/format.h>

#include <array>
#include <filesystem>
#include <unistd.h>

namespace tvf {

std::uint64_t field_memory_bytes(int frames, long long vertices) {
  // 16 bytes per complex double in memory, 12 per float32 world vector when exporting.
  return static_cast<std::uint64_t>(frames) * static_cast<std::uint64_t>(vertices) * 28u;
}

namespace {

std::uint64_t physical_memory_bytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES);
  const long page = ::sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page)
                               : std::uint64_t{1} << 34;
}

}  // namespace

void check_field_memory(const Scene& scene, long long vertices) {
  const int frames = scene.time.frames;
  const std::uint64_t need = field_memory_bytes(frames, vertices);
  const std::uint64_t have = physical_memory_bytes();
  if (need > have / 10 * 8)
    throw_input_error(scene.label(), "time.frames",
                      fmt::format("{} frames × {} vertices need {:.1f} GiB, more than 80 % of the {:.1f} GiB "
                                  "of memory this machine has",
                                  frames, vertices, static_cast<double>(need) / (1u << 30),
                                  static_cast<double>(have) / (1u << 30)));
}

DesignSpace::DesignSpace(Mesh mesh)
    : mesh_(std::move(mesh)), bundle_(mesh_), locator_(mesh_), diameter_(mesh_.diameter()) {}

const LogMap& DesignSpace::log_map() const {
  std::call_once(log_map_once_, [this] { log_map_ = std::make_unique<LogMap>(bundle_); });
  return *log_map_;
}

SurfacePoint DesignSpace::locate(const Vec3& x) const { return locator_.closest(x); }

double DesignSpace::curvature_within(const Vec3& x, double radius) const {
  if (planar()) return 0;
  const SurfacePoint p = locate(x);
  const Vec3 at = surface_position(mesh_, p);
  const Face& f = mesh_.face(p.face);
  const std::array<EdgePathSeed, 3> seeds{{{f[0], (mesh_.position(f[0]) - at).norm()},
                                           {f[1], (mesh_.position(f[1]) - at).norm()},
                                           {f[2], (mesh_.position(f[2]) - at).norm()}}};
  double total = 0;
  edge_path_distances(mesh_, seeds, radius, [&](int v, double) {
    total += bundle_.angle_defect(v);
    return true;
  });
  return total;
}

std::unique_ptr<DesignSpace> make_design_space(const Scene& scene) {
  const Domain& d = scene.domain;
  // Fields that could not fit are refused before the domain is built (a huge grid takes
  // seconds to build); meshes are checked once their size is known.
  if (d.grid) {
    check_field_memory(scene, static_cast<long long>(d.grid->nx) * d.grid->ny);
    return std::make_unique<DesignSpace>(make_grid(*d.grid, scene.label() + ": domain.grid"));
  }
  if (d.sphere)
    return std::make_unique<DesignSpace>(make_icosphere(d.sphere->subdivisions, d.sphere->radius));
  if (d.torus)
    return std::make_unique<DesignSpace>(make_torus(d.torus->nu, d.torus->nv,
                                                    d.torus->major_radius, d.torus->minor_radius));
  if (!d.mesh.empty()) {
    const std::string path = scene.resolved_mesh_path();
    // The error_code form: a name the file system refuses (longer than 255 bytes, say) is
    // an input error, not a std::filesystem exception.
    std::error_code ec;
    if (!std::filesystem::exists(std::filesystem::status(path, ec)))
      throw_input_error(scene.label(), "domain.mesh",
                        ec && ec != std::errc::no_such_file_or_directory
                            ? fmt::format("the mesh file '{:.200}' cannot be used: {}", path, ec.message())
                            : fmt::format("the mesh file '{}' does not exist", path));
    LoadedMesh loaded = load_mesh(path);
    check_field_memory(scene, loaded.mesh.num_vertices());
    auto space = std::make_unique<DesignSpace>(std::move(loaded.mesh));
    space->repairs = loaded.repairs;
    return space;
  }
  throw_input_error(scene.label(), "domain", "no domain is given (grid, mesh, sphere or torus)");
}

}  // namespace tvf
