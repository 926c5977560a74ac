#include "tvf/field/field_io.h"

#include "tvf/core/error.h"
#include "support/test_meshes.h"
#include "support/test_paths.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <random>

namespace tvf {
namespace {

namespace fs = std::filesystem;
using test::read_text;
using test::TempDir;
using test::error_of;
using test::write_text;

// Random doubles, with a few awkward ones (signed zero, subnormal, huge).
Field random_field(const TimeSampling& ts, int nv, unsigned seed) {
  Field field(ts, nv);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  for (cplx& z : field.data()) z = {g(rng) / 3.0, g(rng) * 1e-7};
  field.data()[0] = {-0.0, std::numeric_limits<double>::denorm_min()};
  field.data()[1] = {1e300, -std::numeric_limits<double>::min()};
  return field;
}

bool same_bits(const void* a, const void* b, size_t bytes) { return std::memcmp(a, b, bytes) == 0; }

TEST(FieldFile, RoundTripIsBitExact) {
  const nlohmann::json scene = {{"tvf", 1},
                                {"time", {{"frames", 3}, {"range", {-0.1, 0.7}}}},
                                {"falloff", 0.1},
                                {"elements", nlohmann::json::array({{{"kind", "singular"}, {"type", "saddle"}}})}};
  for (const Mesh* mesh : {&test::grid_mesh(), &test::icosphere_mesh()}) {
    TempDir dir;
    const TimeSampling ts{-0.1, 0.7, 3};  // neither end is exact in binary
    const Field field = random_field(ts, mesh->num_vertices(), 99);
    const std::string path = (dir / "field.tvff").string();
    save_field_file(path, *mesh, field, scene);
    const FieldFile loaded = load_field_file(path);

    ASSERT_EQ(loaded.mesh.num_vertices(), mesh->num_vertices());
    ASSERT_EQ(loaded.mesh.num_faces(), mesh->num_faces());
    EXPECT_TRUE(same_bits(loaded.mesh.positions().data(), mesh->positions().data(),
                          sizeof(Vec3) * mesh->positions().size()));
    EXPECT_EQ(loaded.mesh.faces(), mesh->faces());
    EXPECT_EQ(loaded.mesh.is_closed(), mesh->is_closed());
    EXPECT_EQ(loaded.field.frames(), 3);
    EXPECT_EQ(loaded.field.num_vertices(), mesh->num_vertices());
    EXPECT_EQ(loaded.field.time().t0, ts.t0);
    EXPECT_EQ(loaded.field.time().t1, ts.t1);
    ASSERT_EQ(loaded.field.data().size(), field.data().size());
    EXPECT_TRUE(same_bits(loaded.field.data().data(), field.data().data(),
                          sizeof(cplx) * field.data().size()));
    EXPECT_EQ(loaded.scene, scene);
    EXPECT_EQ(loaded.scene.dump(), scene.dump());
    size_t files = 0;
    for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir.path())) ++files;
    EXPECT_EQ(files, 1u);  // no temporaries left
  }
}

TEST(FieldFile, NullSceneRoundTrips) {
  TempDir dir;
  const Mesh& mesh = test::grid_mesh();
  const Field field = random_field(TimeSampling{0, 1, 1}, mesh.num_vertices(), 1);
  save_field_file((dir / "f.tvff").string(), mesh, field, nullptr);
  const FieldFile loaded = load_field_file((dir / "f.tvff").string());
  EXPECT_TRUE(loaded.scene.is_null());
  EXPECT_EQ(loaded.field.frames(), 1);
}

// A field file written by hand: magic, version, header, then `payload`.
std::string field_bytes(const std::string& header, const std::string& payload,
                        const char* magic = "TVFFIELD", std::uint32_t version = 1) {
  std::string b(magic, 8);
  b.append(reinterpret_cast<const char*>(&version), 4);
  const auto len = static_cast<std::uint64_t>(header.size());
  b.append(reinterpret_cast<const char*>(&len), 8);
  return b + header + payload;
}

