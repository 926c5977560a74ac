#include "tvf/field/npy.h"

#include "tvf/core/error.h"
#include "support/test_paths.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>

namespace tvf {
namespace {

namespace fs = std::filesystem;
using test::read_text;
using test::TempDir;
using test::error_of;
using test::write_text;

// A version 1.0 file with the given header dict (padded here) and raw data.
std::string make_npy(std::string dict, const std::string& data) {
  dict.append((64 - (10 + dict.size() + 1) % 64) % 64, ' ');
  dict += '\n';
  std::string bytes("\x93NUMPY\x01\x00", 8);
  bytes += static_cast<char>(dict.size() & 0xff);
  bytes += static_cast<char>(dict.size() >> 8);
  return bytes + dict + data;
}

std::string header_of(const std::string& bytes) {
  const size_t len = static_cast<unsigned char>(bytes[8]) | (static_cast<size_t>(static_cast<unsigned char>(bytes[9])) << 8);
  return bytes.substr(10, len);
}

TEST(Npy, HeaderIsNumPy10PaddedTo64Bytes) {
  TempDir dir;
  const std::vector<size_t> shape{100, 4225, 3};
  std::vector<float> data(100 * 4225 * 3, 0.5f);
  write_npy((dir / "a.npy").string(), shape, data.data());
  const std::string bytes = read_text(dir / "a.npy");
  ASSERT_GE(bytes.size(), 10u);
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x93NUMPY\x01\x00", 8));
  const std::string header = header_of(bytes);
  EXPECT_EQ((10 + header.size()) % 64, 0u);
  EXPECT_EQ(header.back(), '\n');
  EXPECT_EQ(header.rfind("{'descr': '<f4', 'fortran_order': False, 'shape': (100, 4225, 3), }", 0), 0u)
      << header;
  const std::string dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (100, 4225, 3), }";
  EXPECT_EQ(header.find_first_not_of(' ', dict.size()), header.size() - 1);
  EXPECT_EQ(bytes.size(), 10 + header.size() + data.size() * sizeof(float));

  const double d[3] = {1, 2, 3};
  write_npy((dir / "b.npy").string(), {3}, d);
  EXPECT_EQ(header_of(read_text(dir / "b.npy")).rfind("{'descr': '<f8', 'fortran_order': False, 'shape': (3,), }", 0),
            0u);
  size_t files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir.path())) ++files;
  EXPECT_EQ(files, 2u);  // no temporaries left
}

TEST(Npy, RoundTripsEveryDtype) {
  TempDir dir;
  std::vector<float> f(2 * 3 * 4);
  for (size_t k = 0; k < f.size(); ++k) f[k] = static_cast<float>(k) * 0.1f - 1.0f;
  std::vector<double> d{0.1, -2.5e-300, 1e300, 3.0, 4.0};
  std::vector<std::int32_t> i{-2147483647 - 1, 0, 7, 2147483647, -5, 12};
  write_npy((dir / "f.npy").string(), {2, 3, 4}, f.data());
  write_npy((dir / "d.npy").string(), {5}, d.data());
  write_npy((dir / "i.npy").string(), {3, 2}, i.data());
  write_npy((dir / "e.npy").string(), {0, 3}, static_cast<const double*>(nullptr));

  const NpyArray fa = read_npy((dir / "f.npy").string());
  EXPECT_EQ(fa.dtype, "<f4");
  EXPECT_EQ(fa.shape, (std::vector<size_t>{2, 3, 4}));
  ASSERT_EQ(fa.values.size(), f.size());
  for (size_t k = 0; k < f.size(); ++k) EXPECT_EQ(fa.values[k], static_cast<double>(f[k]));

  const NpyArray da = read_npy((dir / "d.npy").string());
  EXPECT_EQ(da.dtype, "<f8");
  EXPECT_EQ(da.shape, std::vector<size_t>{5});
  EXPECT_EQ(da.values, d);

  const NpyArray ia = read_npy((dir / "i.npy").string());
  EXPECT_EQ(ia.dtype, "<i4");
  EXPECT_EQ(ia.shape, (std::vector<size_t>{3, 2}));
  ASSERT_EQ(ia.values.size(), i.size());
  for (size_t k = 0; k < i.size(); ++k) EXPECT_EQ(ia.values[k], static_cast<double>(i[k]));

  const NpyArray ea = read_npy((dir / "e.npy").string());
  EXPECT_EQ(ea.shape, (std::vector<size_t>{0, 3}));
  EXPECT_TRUE(ea.values.empty());
}

