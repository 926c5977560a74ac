#include "tvf/synth/terrain.h"

#include "tvf/core/error.h"
#include "tvf/mesh/mesh_io.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

namespace tvf {

Mesh height_field_mesh(std::span<const float> height, int w, int h, const Vec2& lo, const Vec2& hi, int resolution,
                       double z_scale) {
  TVF_CHECK(height.size() == static_cast<size_t>(w) * static_cast<size_t>(h), "height grid {}×{} with {} values", w, h,
            height.size());
  const Vec2 ext = hi - lo;
  const double step = std::max(ext.x(), ext.y()) / std::max(1, resolution - 1);
  const int nx = std::max(2, static_cast<int>(std::lround(ext.x() / step)) + 1);
  const int ny = std::max(2, static_cast<int>(std::lround(ext.y() / step)) + 1);
  auto sample = [&](double px, double py) {  // pixel-index coordinates, clamped bilinear
    px = std::clamp(px, 0.0, w - 1.0);
    py = std::clamp(py, 0.0, h - 1.0);
    const int x0 = std::min(static_cast<int>(px), w - 1), y0 = std::min(static_cast<int>(py), h - 1);
    const int x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
    const double fx = px - x0, fy = py - y0;
    auto at = [&](int x, int y) { return static_cast<double>(height[static_cast<size_t>(y) * static_cast<size_t>(w) + static_cast<size_t>(x)]); };
    return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x1, y0)) + fy * ((1 - fx) * at(x0, y1) + fx * at(x1, y1));
  };
  std::vector<Vec3> positions;
  positions.reserve(static_cast<size_t>(nx) * static_cast<size_t>(ny));
  for (int iy = 0; iy < ny; ++iy)
    for (int ix = 0; ix < nx; ++ix) {
      const double x = lo.x() + ext.x() * ix / (nx - 1), y = lo.y() + ext.y() * iy / (ny - 1);
      const double px = (x - lo.x()) / ext.x() * w - 0.5, py = (hi.y() - y) / ext.y() * h - 0.5;
      positions.emplace_back(x, y, sample(px, py) * z_scale);
    }
  std::vector<Face> faces;
  faces.reserve(2 * static_cast<size_t>(nx - 1) * static_cast<size_t>(ny - 1));
  for (int iy = 0; iy + 1 < ny; ++iy)
    for (int ix = 0; ix + 1 < nx; ++ix) {
      const int a = iy * nx + ix, b = a + 1, c = a + nx, d = c + 1;
      faces.push_back({a, b, d});
      faces.push_back({a, d, c});
    }
  return Mesh(std::move(positions), std::move(faces), "terrain grid");
}

Mesh displace_along_normals(const TangentBundle& bundle, std::span<const float> height, double amount) {
  const Mesh& mesh = bundle.mesh();
  TVF_CHECK(height.size() == static_cast<size_t>(mesh.num_vertices()), "{} heights for {} vertices", height.size(),
            mesh.num_vertices());
  std::vector<Vec3> positions(mesh.positions());
  for (size_t v = 0; v < positions.size(); ++v)
    positions[v] += (static_cast<double>(height[v]) - 0.5) * amount * bundle.vertex_normal(static_cast<int>(v));
  return Mesh(std::move(positions), mesh.faces(), mesh.source());
}

void write_colored_ply(const std::string& path, const Mesh& mesh, std::span<const Vec3> colours) {
  TVF_CHECK(colours.size() == static_cast<size_t>(mesh.num_vertices()), "{} colours for {} vertices", colours.size(),
            mesh.num_vertices());
  std::ostringstream out;
  out << "ply\nformat binary_little_endian 1.0\ncomment written by tvf\n"
      << "element vertex " << mesh.num_vertices() << "\nproperty float x\nproperty float y\nproperty float z\n"
      << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
      << "element face " << mesh.num_faces() << "\nproperty list uchar int vertex_indices\nend_header\n";
  std::string bytes = out.str();
  auto put = [&](const void* p, size_t n) { bytes.append(static_cast<const char*>(p), n); };
  static_assert(sizeof(float) == 4 && sizeof(int) == 4);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Vec3& p = mesh.position(v);
    const float xyz[3] = {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())};
    put(xyz, sizeof xyz);  // the project's machines are little-endian (x86-64, arm64)
    unsigned char c[3];
    for (int k = 0; k < 3; ++k)
      c[k] = static_cast<unsigned char>(std::lround(std::clamp(colours[static_cast<size_t>(v)][k], 0.0, 1.0) * 255));
    put(c, 3);
  }
  for (const Face& f : mesh.faces()) {
    const unsigned char n = 3;
    put(&n, 1);
    put(f.data(), 3 * sizeof(int));
  }
  write_file_atomically(path, bytes);
}

Vec3 terrain_colour(double h) {
  h = std::clamp(h, 0.0, 1.0);
  const Vec3 low(0.30, 0.36, 0.20), mid(0.55, 0.47, 0.32), high(0.90, 0.84, 0.70);
  return h < 0.5 ? low + (mid - low) * (2 * h) : mid + (high - mid) * (2 * h - 1);
}

TerrainMeshWriter::TerrainMeshWriter(const std::string& folder, const Mesh& domain, const TerrainMeshOptions& options)
    : folder_(folder), domain_(domain), options_(options) {
  if (options.format != "obj" && options.format != "ply")
    throw Error(fmt::format("terrain mesh format '{}': choose obj or ply", options.format));
  if (options.resolution < 2 || options.resolution > 4096)
    throw Error(fmt::format("terrain mesh resolution {}: must be in [2, 4096]", options.resolution));
  if (!std::isfinite(options.height_scale) || options.height_scale < 0 || options.height_scale > 10)
    throw Error(fmt::format("terrain height scale {}: must be in [0, 10]", options.height_scale));
  stage_ = std::make_unique<OutputStage>(folder);
}

TerrainMeshWriter::~TerrainMeshWriter() = default;

void TerrainMeshWriter::save(const Mesh& mesh, std::span<const float> vertex_heights) {
  const std::string path = stage_->file(fmt::format("frame_{:05d}.{}", count_++, options_.format)).string();
  if (options_.format == "ply") {
    std::vector<Vec3> colours(static_cast<size_t>(mesh.num_vertices()));
    for (size_t v = 0; v < colours.size(); ++v) colours[v] = terrain_colour(vertex_heights[v]);
    write_colored_ply(path, mesh, colours);
  } else {
    save_mesh(mesh, path);
  }
}

void TerrainMeshWriter::add_grid(std::span<const float> height, int w, int h) {
  const Vec2 lo = domain_.bbox_min().head<2>(), hi = domain_.bbox_max().head<2>();
  const double size = std::max(hi.x() - lo.x(), hi.y() - lo.y());
  const Mesh mesh = height_field_mesh(height, w, h, lo, hi, options_.resolution, options_.height_scale * size);
  std::vector<float> heights(static_cast<size_t>(mesh.num_vertices()));
  const double z_scale = options_.height_scale * size;
  for (size_t v = 0; v < heights.size(); ++v)
    heights[v] = z_scale > 0 ? static_cast<float>(mesh.position(static_cast<int>(v)).z() / z_scale) : 0.f;
  save(mesh, heights);
}

void TerrainMeshWriter::add_surface(const TangentBundle& bundle, std::span<const float> height) {
  const Mesh mesh = displace_along_normals(bundle, height, options_.height_scale * bundle.mesh().diameter());
  save(mesh, height);
}

std::vector<std::string> TerrainMeshWriter::finish() {
  std::vector<std::string> files;
  for (const auto& p : stage_->commit()) files.push_back(p.string());
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace tvf
