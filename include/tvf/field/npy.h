#pragma once
// NumPy .npy files (format version 1.0, little-endian, C order): the interchange format
// of DESIGN §11. Written by hand because the format is a 10-line header plus raw data
// and no Debian C++ library provides it (see docs/architecture.md).
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace tvf {

// Writes `data` (row-major, product of `shape` elements) to `path` via a temporary name.
void write_npy(const std::string& path, const std::vector<size_t>& shape, const float* data);
void write_npy(const std::string& path, const std::vector<size_t>& shape, const double* data);
void write_npy(const std::string& path, const std::vector<size_t>& shape, const std::int32_t* data);

// A float32 array written in `parts` consecutive parts of equal size (a field's frames, one
// at a time): part(k) returns part k's values, the shape's product / parts of them. The
// bytes are write_npy's for the whole array; only one part is held at a time. An exception
// from part() leaves no file.
void write_npy_parts(const std::string& path, const std::vector<size_t>& shape, size_t parts,
                     const std::function<std::vector<float>(size_t)>& part);

// A loaded array: dtype is "<f4", "<f8" or "<i4"; values converted to double.
struct NpyArray {
  std::string dtype;
  std::vector<size_t> shape;
  std::vector<double> values;
};
// Throws tvf::Error naming `path` for a missing file, a bad header, a dtype other than
// the three above, Fortran order or a truncated file.
NpyArray read_npy(const std::string& path);

}  // namespace tvf