// A float32 array written in parts (field.npy frame by frame) is write_npy's file byte for
// byte; a part that fails leaves no file.
TEST(Npy, WrittenInPartsIsTheWholeArraysFile) {
  TempDir dir;
  std::vector<float> f(4 * 3 * 2);
  for (size_t k = 0; k < f.size(); ++k) f[k] = static_cast<float>(k) * 0.37f - 2.0f;
  write_npy((dir / "whole.npy").string(), {4, 3, 2}, f.data());
  std::vector<size_t> asked;
  write_npy_parts((dir / "parts.npy").string(), {4, 3, 2}, 4, [&](size_t k) {
    asked.push_back(k);
    return std::vector<float>(f.begin() + static_cast<std::ptrdiff_t>(6 * k),
                              f.begin() + static_cast<std::ptrdiff_t>(6 * k + 6));
  });
  EXPECT_EQ(asked, (std::vector<size_t>{0, 1, 2, 3}));
  EXPECT_EQ(read_text(dir / "parts.npy"), read_text(dir / "whole.npy"));
  const std::string message = error_of([&] {
    write_npy_parts((dir / "failed.npy").string(), {4, 3, 2}, 4, [&](size_t k) {
      if (k == 2) throw Error("part 2 is not finite");
      return std::vector<float>(6, 1.0f);
    });
  });
  EXPECT_EQ(message, "part 2 is not finite");
  EXPECT_FALSE(fs::exists(dir / "failed.npy"));
  size_t files = 0;  // no temporary file left either
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir.path())) ++files;
  EXPECT_EQ(files, 2u);
}

TEST(Npy, ReadsVersion2Headers) {
  TempDir dir;
  std::string dict = "{'shape': (2,), 'fortran_order': False, 'descr': '<i4'}";
  dict.append((64 - (12 + dict.size() + 1) % 64) % 64, ' ');
  dict += '\n';
  std::string bytes("\x93NUMPY\x02\x00", 8);
  const auto len = static_cast<std::uint32_t>(dict.size());
  bytes.append(reinterpret_cast<const char*>(&len), 4);
  bytes += dict;
  const std::int32_t values[2] = {-3, 9};
  bytes.append(reinterpret_cast<const char*>(values), sizeof(values));
  write_text(dir / "v2.npy", bytes);
  const NpyArray a = read_npy((dir / "v2.npy").string());
  EXPECT_EQ(a.dtype, "<i4");
  EXPECT_EQ(a.shape, std::vector<size_t>{2});
  EXPECT_EQ(a.values, (std::vector<double>{-3, 9}));
}

TEST(Npy, BadFilesAreErrorsNamingThePath) {
  TempDir dir;
  const std::vector<double> d{1, 2, 3, 4, 5, 6};
  const fs::path good = dir / "good.npy";
  write_npy(good.string(), {2, 3}, d.data());
  const std::string bytes = read_text(good);

  struct Case {
    std::string name, bytes, expect;
  };
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string b = bytes;
    const size_t at = b.find(from);
    EXPECT_NE(at, std::string::npos);
    b.replace(at, from.size(), to);
    return b;
  };
  const std::string payload(reinterpret_cast<const char*>(d.data()), d.size() * sizeof(double));
  ASSERT_EQ(make_npy("{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }", payload), bytes);
  std::string bad_magic = bytes;
  bad_magic[0] = '\x92';
  std::string version3 = bytes;
  version3[6] = '\x03';
  const std::vector<Case> cases = {
      {"empty.npy", "", "too short"},
      {"magic.npy", bad_magic, "bad magic"},
      {"version.npy", version3, "version 3.0"},
      {"truncated.npy", bytes.substr(0, bytes.size() - 1), "size does not match"},
      {"longer.npy", bytes + "x", "size does not match"},
      {"header.npy", bytes.substr(0, 40), "truncated .npy header"},
      {"fortran.npy", replaced("False", "True "), "Fortran"},
      {"dtype.npy", replaced("<f8", ">f8"), "dtype '>f8'"},
      {"int64.npy", replaced("<f8", "<i8"), "dtype '<i8'"},
      {"shape.npy", replaced("(2, 3)", "(2, x)"), "bad .npy header"},
      {"huge.npy", make_npy("{'descr': '<f8', 'fortran_order': False, 'shape': (99999999999999999999,), }", payload),
       "dimension too large"},
      {"overflow.npy", make_npy("{'descr': '<f8', 'fortran_order': False, 'shape': (4294967296, 4294967296), }", payload),
       "size does not match"},
      {"nokey.npy", make_npy("{'descr': '<f8', 'shape': (6,), }", payload), "needs"},
      {"extra.npy", make_npy("{'descr': '<f8', 'fortran_order': False, 'shape': (6,), 'x': 1, }", payload),
       "unknown key 'x'"},
  };
  for (const Case& c : cases) {
    const fs::path path = dir / c.name;
    write_text(path, c.bytes);
    const std::string message = error_of([&] { read_npy(path.string()); });
    EXPECT_NE(message.find(path.string()), std::string::npos) << message;
    EXPECT_NE(message.find(c.expect), std::string::npos) << c.name << ": " << message;
  }
  const fs::path missing = dir / "missing.npy";
  EXPECT_NE(error_of([&] { read_npy(missing.string()); }).find(missing.string()), std::string::npos);
  const fs::path no_dir = dir / "no" / "x.npy";
  EXPECT_NE(error_of([&] { write_npy(no_dir.string(), {6}, d.data()); }).find(no_dir.string()),
            std::string::npos);
}

