#include "tvf/field/npy.h"

#include "tvf/core/atomic_output.h"
#include "tvf/core/error.h"

#include <bit>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <string_view>
#include <system_error>

namespace tvf {

namespace fs = std::filesystem;

static_assert(std::endian::native == std::endian::little,
              "npy.cpp writes the host's bytes as little-endian data");

namespace {

constexpr char kMagic[] = "\x93NUMPY";  // 6 bytes
constexpr size_t kMagicSize = 6;

[[noreturn]] void fail(const std::string& path, const std::string& message) {
  throw_input_error(path, "", message);
}

// Product of the dimensions, or nullopt when it overflows size_t.
std::optional<size_t> element_count(const std::vector<size_t>& shape, size_t item_size) {
  size_t n = item_size;
  for (size_t d : shape) {
    if (d != 0 && n > std::numeric_limits<size_t>::max() / d) return std::nullopt;
    n *= d;
  }
  return item_size == 0 ? n : n / item_size;
}

// The complete preamble + header of a version 1.0 file, padded with spaces and ended by
// '\n' so that the data starts at a multiple of 64 bytes.
std::string npy_header(const std::string& path, const char* descr, const std::vector<size_t>& shape) {
  std::string dict = std::string("{'descr': '") + descr + "', 'fortran_order': False, 'shape': (";
  for (size_t k = 0; k < shape.size(); ++k) {
    dict += std::to_string(shape[k]);
    if (k + 1 < shape.size() || shape.size() == 1) dict += shape.size() == 1 ? "," : ", ";
  }
  dict += "), }";
  const size_t preamble = kMagicSize + 2 + 2;
  size_t total = preamble + dict.size() + 1;
  total = (total + 63) / 64 * 64;
  const size_t header_len = total - preamble;
  if (header_len > std::numeric_limits<std::uint16_t>::max())
    fail(path, "array has too many dimensions for a NumPy 1.0 header");
  dict.append(header_len - dict.size() - 1, ' ');
  dict += '\n';
  std::string out(kMagic, kMagicSize);
  out += '\x01';
  out += '\x00';
  out += static_cast<char>(header_len & 0xff);
  out += static_cast<char>(header_len >> 8);
  out += dict;
  return out;
}

template <class T>
void write_array(const std::string& path, const char* descr, const std::vector<size_t>& shape,
                 const T* data) {
  const auto count = element_count(shape, sizeof(T));
  if (!count) fail(path, "array shape is too large");
  const std::string header = npy_header(path, descr, shape);
  TVF_CHECK(*count == 0 || data != nullptr, "no data for {} elements", *count);
  write_file_atomically(fs::path(path), [&](std::ostream& out) {
    out.write(header.data(), static_cast<std::streamsize>(header.size()));
    if (*count > 0)
      out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(*count * sizeof(T)));
  });
}

// A minimal reader for the Python literal of an .npy header: a dict whose values are
// strings, True/False or tuples of non-negative integers.
class HeaderParser {
public:
  HeaderParser(const std::string& path, std::string_view text) : path_(path), s_(text) {}

  void parse(std::string& descr, std::optional<bool>& fortran, std::optional<std::vector<size_t>>& shape) {
    expect('{');
    while (true) {
      skip_space();
      if (peek() == '}') break;
      const std::string key = string_literal();
      expect(':');
      skip_space();
      if (key == "descr") {
        descr = string_literal();
      } else if (key == "fortran_order") {
        fortran = boolean();
      } else if (key == "shape") {
        shape = tuple();
      } else {
        bad("unknown key '" + key + "'");
      }
      skip_space();
      if (peek() == ',') {
        ++i_;
        continue;
      }
      skip_space();
      if (peek() != '}') bad("expected ',' or '}'");
    }
    ++i_;
    skip_space();
    if (i_ != s_.size()) bad("unexpected text after the dictionary");
  }

private:
  [[noreturn]] void bad(const std::string& what) {
    fail(path_, "bad .npy header (" + what + " at character " + std::to_string(i_) + ")");
  }
  void skip_space() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  char peek() const { return i_ < s_.size() ? s_[i_] : '\0'; }
  void expect(char c) {
    skip_space();
    if (peek() != c) bad(std::string("expected '") + c + "'");
    ++i_;
  }
  std::string string_literal() {
    skip_space();
    const char q = peek();
    if (q != '\'' && q != '"') bad("expected a string");
    const size_t end = s_.find(q, i_ + 1);
    if (end == std::string_view::npos) bad("unterminated string");
    std::string out(s_.substr(i_ + 1, end - i_ - 1));
    i_ = end + 1;
    return out;
  }
  bool boolean() {
    if (s_.substr(i_, 4) == "True") {
      i_ += 4;
      return true;
    }
    if (s_.substr(i_, 5) == "False") {
      i_ += 5;
      return false;
    }
    bad("expected True or False");
  }
  std::vector<size_t> tuple() {
    expect('(');
    std::vector<size_t> dims;
    while (true) {
      skip_space();
      if (peek() == ')') break;
      if (!std::isdigit(static_cast<unsigned char>(peek()))) bad("expected a dimension");
      size_t d = 0;
      while (std::isdigit(static_cast<unsigned char>(peek()))) {
        const auto digit = static_cast<size_t>(s_[i_] - '0');
        if (d > (std::numeric_limits<size_t>::max() - digit) / 10) bad("dimension too large");
        d = d * 10 + digit;
        ++i_;
      }
      dims.push_back(d);
      skip_space();
      if (peek() == ',') {
        ++i_;
      } else if (peek() != ')') {
        bad("expected ',' or ')'");
      }
    }
    ++i_;
    return dims;
  }

