#pragma once
// Closest points on a triangle mesh through an AABB tree (CGAL's): O(log |F|) per query
// after one O(|F| log |F|) build, where closest_point() (field_sampler.h) scans every
// face. Placing elements, key-frame streamlines and integration steps ask this many
// times per frame. Queries are thread-safe; the mesh must outlive the locator.
#include "tvf/field/field_sampler.h"
#include "tvf/mesh/mesh.h"

#include <memory>

namespace tvf {

class PointLocator {
public:
  explicit PointLocator(const Mesh& mesh);
  ~PointLocator();
  PointLocator(const PointLocator&) = delete;
  PointLocator& operator=(const PointLocator&) = delete;

  // The point of the mesh closest to x: its face and barycentric coordinates there.
  SurfacePoint closest(const Vec3& x) const;

private:
  struct Impl;
  const Mesh& mesh_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tvf