// NumPy itself reads what we write, and we read what NumPy writes.
TEST(Npy, NumPyAgrees) {
  const std::string py = test::python();
  if (py.empty() || test::run_command("'" + py + "' -c 'import numpy'").exit_code != 0)
    GTEST_SKIP() << "Debian python3 with numpy not available";
  TempDir dir;
  std::vector<float> f(2 * 3 * 4);
  for (size_t k = 0; k < f.size(); ++k) f[k] = static_cast<float>(k) * 0.25f - 1.0f;
  std::vector<double> d(7);
  for (size_t k = 0; k < d.size(); ++k) d[k] = 1.0 / static_cast<double>(k + 3);
  std::vector<std::int32_t> i{-5, 0, 5, 2147483647, -2147483647 - 1, 12};
  write_npy((dir / "f.npy").string(), {2, 3, 4}, f.data());
  write_npy((dir / "d.npy").string(), {7}, d.data());
  write_npy((dir / "i.npy").string(), {3, 2}, i.data());
  test::write_text(dir / "check.py", R"(
import sys, numpy as np
d = sys.argv[1]
def check(name, dtype, shape, expected):
    a = np.load(d + '/' + name)
    if a.dtype != np.dtype(dtype) or a.shape != shape or not np.array_equal(a, np.asarray(expected, dtype=dtype).reshape(shape)):
        print('mismatch in', name, a.dtype, a.shape, a)
        sys.exit(1)
check('f.npy', '<f4', (2, 3, 4), np.arange(24, dtype='<f4') * np.float32(0.25) - np.float32(1))
check('d.npy', '<f8', (7,), 1.0 / (np.arange(7) + 3.0))
check('i.npy', '<i4', (3, 2), [-5, 0, 5, 2147483647, -2147483648, 12])
np.save(d + '/np_f8.npy', np.arange(12, dtype='<f8').reshape(3, 4) / 7.0)
np.save(d + '/np_i4.npy', np.arange(-3, 3, dtype='<i4'))
np.save(d + '/np_f4.npy', np.full((2, 1, 2), 0.1, dtype='<f4'))
np.save(d + '/np_fortran.npy', np.asfortranarray(np.ones((2, 3))))
)");
  const auto r = test::run_command("'" + py + "' '" + (dir / "check.py").string() + "' '" + dir.path().string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.output;

  const NpyArray a = read_npy((dir / "np_f8.npy").string());
  EXPECT_EQ(a.dtype, "<f8");
  EXPECT_EQ(a.shape, (std::vector<size_t>{3, 4}));
  for (size_t k = 0; k < 12; ++k) EXPECT_EQ(a.values[k], static_cast<double>(k) / 7.0);
  const NpyArray b = read_npy((dir / "np_i4.npy").string());
  EXPECT_EQ(b.shape, std::vector<size_t>{6});
  EXPECT_EQ(b.values, (std::vector<double>{-3, -2, -1, 0, 1, 2}));
  const NpyArray c = read_npy((dir / "np_f4.npy").string());
  EXPECT_EQ(c.shape, (std::vector<size_t>{2, 1, 2}));
  for (double v : c.values) EXPECT_EQ(v, static_cast<double>(0.1f));
  EXPECT_NE(error_of([&] { read_npy((dir / "np_fortran.npy").string()); }).find("Fortran"),
            std::string::npos);
}

}  // namespace
}  // namespace tvf