TEST(FieldFile, CorruptFilesAreErrorsNamingTheFile) {
  TempDir dir;
  const Mesh& mesh = test::grid_mesh();
  const Field field = random_field(TimeSampling{0, 1, 2}, mesh.num_vertices(), 5);
  const fs::path good = dir / "good.tvff";
  save_field_file(good.string(), mesh, field, nullptr);
  const std::string bytes = read_text(good);
  // The file as it was written, rebuilt by hand from the documented layout.
  std::uint64_t header_len = 0;
  std::memcpy(&header_len, bytes.data() + 12, 8);
  const std::string header = bytes.substr(20, header_len);
  const std::string payload = bytes.substr(20 + header_len);
  ASSERT_EQ(payload.size(), static_cast<size_t>(mesh.num_vertices()) * 24 +
                                static_cast<size_t>(mesh.num_faces()) * 12 +
                                2 * static_cast<size_t>(mesh.num_vertices()) * 16);
  ASSERT_EQ(field_bytes(header, payload), bytes);

  std::string nan_payload = payload;
  const double nan_value[2] = {std::numeric_limits<double>::quiet_NaN(), 0.0};
  std::memcpy(nan_payload.data() + static_cast<size_t>(mesh.num_vertices()) * 24 +
                  static_cast<size_t>(mesh.num_faces()) * 12 + (static_cast<size_t>(mesh.num_vertices()) + 2) * 16,
              nan_value, 16);
  nlohmann::json deep = nlohmann::json::array();
  for (int k = 0; k < 1200; ++k) deep = nlohmann::json::array({deep});
  auto with = [&](const char* key, const nlohmann::json& value) {
    nlohmann::json h = nlohmann::json::parse(header);
    h[key] = value;
    return h.dump();
  };
  std::string huge_header_len = bytes;
  const std::uint64_t huge = std::numeric_limits<std::uint64_t>::max() - 4;
  std::memcpy(huge_header_len.data() + 12, &huge, 8);

  struct Case {
    std::string name, bytes, expect;
  };
  const std::vector<Case> cases = {
      {"empty.tvff", "", "too short"},
      {"magic.tvff", field_bytes(header, payload, "TVFFIELX"), "bad magic"},
      {"npy.tvff", std::string("\x93NUMPY\x01\x00", 8) + bytes.substr(8), "bad magic"},
      {"version.tvff", field_bytes(header, payload, "TVFFIELD", 2), "version 2"},
      {"truncated.tvff", bytes.substr(0, bytes.size() - 1), "truncated"},
      {"cut_header.tvff", bytes.substr(0, 30), "truncated"},
      {"longer.tvff", bytes + "xx", "corrupt"},
      {"huge_header.tvff", huge_header_len, "truncated"},
      {"json.tvff", field_bytes("{\"vertices\": ", payload), "bad field file header"},
      {"array.tvff", field_bytes("[1, 2]", payload), "not a JSON object"},
      {"vertices.tvff", field_bytes(with("vertices", 2147483647), payload), "2147483647 vertices"},
      {"frames.tvff", field_bytes(with("frames", 2147483647), payload), "truncated"},
      {"all.tvff",
       field_bytes(nlohmann::json({{"vertices", 2147483647}, {"faces", 2147483647}, {"frames", 2147483647},
                                   {"t0", 0}, {"t1", 1}, {"scene", nullptr}})
                       .dump(),
                   payload),
       "truncated"},
      {"too_big.tvff", field_bytes(with("vertices", 1e30), payload), "'vertices' must be an integer"},
      {"negative.tvff", field_bytes(with("faces", -3), payload), "'faces' = -3 is out of range"},
      {"no_frames.tvff", field_bytes(with("frames", 0), payload), "'frames' = 0 is out of range"},
      {"string.tvff", field_bytes(with("t0", "zero"), payload), "'t0' must be a number"},
      // Issue 17: a reversed time range, a NaN vector and a header nested too deep.
      {"reversed.tvff", field_bytes(with("t0", 2.0), payload), "header: the time range [2, 1] must have t0 < t1"},
      {"nan.tvff", field_bytes(header, nan_payload), "frame 1, vertex 2: the vector (nan, 0) is not finite"},
      {"deep.tvff", field_bytes(with("scene", deep), payload), "arrays and objects nest more than 1000 deep"},
  };
  for (const Case& c : cases) {
    const fs::path path = dir / c.name;
    write_text(path, c.bytes);
    const std::string message = error_of([&] { load_field_file(path.string()); });
    EXPECT_NE(message.find(path.string()), std::string::npos) << message;
    EXPECT_NE(message.find(c.expect), std::string::npos) << c.name << ": " << message;
  }

  // A face index out of range reaches the mesh's own validation, which names the file.
  std::string bad_face = payload;
  const std::int32_t out_of_range = mesh.num_vertices() + 5;
  std::memcpy(bad_face.data() + static_cast<size_t>(mesh.num_vertices()) * 24, &out_of_range, 4);
  const fs::path face_path = dir / "face.tvff";
  write_text(face_path, field_bytes(header, bad_face));
  EXPECT_NE(error_of([&] { load_field_file(face_path.string()); }).find(face_path.string()),
            std::string::npos);

  // A folder whose commit was interrupted (core/atomic_output.h) is refused.
  write_text(dir / ".tvf-committing", "");
  EXPECT_NE(error_of([&] { load_field_file(good.string()); }).find("interrupted output"), std::string::npos);
  fs::remove(dir / ".tvf-committing");
  EXPECT_NO_THROW(load_field_file(good.string()));

  const fs::path missing = dir / "missing.tvff";
  EXPECT_NE(error_of([&] { load_field_file(missing.string()); }).find(missing.string()), std::string::npos);
  const fs::path no_dir = dir / "no" / "f.tvff";
  EXPECT_NE(error_of([&] { save_field_file(no_dir.string(), mesh, field, nullptr); }).find(no_dir.string()),
            std::string::npos);
}

}  // namespace
}  // namespace tvf