  const std::string& path_;
  std::string_view s_;
  size_t i_ = 0;
};

template <class T>
void convert(const char* bytes, size_t n, std::vector<double>& out) {
  out.resize(n);
  for (size_t k = 0; k < n; ++k) {
    T value;
    std::memcpy(&value, bytes + k * sizeof(T), sizeof(T));
    out[k] = static_cast<double>(value);
  }
}

}  // namespace

void write_npy(const std::string& path, const std::vector<size_t>& shape, const float* data) {
  write_array(path, "<f4", shape, data);
}
void write_npy(const std::string& path, const std::vector<size_t>& shape, const double* data) {
  write_array(path, "<f8", shape, data);
}
void write_npy_parts(const std::string& path, const std::vector<size_t>& shape, size_t parts,
                     const std::function<std::vector<float>(size_t)>& part) {
  const auto count = element_count(shape, sizeof(float));
  if (!count) fail(path, "array shape is too large");
  TVF_CHECK(parts > 0 ? *count % parts == 0 : *count == 0, "{} elements in {} parts", *count, parts);
  const size_t each = parts > 0 ? *count / parts : 0;
  const std::string header = npy_header(path, "<f4", shape);
  write_file_atomically(fs::path(path), [&](std::ostream& out) {
    out.write(header.data(), static_cast<std::streamsize>(header.size()));
    for (size_t k = 0; k < parts; ++k) {
      const std::vector<float> values = part(k);
      TVF_CHECK(values.size() == each, "part {} has {} values, not {}", k, values.size(), each);
      out.write(reinterpret_cast<const char*>(values.data()), static_cast<std::streamsize>(each * sizeof(float)));
    }
  });
}

void write_npy(const std::string& path, const std::vector<size_t>& shape, const std::int32_t* data) {
  write_array(path, "<i4", shape, data);
}

NpyArray read_npy(const std::string& path) {
  std::error_code ec;
  const auto file_size = fs::file_size(path, ec);
  if (ec) fail(path, "cannot read the file (" + ec.message() + ")");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open the file");

  char preamble[12];
  const size_t min_preamble = kMagicSize + 2 + 2;
  if (file_size < min_preamble || !in.read(preamble, static_cast<std::streamsize>(min_preamble)))
    fail(path, "not a NumPy .npy file (too short)");
  if (std::memcmp(preamble, kMagic, kMagicSize) != 0) fail(path, "not a NumPy .npy file (bad magic)");
  const auto major = static_cast<unsigned char>(preamble[6]);
  const auto minor = static_cast<unsigned char>(preamble[7]);
  size_t header_len = 0;
  size_t header_start = 0;
  if (major == 1 && minor == 0) {
    header_len = static_cast<unsigned char>(preamble[8]) |
                 (static_cast<size_t>(static_cast<unsigned char>(preamble[9])) << 8);
    header_start = 10;
  } else if (major == 2 && minor == 0) {
    if (!in.read(preamble + 10, 2)) fail(path, "truncated .npy header");
    header_len = 0;
    for (int k = 3; k >= 0; --k)
      header_len = (header_len << 8) | static_cast<unsigned char>(preamble[8 + k]);
    header_start = 12;
  } else {
    fail(path, "unsupported .npy format version " + std::to_string(major) + "." + std::to_string(minor));
  }
  if (header_len > file_size - header_start) fail(path, "truncated .npy header");
  std::string header(header_len, '\0');
  if (!in.read(header.data(), static_cast<std::streamsize>(header_len)))
    fail(path, "truncated .npy header");

  NpyArray array;
  std::optional<bool> fortran;
  std::optional<std::vector<size_t>> shape;
  HeaderParser(path, header).parse(array.dtype, fortran, shape);
  if (array.dtype.empty() || !fortran || !shape)
    fail(path, "bad .npy header (it needs 'descr', 'fortran_order' and 'shape')");
  size_t item = 0;
  if (array.dtype == "<f4") item = 4;
  else if (array.dtype == "<f8") item = 8;
  else if (array.dtype == "<i4") item = 4;
  else fail(path, "unsupported .npy dtype '" + array.dtype + "' (expected <f4, <f8 or <i4)");
  if (*fortran) fail(path, "Fortran-order .npy arrays are not supported");
  array.shape = *shape;

  const auto count = element_count(array.shape, item);
  const size_t data_start = header_start + header_len;
  if (!count || *count > (file_size - data_start) / item || *count * item != file_size - data_start)
    fail(path, fmt::format("size does not match its header: shape needs {} bytes of data, the file "
                           "holds {}",
                           count ? std::to_string(*count * item) : std::string("too many"),
                           file_size - data_start));
  std::vector<char> bytes(*count * item);
  if (!bytes.empty() && !in.read(bytes.data(), static_cast<std::streamsize>(bytes.size())))
    fail(path, "cannot read the array data");
  if (array.dtype == "<f4") convert<float>(bytes.data(), *count, array.values);
  else if (array.dtype == "<f8") convert<double>(bytes.data(), *count, array.values);
  else convert<std::int32_t>(bytes.data(), *count, array.values);
  return array;
}

}  // namespace tvf
