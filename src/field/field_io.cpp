#include "tvf/field/field_io.h"

#include "tvf/core/atomic_output.h"
#include "tvf/core/error.h"
#include "tvf/core/json_text.h"

#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <system_error>

namespace tvf {

namespace fs = std::filesystem;

static_assert(std::endian::native == std::endian::little,
              "field_io.cpp writes the host's bytes as little-endian data");
static_assert(sizeof(cplx) == 2 * sizeof(double), "std::complex<double> is two doubles");

namespace {

constexpr char kMagic[8] = {'T', 'V', 'F', 'F', 'I', 'E', 'L', 'D'};
constexpr std::uint32_t kVersion = 1;
constexpr size_t kPreamble = sizeof(kMagic) + sizeof(std::uint32_t) + sizeof(std::uint64_t);

[[noreturn]] void fail(const std::string& path, const std::string& message) {
  throw_input_error(path, "", message);
}

template <class T>
void put(std::ostream& out, const T& value) {
  out.write(reinterpret_cast<const char*>(&value), sizeof(T));
}

template <class T>
void put_array(std::ostream& out, const T* data, size_t count) {
  if (count > 0) out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(count * sizeof(T)));
}

// Bytes of `count` items of `item` bytes, added to `total`; false on overflow.
bool add_bytes(std::uint64_t& total, std::uint64_t count, std::uint64_t item) {
  if (count > 0 && item > std::numeric_limits<std::uint64_t>::max() / count) return false;
  const std::uint64_t bytes = count * item;
  if (bytes > std::numeric_limits<std::uint64_t>::max() - total) return false;
  total += bytes;
  return true;
}

// An integer of the header in [minimum, INT_MAX].
int header_count(const std::string& path, const nlohmann::json& header, const char* key,
                 int minimum) {
  const auto it = header.find(key);
  if (it == header.end() || !it->is_number_integer())
    fail(path, fmt::format("header: '{}' must be an integer", key));
  const auto value = it->get<std::int64_t>();
  if (value < minimum || value > std::numeric_limits<int>::max())
    fail(path, fmt::format("header: '{}' = {} is out of range", key, value));
  return static_cast<int>(value);
}

double header_number(const std::string& path, const nlohmann::json& header, const char* key) {
  const auto it = header.find(key);
  if (it == header.end() || !it->is_number()) fail(path, fmt::format("header: '{}' must be a number", key));
  return it->get<double>();
}

}  // namespace

void save_field_file(const std::string& path, const Mesh& mesh, const Field& field,
                     const nlohmann::json& scene) {
  TVF_CHECK(field.num_vertices() == mesh.num_vertices(), "field has {} vertices, mesh has {}",
            field.num_vertices(), mesh.num_vertices());
  const nlohmann::json header_json = {{"vertices", mesh.num_vertices()},
                                      {"faces", mesh.num_faces()},
                                      {"frames", field.frames()},
                                      {"t0", field.time().t0},
                                      {"t1", field.time().t1},
                                      {"scene", scene}};
  std::string header = header_json.dump();
  // Pad with spaces (valid trailing JSON whitespace) so the arrays start 8-byte aligned.
  header.append((8 - (kPreamble + header.size()) % 8) % 8, ' ');

  write_file_atomically(fs::path(path), [&](std::ostream& out) {
    out.write(kMagic, sizeof(kMagic));
    put(out, kVersion);
    put(out, static_cast<std::uint64_t>(header.size()));
    out.write(header.data(), static_cast<std::streamsize>(header.size()));
    for (const Vec3& p : mesh.positions()) put_array(out, p.data(), 3);
    for (const Face& f : mesh.faces()) {
      const std::int32_t idx[3] = {f[0], f[1], f[2]};
      put_array(out, idx, 3);
    }
    put_array(out, reinterpret_cast<const double*>(field.data().data()), 2 * field.data().size());
  });
}

