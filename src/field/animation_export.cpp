#include "tvf/field/animation_export.h"

#include "tvf/core/atomic_output.h"
#include "tvf/core/error.h"
#include "tvf/field/world_vectors.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <ostream>

#if TVF_HAVE_OPENVDB
#include "vdb/vdb_module.h"

#include <dlfcn.h>

#include <mutex>
#include <string>
#endif

namespace fs = std::filesystem;

namespace tvf {

bool vdb_export_available() { return TVF_HAVE_OPENVDB != 0; }

#if TVF_HAVE_OPENVDB
namespace {

// OpenVDB's writer lives in the module libtvf_vdb.so (vdb/vdb_module.h), opened here on
// the first export: linking OpenVDB into libtvf made every tvf command and every
// `import tvf` load it. Looked for beside the program (tvf), beside the object that holds
// this code (the Python module's _tvf.so, installed with the module beside it), then where
// this build put it (TVF_VDB_MODULE_PATH).
constexpr const char* kVdbModule = "libtvf_vdb.so";

struct VdbModule {
  tvf_vdb_write_frame_fn write = nullptr;
  std::string error;  // why it could not be opened
};

const VdbModule& vdb_module() {
  static VdbModule module;
  static std::once_flag once;
  std::call_once(once, [] {
    std::vector<fs::path> candidates;
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec) candidates.push_back(exe.parent_path() / kVdbModule);
    Dl_info info{};
    if (dladdr(reinterpret_cast<void*>(&vdb_export_available), &info) != 0 && info.dli_fname != nullptr &&
        fs::path(info.dli_fname).is_absolute())
      candidates.push_back(fs::path(info.dli_fname).parent_path() / kVdbModule);
    candidates.emplace_back(TVF_VDB_MODULE_PATH);
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    std::string looked;
    for (const fs::path& c : candidates) {
      if (!looked.empty()) looked += ", ";
      looked += c.string();
      if (!fs::exists(c, ec)) continue;
      void* handle = dlopen(c.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (handle == nullptr) {
        module.error = fmt::format("cannot open the OpenVDB module {}: {}", c.string(), dlerror());
        return;
      }
      const auto version = reinterpret_cast<tvf_vdb_abi_version_fn>(dlsym(handle, "tvf_vdb_abi_version"));
      module.write = reinterpret_cast<tvf_vdb_write_frame_fn>(dlsym(handle, "tvf_vdb_write_frame"));
      if (version == nullptr || module.write == nullptr || version() != TVF_VDB_ABI_VERSION) {
        module.write = nullptr;
        module.error = fmt::format("the OpenVDB module {} is not the one of this tvf (rebuild or reinstall tvf)",
                                   c.string());
      }
      return;  // the module stays loaded for the life of the process
    }
    module.error = fmt::format("the OpenVDB module {} is missing (looked in {}): rebuild or reinstall tvf",
                               kVdbModule, looked);
  });
  return module;
}

}  // namespace
#endif

GridLattice grid_lattice(const Mesh& mesh, const std::string& label) {
  const auto not_grid = [&](const std::string& why) {
    return Error(fmt::format("{}: the domain is not a planar grid ({}): OpenVDB export needs a scene "
                             "with \"domain\": {{\"grid\": ...}} (export surfaces as PLY)",
                             label, why));
  };
  const int nv = mesh.num_vertices();
  if (nv < 4) throw not_grid("fewer than 4 vertices");
  GridLattice g;
  const Vec3& p0 = mesh.position(0);
  g.x0 = p0.x();
  g.y0 = p0.y();
  // nx: the vertices of the first row share vertex 0's y.
  g.nx = 1;
  while (g.nx < nv && mesh.position(g.nx).y() == p0.y()) ++g.nx;
  if (g.nx < 2 || nv % g.nx != 0) throw not_grid("its vertices do not form rows of equal length");
  g.ny = nv / g.nx;
  if (g.ny < 2) throw not_grid("a single row of vertices");
  g.hx = (mesh.position(g.nx - 1).x() - g.x0) / (g.nx - 1);
  g.hy = (mesh.position(nv - 1).y() - g.y0) / (g.ny - 1);
  if (!(g.hx > 0) || !(g.hy > 0)) throw not_grid("its vertices are not ordered row by row along +x, +y");
  const double tol = 1e-6 * std::min(g.hx, g.hy);
  for (int iy = 0; iy < g.ny; ++iy)
    for (int ix = 0; ix < g.nx; ++ix) {
      const Vec3& p = mesh.position(iy * g.nx + ix);
      if (std::abs(p.x() - (g.x0 + ix * g.hx)) > tol || std::abs(p.y() - (g.y0 + iy * g.hy)) > tol ||
          p.z() != 0.0)
        throw not_grid(fmt::format("vertex {} is off the regular lattice", iy * g.nx + ix));
    }
  return g;
}

std::vector<fs::path> write_vdb_sequence(const fs::path& dir, const TangentBundle& bundle, const Field& field,
                                         const std::string& label) {
  const GridLattice g = grid_lattice(bundle.mesh(), label);
#if TVF_HAVE_OPENVDB
  const VdbModule& module = vdb_module();
  if (module.write == nullptr) throw Error(fmt::format("{}: cannot write OpenVDB files: {}", label, module.error));
  OutputStage stage(dir);
  for (int j = 0; j < field.frames(); ++j) {
    const std::vector<float> w = world_vectors_f32(bundle, field, j);
    const fs::path file = stage.file(fmt::format("velocity_{:04d}.vdb", j));
    char error[512] = {};
    if (module.write(file.c_str(), g.nx, g.ny, g.x0, g.y0, g.hx, g.hy, static_cast<float>(field.time().time(j)),
                     w.data(), error, sizeof error) != 0)
      throw Error(fmt::format("{}: cannot write: {}", file.string(), error));
  }
  return stage.commit();
#else
  (void)dir;
  (void)field;
  (void)g;
  throw Error(fmt::format("{}: this tvf was built without OpenVDB: install the Debian package 'libopenvdb-dev' "
                          "(scripts/install-deps.sh) and rebuild",
                          label));
#endif
}

std::vector<fs::path> write_ply_sequence(const fs::path& dir, const TangentBundle& bundle, const Field& field) {
  const Mesh& mesh = bundle.mesh();
  OutputStage stage(dir);
  static_assert(sizeof(float) == 4 && sizeof(std::int32_t) == 4);
  for (int j = 0; j < field.frames(); ++j) {
    const std::vector<float> w = world_vectors_f32(bundle, field, j);
    write_file_atomically(stage.file(fmt::format("velocity_{:04d}.ply", j)), [&](std::ostream& os) {
      os << "ply\nformat binary_little_endian 1.0\n"
         << fmt::format("comment tvf velocity field, frame {}\ncomment t {:.17g}\n", j, field.time().time(j))
         << "element vertex " << mesh.num_vertices() << "\n"
         << "property float x\nproperty float y\nproperty float z\n"
         << "property float vx\nproperty float vy\nproperty float vz\n"
         << "element face " << mesh.num_faces() << "\n"
         << "property list uchar int vertex_indices\nend_header\n";
      std::vector<char> bytes(static_cast<size_t>(mesh.num_vertices()) * 24);
      for (int v = 0; v < mesh.num_vertices(); ++v) {
        const Vec3& p = mesh.position(v);
        const float row[6] = {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()),
                              w[3 * static_cast<size_t>(v)], w[3 * static_cast<size_t>(v) + 1],
                              w[3 * static_cast<size_t>(v) + 2]};
        std::memcpy(bytes.data() + 24 * static_cast<size_t>(v), row, 24);  // x86-64: little-endian
      }
      os.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
      std::vector<char> faces(static_cast<size_t>(mesh.num_faces()) * 13);
      for (int f = 0; f < mesh.num_faces(); ++f) {
        char* o = faces.data() + 13 * static_cast<size_t>(f);
        o[0] = 3;
        const std::int32_t idx[3] = {mesh.face(f)[0], mesh.face(f)[1], mesh.face(f)[2]};
        std::memcpy(o + 1, idx, 12);
      }
      os.write(faces.data(), static_cast<std::streamsize>(faces.size()));
    });
  }
  return stage.commit();
}

}  // namespace tvf
