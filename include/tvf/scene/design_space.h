#pragma once
// The domain a design lives on, built once from a scene: the mesh (grid, file or
// primitive), its tangent bundle and its log map. Not movable: the bundle and log map
// refer to the mesh. The log map (three sparse factorizations on a surface) is built on
// its first use, so a domain that only carries a field read from a file (rendering,
// analysis) does not pay for it.
#include "tvf/scene/scene.h"
#include "tvf/field/point_locator.h"
#include "tvf/mesh/log_map.h"
#include "tvf/mesh/mesh_validate.h"
#include "tvf/mesh/tangent_bundle.h"

#include <cstdint>
#include <memory>
#include <mutex>

namespace tvf {

class DesignSpace {
public:
  explicit DesignSpace(Mesh mesh);
  DesignSpace(const DesignSpace&) = delete;
  DesignSpace& operator=(const DesignSpace&) = delete;

  const Mesh& mesh() const { return mesh_; }
  const TangentBundle& bundle() const { return bundle_; }
  // Built on first use (thread-safe).
  const LogMap& log_map() const;
  bool planar() const { return bundle_.is_flat(); }
  // Length unit of the falloff: the bounding-box diagonal (DESIGN §4).
  double diameter() const { return diameter_; }
  // The point of the domain closest to x (x itself, located in a face, on planar grids).
  SurfacePoint locate(const Vec3& x) const;
  const PointLocator& locator() const { return locator_; }
  // The Gaussian curvature within edge-path distance `radius` of the domain's point
  // nearest x: the sum of the angle defects of the vertices reached (edge_path_distances
  // from that point's face corners). 0 on a plane; a whole cap (the end of a tail, a finger) holds
  // 2π, and over π the disk closes round: its circles stop growing.
  double curvature_within(const Vec3& x, double radius) const;

  MeshRepairReport repairs;  // what loading the mesh file repaired, if anything

private:
  Mesh mesh_;
  TangentBundle bundle_;
  mutable std::once_flag log_map_once_;
  mutable std::unique_ptr<LogMap> log_map_;
  PointLocator locator_;
  double diameter_;
};

// Bytes a generated field needs in memory (double complex values plus float32 export).
std::uint64_t field_memory_bytes(int frames, long long vertices);
// Throws tvf::Error naming the scene and "time.frames" when the field of `scene` on
// `vertices` vertices would need more than 80 % of this machine's memory.
void check_field_memory(const Scene& scene, long long vertices);

// Builds the domain of a scene. Mesh files are resolved relative to the scene file;
// errors name the scene and "domain.mesh" or the mesh file.
std::unique_ptr<DesignSpace> make_design_space(const Scene& scene);

}  // namespace tvf