FieldFile load_field_file(const std::string& path) {
  // A folder whose commit was interrupted may hold this file from one run and the rest
  // from another (core/atomic_output.h).
  check_output_complete(fs::path(path).parent_path().empty() ? fs::path(".") : fs::path(path).parent_path());
  std::error_code ec;
  const std::uint64_t file_size = fs::file_size(path, ec);
  if (ec) fail(path, "cannot read the field file (" + ec.message() + ")");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open the field file");

  char magic[sizeof(kMagic)];
  std::uint32_t version = 0;
  std::uint64_t header_len = 0;
  if (file_size < kPreamble) fail(path, "not a tvf field file (too short)");
  in.read(magic, sizeof(magic));
  in.read(reinterpret_cast<char*>(&version), sizeof(version));
  in.read(reinterpret_cast<char*>(&header_len), sizeof(header_len));
  if (!in) fail(path, "cannot read the field file");
  if (std::memcmp(magic, kMagic, sizeof(kMagic)) != 0)
    fail(path, "not a tvf field file (bad magic; expected \"TVFFIELD\")");
  if (version != kVersion)
    fail(path, fmt::format("unsupported field file version {} (this tvf reads version {})", version,
                           kVersion));
  if (header_len > file_size - kPreamble)
    fail(path, fmt::format("truncated field file (header of {} bytes, but only {} bytes follow)",
                           header_len, file_size - kPreamble));

  std::string header_text(static_cast<size_t>(header_len), '\0');
  if (!in.read(header_text.data(), static_cast<std::streamsize>(header_len)))
    fail(path, "cannot read the field file header");
  nlohmann::json header;
  try {
    header = parse_json_text(header_text, "", "expected a JSON object");
  } catch (const Error& e) {
    fail(path, std::string("bad field file header (") + e.what() + ")");
  }
  if (!header.is_object()) fail(path, "bad field file header (not a JSON object)");
  const int nv = header_count(path, header, "vertices", 0);
  const int nf = header_count(path, header, "faces", 0);
  const int frames = header_count(path, header, "frames", 1);
  const TimeSampling time{header_number(path, header, "t0"), header_number(path, header, "t1"), frames};
  if (!(time.t0 < time.t1))
    fail(path, fmt::format("header: the time range [{}, {}] must have t0 < t1", time.t0, time.t1));
  if (!std::isfinite(time.t1 - time.t0))
    fail(path, fmt::format("header: the time range [{}, {}] is too long to represent", time.t0, time.t1));

  // Check the sizes against the file before allocating anything they imply.
  std::uint64_t expected = kPreamble + header_len;
  const bool fits = add_bytes(expected, static_cast<std::uint64_t>(nv), 3 * sizeof(double)) &&
                    add_bytes(expected, static_cast<std::uint64_t>(nf), 3 * sizeof(std::int32_t)) &&
                    add_bytes(expected, static_cast<std::uint64_t>(frames) * static_cast<std::uint64_t>(nv),
                              2 * sizeof(double));
  if (!fits || expected != file_size)
    fail(path, fmt::format("{} field file: its header ({} vertices, {} faces, {} frames) needs {} "
                           "bytes, the file has {}",
                           !fits || expected > file_size ? "truncated" : "corrupt", nv, nf, frames,
                           fits ? std::to_string(expected) : std::string("more than 2^64"), file_size));

  std::vector<Vec3> positions(static_cast<size_t>(nv));
  for (Vec3& p : positions) in.read(reinterpret_cast<char*>(p.data()), 3 * sizeof(double));
  std::vector<Face> faces(static_cast<size_t>(nf));
  for (Face& f : faces) {
    std::int32_t idx[3];
    in.read(reinterpret_cast<char*>(idx), sizeof(idx));
    f = {idx[0], idx[1], idx[2]};
  }
  Field field(time, nv);
  if (!field.data().empty())
    in.read(reinterpret_cast<char*>(field.data().data()),
            static_cast<std::streamsize>(field.data().size() * sizeof(cplx)));
  if (!in) fail(path, "cannot read the field file data");
  for (size_t k = 0; k < field.data().size(); ++k) {
    const cplx z = field.data()[k];
    if (!std::isfinite(z.real()) || !std::isfinite(z.imag()))
      fail(path, fmt::format("frame {}, vertex {}: the vector ({}, {}) is not finite", k / static_cast<size_t>(nv),
                             k % static_cast<size_t>(nv), z.real(), z.imag()));
  }

  FieldFile result{Mesh(std::move(positions), std::move(faces), path), std::move(field),
                   header.value("scene", nlohmann::json())};
  return result;
}

}  // namespace tvf
