#include "tvf/field/world_vectors.h"

#include "tvf/core/error.h"

#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>

namespace tvf {

namespace {

void frames_to_world(const TangentBundle& bundle, const Field& field, int first, int last,
                     float* out) {
  const int nv = field.num_vertices();
  TVF_CHECK(nv == bundle.mesh().num_vertices(), "field has {} vertices, mesh has {}", nv,
            bundle.mesh().num_vertices());
  // Frames × vertex blocks, so that a few frames on a large mesh still use every core.
  tbb::parallel_for(tbb::blocked_range2d<int>(first, last, 1, 0, nv, 4096),
                    [&](const tbb::blocked_range2d<int>& r) {
                      for (int j = r.rows().begin(); j < r.rows().end(); ++j) {
                        const auto values = field.frame(j);
                        float* row = out + static_cast<size_t>(j - first) * static_cast<size_t>(nv) * 3;
                        for (int v = r.cols().begin(); v < r.cols().end(); ++v) {
                          const Vec3 w = bundle.vertex_to_world(v, values[static_cast<size_t>(v)]);
                          float* o = row + 3 * static_cast<size_t>(v);
                          o[0] = static_cast<float>(w.x());
                          o[1] = static_cast<float>(w.y());
                          o[2] = static_cast<float>(w.z());
                        }
                      }
                    });
}

}  // namespace

std::vector<float> world_vectors_f32(const TangentBundle& bundle, const Field& field) {
  std::vector<float> out(static_cast<size_t>(field.frames()) *
                         static_cast<size_t>(field.num_vertices()) * 3);
  frames_to_world(bundle, field, 0, field.frames(), out.data());
  return out;
}

std::vector<float> world_vectors_f32(const TangentBundle& bundle, const Field& field, int frame) {
  TVF_CHECK(frame >= 0 && frame < field.frames(), "frame {} of {}", frame, field.frames());
  std::vector<float> out(static_cast<size_t>(field.num_vertices()) * 3);
  frames_to_world(bundle, field, frame, frame + 1, out.data());
  return out;
}

}  // namespace tvf
