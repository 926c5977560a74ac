#include "tvf/field/vtk_io.h"

#include "tvf/core/atomic_output.h"
#include "tvf/core/error.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <system_error>

namespace tvf {

namespace fs = std::filesystem;

static_assert(std::endian::native == std::endian::little,
              "vtk_io.cpp writes the host's bytes as LittleEndian appended data");

namespace {

// Writes head + body + tail to `path` through a temporary sibling (complete or absent).
void write_whole_file(const fs::path& path, const std::string& head, const std::string& body,
                      const std::string& tail) {
  write_file_atomically(path, [&](std::ostream& out) {
    out.write(head.data(), static_cast<std::streamsize>(head.size()));
    out.write(body.data(), static_cast<std::streamsize>(body.size()));
    out.write(tail.data(), static_cast<std::streamsize>(tail.size()));
  });
}

std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

// The appended-data section: each array is a UInt64 byte count followed by its bytes.
class Appended {
public:
  // Starts an array of `bytes` bytes and returns its offset (from the byte after '_').
  std::uint64_t begin(std::uint64_t bytes) {
    const auto offset = static_cast<std::uint64_t>(data_.size());
    put(bytes);
    return offset;
  }
  template <class T>
  void put(const T& value) {
    data_.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  std::string& data() { return data_; }

private:
  std::string data_;
};

// The frame-independent part of every .vtu: points and cells.
struct Geometry {
  std::string appended;  // points, connectivity, offsets, types
  std::uint64_t points = 0, connectivity = 0, offsets = 0, types = 0;
  std::uint64_t num_points = 0, num_cells = 0;
};

// The points `points` (vertex indices) of `mesh` and its faces `faces` whose corners are
// renumbered by `local` (vertex → index among `points`); every vertex and face when both
// are empty.
Geometry make_geometry(const Mesh& mesh, const std::vector<int>& points = {}, const std::vector<int>& faces = {},
                       const std::vector<int>& local = {}) {
  Geometry g;
  Appended a;
  const bool whole = points.empty() && faces.empty();
  const auto nv = whole ? static_cast<std::uint64_t>(mesh.num_vertices()) : points.size();
  const auto nf = whole ? static_cast<std::uint64_t>(mesh.num_faces()) : faces.size();
  g.num_points = nv;
  g.num_cells = nf;
  g.points = a.begin(nv * 3 * sizeof(double));
  for (std::uint64_t i = 0; i < nv; ++i) {
    const Vec3& p = mesh.position(whole ? static_cast<int>(i) : points[i]);
    for (int k = 0; k < 3; ++k) a.put(p[k]);
  }
  g.connectivity = a.begin(nf * 3 * sizeof(std::int32_t));
  for (std::uint64_t i = 0; i < nf; ++i)
    for (int v : mesh.face(whole ? static_cast<int>(i) : faces[i]))
      a.put(static_cast<std::int32_t>(whole ? v : local[static_cast<size_t>(v)]));
  // Offsets end at 3·|F| = the number of halfedges, an int.
  g.offsets = a.begin(nf * sizeof(std::int32_t));
  for (std::uint64_t f = 0; f < nf; ++f) a.put(static_cast<std::int32_t>(3 * (f + 1)));
  g.types = a.begin(nf * sizeof(std::uint8_t));
  for (std::uint64_t f = 0; f < nf; ++f) a.put(std::uint8_t{5});  // VTK_TRIANGLE
  g.appended = std::move(a.data());
  return g;
}

// Writes one .vtu: the mesh of `g` and the point data arrays described by `data_arrays`
// (their <DataArray> lines, offsets counted from the start of the appended section) whose
// bytes `a` holds after g's. `attributes` are the <PointData> element's (active arrays).
void write_piece(const fs::path& path, double time, const Geometry& g,
                 const std::string& attributes, const std::string& data_arrays, Appended& a) {
  const std::string head = fmt::format(
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
      "header_type=\"UInt64\">\n"
      "  <UnstructuredGrid>\n"
      "    <FieldData>\n"
      "      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" "
      "format=\"ascii\">{:.17g}</DataArray>\n"
      "    </FieldData>\n"
      "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n"
      "      <PointData {}>\n"
      "{}"
      "      </PointData>\n"
      "      <Points>\n"
      "        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"appended\" "
      "offset=\"{}\"/>\n"
      "      </Points>\n"
      "      <Cells>\n"
      "        <DataArray type=\"Int32\" Name=\"connectivity\" format=\"appended\" offset=\"{}\"/>\n"
      "        <DataArray type=\"Int32\" Name=\"offsets\" format=\"appended\" offset=\"{}\"/>\n"
      "        <DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"{}\"/>\n"
      "      </Cells>\n"
      "    </Piece>\n"
      "  </UnstructuredGrid>\n"
      "  <AppendedData encoding=\"raw\">\n"
      "   _",
      time, g.num_points, g.num_cells, attributes, data_arrays, g.points, g.connectivity, g.offsets,
      g.types);
  a.data().append("\n  </AppendedData>\n</VTKFile>\n");
  write_whole_file(path, head, g.appended, a.data());
}

void write_frame(const fs::path& path, const TangentBundle& bundle, const Field& field, int frame,
                 const Geometry& g) {
  const Mesh& mesh = bundle.mesh();
  const int nv = mesh.num_vertices();
  Appended a;
  const std::uint64_t base = g.appended.size();
  const std::uint64_t vector = base + a.begin(static_cast<std::uint64_t>(nv) * 3 * sizeof(float));
  std::vector<float> magnitude(static_cast<size_t>(nv));
  const auto values = field.frame(frame);
  for (int v = 0; v < nv; ++v) {
    const Vec3 w = bundle.vertex_to_world(v, values[static_cast<size_t>(v)]);
    for (int k = 0; k < 3; ++k) a.put(static_cast<float>(w[k]));
    magnitude[static_cast<size_t>(v)] = static_cast<float>(w.norm());
  }
  const std::uint64_t mag = base + a.begin(static_cast<std::uint64_t>(nv) * sizeof(float));
  for (float m : magnitude) a.put(m);

  const std::string data_arrays = fmt::format(
      "        <DataArray type=\"Float32\" Name=\"vector\" NumberOfComponents=\"3\" "
      "format=\"appended\" offset=\"{}\"/>\n"
      "        <DataArray type=\"Float32\" Name=\"magnitude\" format=\"appended\" offset=\"{}\"/>\n",
      vector, mag);
  write_piece(path, field.time().time(frame), g, "Vectors=\"vector\" Scalars=\"magnitude\"", data_arrays,
              a);
}

std::string frame_name(const std::string& stem, int frame, int digits) {
  return fmt::format("{}_{:0{}}.vtu", stem, frame, digits);
}

int frame_digits(size_t frames) {
  int digits = 4;
  for (auto n = static_cast<long>(frames) - 1; n >= 10000; n /= 10) ++digits;
  return digits;
}

std::string parallel_frame_name(const std::string& stem, int frame, int digits) {
  return fmt::format("{}_{:0{}}.pvtu", stem, frame, digits);
}

std::string piece_name(const std::string& stem, int frame, int digits, int rank) {
  return fmt::format("{}_{:0{}}_p{}.vtu", stem, frame, digits, rank);
}

// `numbers`: the files' numbers (default: 0, 1, …).
void write_collection(const fs::path& folder, const std::string& stem, const std::vector<double>& times, int digits,
                      bool parallel = false, std::span<const int> numbers = {}) {
  std::string pvd =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
      "  <Collection>\n";
  for (size_t j = 0; j < times.size(); ++j) {
    const int number = numbers.empty() ? static_cast<int>(j) : numbers[j];
    pvd += fmt::format("    <DataSet timestep=\"{:.17g}\" part=\"0\" file=\"{}\"/>\n", times[j],
                       xml_escape(parallel ? parallel_frame_name(stem, number, digits) : frame_name(stem, number, digits)));
  }
  pvd += "  </Collection>\n</VTKFile>\n";
  write_whole_file(folder / (stem + ".pvd"), pvd, {}, {});
}

}  // namespace

void write_vtk_scalar_series(const std::string& dir, const std::string& stem, const Mesh& mesh,
                             const std::vector<double>& times, const std::vector<VtkScalarArray>& arrays,
                             std::span<const int> numbers) {
  const auto nv = static_cast<size_t>(mesh.num_vertices());
  for (const auto& array : arrays)
    TVF_CHECK(array.values.size() == times.size() * nv, "array {} has {} values for {} frames × {} vertices",
              array.name, array.values.size(), times.size(), nv);
  TVF_CHECK(numbers.empty() || numbers.size() == times.size(), "{} file numbers for {} times", numbers.size(),
            times.size());
  const fs::path folder(dir);
  int digits = 4;
  long largest = static_cast<long>(times.size()) - 1;
  for (const int n : numbers) largest = std::max(largest, static_cast<long>(n));
  for (long n = largest; n >= 10000; n /= 10) ++digits;
  const Geometry g = make_geometry(mesh);
  tbb::parallel_for(0, static_cast<int>(times.size()), [&](int j) {
    Appended a;
    const std::uint64_t base = g.appended.size();
    std::string data_arrays;
    for (const auto& array : arrays) {
      const std::uint64_t offset = base + a.begin(nv * sizeof(float));
      for (size_t v = 0; v < nv; ++v) a.put(array.values[static_cast<size_t>(j) * nv + v]);
      data_arrays += fmt::format(
          "        <DataArray type=\"Float32\" Name=\"{}\" format=\"appended\" offset=\"{}\"/>\n",
          xml_escape(array.name), offset);
    }
    const std::string attributes =
        fmt::format("Scalars=\"{}\"", arrays.empty() ? "" : xml_escape(arrays.front().name));
    const int number = numbers.empty() ? j : numbers[static_cast<size_t>(j)];
    write_piece(folder / frame_name(stem, number, digits), times[static_cast<size_t>(j)], g, attributes, data_arrays, a);
  });
  write_collection(folder, stem, times, digits, false, numbers);
}

void write_vtk_series(const std::string& dir, const std::string& stem, const TangentBundle& bundle,
                      const Field& field) {
  const Mesh& mesh = bundle.mesh();
  TVF_CHECK(field.num_vertices() == mesh.num_vertices(), "field has {} vertices, mesh has {}",
            field.num_vertices(), mesh.num_vertices());
  const fs::path folder(dir);
  int digits = 4;
  for (int n = field.frames() - 1; n >= 10000; n /= 10) ++digits;

  const Geometry geometry = make_geometry(mesh);
  tbb::parallel_for(0, field.frames(), [&](int j) {
    write_frame(folder / frame_name(stem, j, digits), bundle, field, j, geometry);
  });

  write_collection(folder, stem, field.time().times(), digits);
}

namespace {

// A rank's piece: its faces (those whose lowest vertex it owns) and points (its own
// vertices and the halo vertices of its faces, in vertex order).
struct PieceParts {
  std::vector<int> points, faces;
};

PieceParts piece_parts(const Mesh& mesh, std::span<const int> owner, int rank) {
  const auto nv = static_cast<size_t>(mesh.num_vertices());
  TVF_CHECK(owner.size() == nv, "a partition of {} vertices for a mesh of {}", owner.size(), nv);
  PieceParts p;
  std::vector<char> used(nv, 0);
  for (size_t v = 0; v < nv; ++v) used[v] = owner[v] == rank ? 1 : 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Face& face = mesh.face(f);
    const int lowest = std::min({face[0], face[1], face[2]});
    if (owner[static_cast<size_t>(lowest)] != rank) continue;
    p.faces.push_back(f);
    for (int v : face) used[static_cast<size_t>(v)] = 1;
  }
  for (size_t v = 0; v < nv; ++v)
    if (used[v] != 0) p.points.push_back(static_cast<int>(v));
  return p;
}

// value(j, i): the field at frame j at the piece's point i.
template <class Value>
void write_pieces(const std::string& dir, const std::string& stem, const TangentBundle& bundle,
                  const TimeSampling& time, std::span<const int> owner, int rank, const PieceParts& parts,
                  const Value& value) {
  const Mesh& mesh = bundle.mesh();
  const std::vector<int>& points = parts.points;
  std::vector<int> local(static_cast<size_t>(mesh.num_vertices()), -1);
  for (size_t i = 0; i < points.size(); ++i) local[static_cast<size_t>(points[i])] = static_cast<int>(i);
  const Geometry g = make_geometry(mesh, points, parts.faces, local);
  const int digits = frame_digits(static_cast<size_t>(time.frames));
  const fs::path folder(dir);
  const auto np = static_cast<std::uint64_t>(points.size());
  tbb::parallel_for(0, time.frames, [&](int j) {
    Appended a;
    const std::uint64_t base = g.appended.size();
    const std::uint64_t vector = base + a.begin(np * 3 * sizeof(float));
    std::vector<float> magnitude(points.size());
    for (size_t i = 0; i < points.size(); ++i) {
      const int v = points[i];
      const Vec3 w = bundle.vertex_to_world(v, value(j, i));
      for (int k = 0; k < 3; ++k) a.put(static_cast<float>(w[k]));
      magnitude[i] = static_cast<float>(w.norm());
    }
    const std::uint64_t mag = base + a.begin(np * sizeof(float));
    for (float m : magnitude) a.put(m);
    const std::uint64_t vertex = base + a.begin(np * sizeof(std::int32_t));
    for (int v : points) a.put(static_cast<std::int32_t>(v));
    const std::uint64_t ghost = base + a.begin(np * sizeof(std::uint8_t));
    for (int v : points) a.put(static_cast<std::uint8_t>(owner[static_cast<size_t>(v)] == rank ? 0 : 1));
    const std::string data_arrays = fmt::format(
        "        <DataArray type=\"Float32\" Name=\"vector\" NumberOfComponents=\"3\" "
        "format=\"appended\" offset=\"{}\"/>\n"
        "        <DataArray type=\"Float32\" Name=\"magnitude\" format=\"appended\" offset=\"{}\"/>\n"
        "        <DataArray type=\"Int32\" Name=\"vertex\" format=\"appended\" offset=\"{}\"/>\n"
        "        <DataArray type=\"UInt8\" Name=\"vtkGhostType\" format=\"appended\" offset=\"{}\"/>\n",
        vector, mag, vertex, ghost);
    write_piece(folder / piece_name(stem, j, digits, rank), time.time(j), g,
                "Vectors=\"vector\" Scalars=\"magnitude\"", data_arrays, a);
  });
}

}  // namespace

void write_vtk_series_piece(const std::string& dir, const std::string& stem, const TangentBundle& bundle,
                            const Field& field, std::span<const int> owner, int rank) {
  const Mesh& mesh = bundle.mesh();
  TVF_CHECK(field.num_vertices() == mesh.num_vertices() && owner.size() == static_cast<size_t>(mesh.num_vertices()),
            "field has {} vertices, mesh {}, partition {}", field.num_vertices(), mesh.num_vertices(), owner.size());
  const PieceParts parts = piece_parts(mesh, owner, rank);
  write_pieces(dir, stem, bundle, field.time(), owner, rank, parts, [&](int j, size_t i) {
    return field.frame(j)[static_cast<size_t>(parts.points[i])];
  });
}

std::vector<int> vtk_piece_points(const Mesh& mesh, std::span<const int> owner, int rank) {
  return piece_parts(mesh, owner, rank).points;
}

void write_vtk_series_piece(const std::string& dir, const std::string& stem, const TangentBundle& bundle,
                            const TimeSampling& time, std::span<const int> owner, int rank,
                            std::span<const cplx> values) {
  const PieceParts parts = piece_parts(bundle.mesh(), owner, rank);
  const size_t np = parts.points.size();
  TVF_CHECK(values.size() == np * static_cast<size_t>(time.frames), "{} values for {} frames × {} points",
            values.size(), time.frames, np);
  write_pieces(dir, stem, bundle, time, owner, rank, parts,
               [&](int j, size_t i) { return values[static_cast<size_t>(j) * np + i]; });
}

void write_vtk_parallel_series(const std::string& dir, const std::string& stem, const std::vector<double>& times,
                               int ranks) {
  const int digits = frame_digits(times.size());
  const fs::path folder(dir);
  for (size_t j = 0; j < times.size(); ++j) {
    std::string pvtu =
        "<?xml version=\"1.0\"?>\n"
        "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
        "header_type=\"UInt64\">\n"
        "  <PUnstructuredGrid GhostLevel=\"0\">\n"
        "    <PPointData Vectors=\"vector\" Scalars=\"magnitude\">\n"
        "      <PDataArray type=\"Float32\" Name=\"vector\" NumberOfComponents=\"3\"/>\n"
        "      <PDataArray type=\"Float32\" Name=\"magnitude\"/>\n"
        "      <PDataArray type=\"Int32\" Name=\"vertex\"/>\n"
        "      <PDataArray type=\"UInt8\" Name=\"vtkGhostType\"/>\n"
        "    </PPointData>\n"
        "    <PPoints>\n"
        "      <PDataArray type=\"Float64\" NumberOfComponents=\"3\"/>\n"
        "    </PPoints>\n";
    for (int r = 0; r < ranks; ++r)
      pvtu += fmt::format("    <Piece Source=\"{}\"/>\n",
                          xml_escape(piece_name(stem, static_cast<int>(j), digits, r)));
    pvtu += "  </PUnstructuredGrid>\n</VTKFile>\n";
    write_whole_file(folder / parallel_frame_name(stem, static_cast<int>(j), digits), pvtu, {}, {});
  }
  write_collection(folder, stem, times, digits, true);
}

}  // namespace tvf
