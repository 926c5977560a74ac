// libtvf_vdb.so: OpenVDB's writer behind a C ABI (vdb/vdb_module.h).
#include "vdb/vdb_module.h"

#include <openvdb/openvdb.h>

#include <cstdio>
#include <exception>
#include <memory>

namespace {

void say(char* error, size_t error_size, const char* what) {
  if (error != nullptr && error_size > 0) std::snprintf(error, error_size, "%s", what);
}

}  // namespace

extern "C" {

__attribute__((visibility("default"))) int tvf_vdb_abi_version(void) { return TVF_VDB_ABI_VERSION; }

__attribute__((visibility("default"))) int tvf_vdb_write_frame(const char* path, int nx, int ny, double x0, double y0,
                                                               double hx, double hy, float time, const float* vectors,
                                                               char* error, size_t error_size) {
  try {
    openvdb::initialize();  // idempotent
    openvdb::math::Transform::Ptr transform;
    if (hx == hy) {
      transform = openvdb::math::Transform::createLinearTransform(hx);
      transform->postTranslate(openvdb::Vec3d(x0, y0, 0.0));
    } else {
      transform = std::make_shared<openvdb::math::Transform>(
          std::make_shared<openvdb::math::ScaleTranslateMap>(openvdb::Vec3d(hx, hy, hx), openvdb::Vec3d(x0, y0, 0.0)));
    }
    auto grid = openvdb::Vec3fGrid::create(openvdb::Vec3f(0.0f));
    grid->setName("v");
    grid->setTransform(transform);
    grid->setVectorType(openvdb::VEC_CONTRAVARIANT_RELATIVE);
    grid->insertMeta("time", openvdb::FloatMetadata(time));
    auto access = grid->getAccessor();
    for (int iy = 0; iy < ny; ++iy)
      for (int ix = 0; ix < nx; ++ix) {
        const float* v = vectors + 3 * (static_cast<size_t>(iy) * static_cast<size_t>(nx) + static_cast<size_t>(ix));
        access.setValueOn(openvdb::Coord(ix, iy, 0), openvdb::Vec3f(v[0], v[1], 0.0f));
      }
    openvdb::io::File out(path);
    out.write({grid});
    out.close();
    return 0;
  } catch (const std::exception& e) {
    say(error, error_size, e.what());
  } catch (...) {
    say(error, error_size, "unknown error");
  }
  return 1;
}

}  // extern "C"
