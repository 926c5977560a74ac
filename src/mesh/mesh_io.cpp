#include "tvf/mesh/mesh_io.h"

#include "tvf/core/atomic_output.h"
#include "tvf/core/error.h"

// CGAL stays inside this file (compile time). The per-format readers and writers are
// called directly: we choose the format from the extension ourselves, and save_mesh
// writes to a temporary name whose extension is not the format's.
#include <CGAL/IO/OBJ.h>
#include <CGAL/IO/OFF.h>
#include <CGAL/IO/PLY.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <charconv>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace tvf {

namespace fs = std::filesystem;

namespace {

// A decimal number as the mesh formats write them ("1", "-0.5", "+2e-3"), the whole word:
// std::from_chars rather than strtod, which also takes hexadecimal ("0x1p3") and follows
// the locale; the three readers then accept the same numbers ("inf" and "nan" still parse,
// and the callers refuse what is not finite).
bool parse_decimal(const std::string& word, double& x) {
  const char* first = word.data();
  const char* last = first + word.size();
  if (first != last && *first == '+') {  // from_chars takes a minus sign only
    ++first;
    if (first != last && (*first == '+' || *first == '-')) return false;
  }
  const auto [end, error] = std::from_chars(first, last, x, std::chars_format::general);
  if (end != last || first == last) return false;
  // Out of range ("1e999", "1e-999"): a decimal all the same; strtod gives its value
  // (± infinity, which the callers refuse, or a number rounded towards 0).
  if (error == std::errc::result_out_of_range) x = std::strtod(std::string(first, last).c_str(), nullptr);
  return error == std::errc();
}

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;

// A polygon as CGAL's readers fill it, refusing absurd sizes: a corrupt OFF face line
// ("9e12 0 1 2") would otherwise make the reader allocate terabytes before it notices
// the missing indices.
inline constexpr std::size_t kMaxPolygonCorners = std::size_t{1} << 20;
struct Polygon : std::vector<std::size_t> {
  void resize(std::size_t n) {
    if (n > kMaxPolygonCorners) throw std::length_error("polygon too large");
    std::vector<std::size_t>::resize(n);
  }
};

enum class Format { obj, ply, off };

const char* format_name(Format f) {
  switch (f) {
    case Format::obj: return "OBJ";
    case Format::ply: return "PLY";
    case Format::off: return "OFF";
  }
  return "";
}

Format format_of(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".obj") return Format::obj;
  if (ext == ".ply") return Format::ply;
  if (ext == ".off") return Format::off;
  throw_input_error(path, "",
                    ext.empty()
                        ? "the file name has no extension; a mesh must be .obj, .ply or .off"
                        : fmt::format("unknown mesh format '{}'; a mesh must be .obj, .ply "
                                      "or .off",
                                      ext));
}

// When CGAL's OBJ reader gives up, find the line it stumbled on (it says nothing itself).
// Returns "" when no line looks wrong.
std::string diagnose_obj(const std::string& path) {
  static const char* const known[] = {
      "v",        "vt",         "vn",        "vp",   "f",      "o",        "g",      "s",
      "usemtl",   "mtllib",     "bevel",     "lod",  "ctech",  "c_interp", "usemap", "stech",
      "d_interp", "shadow_obj", "trace_obj", "p",    "cstype", "deg",      "step",   "bmat",
      "con",      "curv",       "curv2",     "surf", "parm",   "trim",     "hole",   "scrv",
      "sp",       "end",        "surf_1",    "q0_1", "q1_1",   "curv2d_1", "surf_2", "q0_2",
      "q1_2",     "curv2d_2",   "bsp",       "bzp",  "cdc",    "cdp",      "res"};
  std::ifstream in(path, std::ios::binary);
  std::string line;
  long long vertices = 0, faces = 0;
  for (long long number = 1; std::getline(in, line); ++number) {
    std::istringstream words(line);
    std::string keyword;
    if (!(words >> keyword) || keyword.front() == '#') continue;
    vertices += keyword == "v" ? 1 : 0;
    faces += keyword == "f" ? 1 : 0;
    auto quoted = [&] {
      std::string l = line.size() > 60 ? line.substr(0, 57) + "..." : line;
      if (!l.empty() && l.back() == '\r') l.pop_back();
      return l;
    };
    if (keyword == "v") {
      int coordinates = 0;
      std::string word;
      for (; coordinates < 3 && words >> word; ++coordinates) {
        double x = 0;
        if (!parse_decimal(word, x) || !std::isfinite(x)) break;
      }
      if (coordinates < 3)
        return fmt::format("line {}: the vertex '{}' does not have three finite coordinates",
                           number, quoted());
    } else if (keyword == "f") {
      // Each corner "v", "v/vt", "v//vn" or "v/vt/vn": v a vertex number, 1-based, or
      // negative counting back from the last vertex read.
      std::string word;
      while (words >> word) {
        const std::string index = word.substr(0, word.find('/'));
        char* end = nullptr;
        errno = 0;
        const long long v = std::strtoll(index.c_str(), &end, 10);
        if (index.empty() || end != index.c_str() + index.size() || errno == ERANGE || v == 0 ||
            v > vertices || v < -vertices)
          return fmt::format("line {}: the face corner '{:.40}' is not a vertex number in 1 to {} (or -1 to -{}) "
                             "of the vertices read before it",
                             number, word, vertices, vertices);
      }
    } else if (std::find_if(std::begin(known), std::end(known),
                            [&](const char* k) { return keyword == k; }) == std::end(known)) {
      return fmt::format("line {}: '{}' is not an OBJ statement that tvf reads", number, quoted());
    }
  }
  if (vertices == 0) return "the file has no vertices ('v' lines)";
  if (faces == 0) return "the file has no faces ('f' lines)";
  return "";
}

[[noreturn]] void fail_unreadable(const std::string& path, Format format) {
  if (format == Format::obj) {
    const std::string line = diagnose_obj(path);
    if (!line.empty()) throw_input_error(path, "", line);
  }
  throw_input_error(path, "",
                    fmt::format("the file is not a readable {} mesh (malformed or truncated)",
                                format_name(format)));
}

// The element counts that a header announces must fit in the file (every element takes at
// least one byte), so that a corrupt header cannot make the reader allocate without bound.
void check_count(const std::string& path, Format format, long long count, const char* what,
                 std::uintmax_t file_size) {
  if (count < 0 || static_cast<std::uintmax_t>(count) > file_size)
    throw_input_error(path, "",
                      fmt::format("the {} header announces {} {}, more than the file can hold "
                                  "(corrupt or truncated file)",
                                  format_name(format), count, what));
}

// The counts of a binary OFF header, read here rather than by CGAL, whose header reader
// computes with them in int before anyone could check them. Each must fit in the file.
// (Text OFF is read by read_off_text below.)
void check_off_header(const std::string& path, std::istream& in, std::uintmax_t file_size) {
  auto unreadable = [&] { fail_unreadable(path, Format::off); };
  // The next word, skipping '#' comments to the end of their line.
  auto word = [&](std::string& w) {
    for (;;) {
      if (!(in >> w)) unreadable();
      const auto hash = w.find('#');
      if (hash == std::string::npos) return;
      // A comment glued to a word ("COFF#4") is read differently by CGAL (found by
      // fuzzing: it then ran past its colour buffer): refused.
      if (hash > 0)
        throw_input_error(path, "", fmt::format("the OFF header's '{:.40}' has a comment glued to it (put a space "
                                                "before '#')",
                                                w));
      std::string rest;
      std::getline(in, rest);
    }
  };
  std::string keyword;
  word(keyword);
  // [ST][C][N][4][n]OFF, optionally followed by BINARY.
  if (keyword.size() < 3 || keyword.compare(keyword.size() - 3, 3, "OFF") != 0) unreadable();
  const bool dimensional = keyword.find('n') != std::string::npos;
  const int numbers = dimensional ? 4 : 3;
  std::vector<long long> counts;
  std::string w;
  word(w);
  if (w == "BINARY") {
    std::string rest;
    std::getline(in, rest);
    for (int k = 0; k < numbers; ++k) {
      unsigned char b[4];
      if (!in.read(reinterpret_cast<char*>(b), 4)) unreadable();
      const auto u = (std::uint32_t{b[0]} << 24) | (std::uint32_t{b[1]} << 16) |
                     (std::uint32_t{b[2]} << 8) | std::uint32_t{b[3]};
      counts.push_back(static_cast<std::int32_t>(u));
    }
  } else {
    for (int k = 0; k < numbers; ++k) {
      if (k > 0) word(w);
      std::size_t used = 0;
      long long value = 0;
      try {
        value = std::stoll(w, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used == 0 || used != w.size()) unreadable();
      counts.push_back(value);
    }
  }
  if (dimensional && (counts[0] < 0 || counts[0] > 64)) unreadable();
  const size_t first = dimensional ? 1 : 0;
  check_count(path, Format::off, counts[first], "vertices", file_size);
  check_count(path, Format::off, counts[first + 1], "faces", file_size);
  check_count(path, Format::off, counts[first + 2], "edges", file_size);
}

// --- Text OFF: our own reader ----------------------------------------------------------
//
// CGAL's OFF reader ran past its buffers twice under fuzzing (colour values counted on the
// first vertex line and read on every other; a face line of no corners and two colour
// values), and its header arithmetic is done in int before anything can be checked. Text
// OFF is simple enough to read strictly here: every error names the file and the line.
// Binary OFF still goes to CGAL, after check_off_header.

// The lines of a text OFF file, comments ('#' to the end of the line) and blank lines skipped.
class OffLines {
public:
  OffLines(const std::string& path, std::istream& in) : path_(path), in_(in) {}
  // The next line with words, split; false at the end of the file.
  bool next(std::vector<std::string>& words) {
    std::string line;
    while (std::getline(in_, line)) {
      ++number_;
      line = line.substr(0, line.find('#'));
      words.clear();
      std::istringstream split(line);
      for (std::string w; split >> w;) words.push_back(std::move(w));
      if (!words.empty()) return true;
    }
    return false;
  }
  long long number() const { return number_; }
  [[noreturn]] void fail(const std::string& what) const {
    throw_input_error(path_, "", fmt::format("line {}: {}", number_, what));
  }
  // A finite number, or an error naming `what` (a vertex, a face).
  double number_of(const std::string& word, const std::string& what) const {
    double x = 0;
    if (!parse_decimal(word, x))
      fail(fmt::format("{}: '{:.40}' is not a number", what, word));
    if (!std::isfinite(x)) fail(fmt::format("{}: '{:.40}' is not a finite number", what, word));
    return x;
  }

private:
  const std::string& path_;
  std::istream& in_;
  long long number_ = 0;
};

// Reads a text OFF file into points and polygons. Returns false, having read nothing, when
// the file is binary OFF ("OFF BINARY"). The header is the keyword [ST][C][N][4][n]OFF, the
// dimension after it for nOFF (3 only), and the counts of vertices, faces and edges (on
// the keyword's line or after it, nothing after them on their line); each count must fit
// in the file. Then one vertex per line: x y z (x y z w with '4', divided by w), then any
// normal, colour and texture values, every vertex line giving as many numbers as the
// first, colours (after the coordinates and any normal) in [0, 255]; then one face per
// line: a corner count k ≥ 3, k vertex numbers in range, then nothing, a colour index, RGB
// or RGBA in [0, 255]. Lines after the faces (edges) are not read, but must hold numbers
// only.
bool read_off_text(const std::string& path, std::istream& in, std::uintmax_t file_size, std::vector<Point>& points,
                   std::vector<Polygon>& polygons) {
  OffLines lines(path, in);
  std::vector<std::string> words;
  if (!lines.next(words)) throw_input_error(path, "", "the file has only comments and blank lines: not a readable OFF mesh");
  const std::string keyword = words[0];
  if (keyword.size() < 3 || keyword.compare(keyword.size() - 3, 3, "OFF") != 0 ||
      keyword.substr(0, keyword.size() - 3).find_first_not_of("STCN4n") != std::string::npos)
    lines.fail(fmt::format("'{:.40}' is not an OFF keyword ([ST][C][N][4][n]OFF): not a readable OFF mesh", keyword));
  if (words.size() > 1 && words[1] == "BINARY") return false;
  const std::string prefix = keyword.substr(0, keyword.size() - 3);
  const bool homogeneous = prefix.find('4') != std::string::npos;
  const bool dimensional = prefix.find('n') != std::string::npos;
  const bool coloured = prefix.find('C') != std::string::npos;
  // The header's numbers: the dimension (nOFF), then the three counts.
  std::vector<long long> header;
  std::size_t at = 1;
  const std::size_t wanted = dimensional ? 4 : 3;
  while (header.size() < wanted) {
    if (at == words.size()) {
      if (!lines.next(words)) lines.fail("the OFF file ends in its header, before the counts of vertices, faces and edges");
      at = 0;
    }
    const std::string& w = words[at++];
    std::size_t used = 0;
    long long value = 0;
    try {
      value = std::stoll(w, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != w.size())
      lines.fail(fmt::format("the OFF header's '{:.40}' is not a whole number (the header gives the counts of "
                             "vertices, faces and edges)",
                             w));
    header.push_back(value);
  }
  if (at != words.size())
    lines.fail(fmt::format("the OFF counts line goes on after its counts ('{:.40}')", words[at]));
  if (dimensional && header[0] != 3)
    lines.fail(fmt::format("the nOFF dimension is {}; tvf reads vertices of 3 coordinates", header[0]));
  const std::size_t first = dimensional ? 1 : 0;
  const long long nv = header[first], nf = header[first + 1];
  check_count(path, Format::off, nv, "vertices", file_size);
  check_count(path, Format::off, nf, "faces", file_size);
  check_count(path, Format::off, header[first + 2], "edges", file_size);

  const std::size_t coordinates = homogeneous ? 4 : 3;
  const std::size_t colour_from = coordinates + (prefix.find('N') != std::string::npos ? 3u : 0u);
  std::size_t expected = 0;
  points.reserve(static_cast<std::size_t>(nv));
  for (long long v = 0; v < nv; ++v) {
    if (!lines.next(words))
      lines.fail(fmt::format("the OFF file ends before vertex {} of the {} its header announces", v, nv));
    const std::string what = fmt::format("OFF vertex {}", v);
    std::vector<double> x;
    x.reserve(words.size());
    for (const std::string& w : words) {
      x.push_back(lines.number_of(w, what));
      // Colours, after the coordinates and any normal.
      if (coloured && x.size() > colour_from && !(x.back() >= 0 && x.back() <= 255))
        lines.fail(fmt::format("{}: the colour value {:.40} is outside [0, 255]", what, w));
    }
    if (x.size() < coordinates)
      lines.fail(fmt::format("{} has {} numbers; a vertex needs at least {}", what, x.size(), coordinates));
    if (expected == 0) expected = x.size();
    if (x.size() != expected)
      lines.fail(fmt::format("{} has {} numbers where vertex 0 has {} (every vertex line of an OFF file gives the "
                             "same values)",
                             what, x.size(), expected));
    const double w = homogeneous ? x[3] : 1.0;
    if (w == 0) lines.fail(fmt::format("{}: the homogeneous coordinate w is 0", what));
    points.emplace_back(x[0] / w, x[1] / w, x[2] / w);
  }
  polygons.reserve(static_cast<std::size_t>(nf));
  for (long long f = 0; f < nf; ++f) {
    if (!lines.next(words))
      lines.fail(fmt::format("the OFF file ends before face {} of the {} its header announces", f, nf));
    const std::string what = fmt::format("OFF face {}", f);
    std::vector<double> values;
    values.reserve(words.size());
    for (const std::string& w : words) values.push_back(lines.number_of(w, what));
    const double k = values[0];
    if (!(k >= 0) || k != std::floor(k) || k > static_cast<double>(values.size() - 1))
      lines.fail(fmt::format("{}: the corner count {} does not match the line", what, k));
    if (k < 3) lines.fail(fmt::format("{} has {} corners; a face needs at least 3", what, k));
    Polygon poly;
    poly.resize(static_cast<std::size_t>(k));
    for (std::size_t c = 1; c <= static_cast<std::size_t>(k); ++c) {
      if (!(values[c] >= 0) || values[c] != std::floor(values[c]) || values[c] >= static_cast<double>(nv))
        lines.fail(fmt::format("{}: {} is not a vertex number in 0 to {}", what, values[c], nv - 1));
      poly[c - 1] = static_cast<std::size_t>(values[c]);
    }
    // After the corners, a face may give a colour: an index, RGB or RGBA in [0, 255].
    const std::size_t extra = values.size() - 1 - static_cast<std::size_t>(k);
    if (extra != 0 && extra != 1 && extra != 3 && extra != 4)
      lines.fail(fmt::format("{}: {} values follow the corners, where a colour has 1, 3 or 4", what, extra));
    for (std::size_t c = values.size() - extra; c < values.size(); ++c)
      if (!(values[c] >= 0 && values[c] <= 255))
        lines.fail(fmt::format("{}: the colour value {} is outside [0, 255]", what, values[c]));
    polygons.push_back(std::move(poly));
  }
  // What follows the faces is not read (edges, or faces beyond the count, as CGAL reads
  // it: CGAL's own prim.off announces 7 faces and lists 8), but it must be numbers.
  while (lines.next(words))
    for (const std::string& w : words) (void)lines.number_of(w, fmt::format("after the {} faces", nf));
  return true;
}

// Bytes of a PLY scalar type, or 0 when the name is not one.
int ply_type_size(const std::string& t) {
  if (t == "char" || t == "int8" || t == "uchar" || t == "uint8") return 1;
  if (t == "short" || t == "int16" || t == "ushort" || t == "uint16") return 2;
  if (t == "int" || t == "int32" || t == "uint" || t == "uint32" || t == "float" || t == "float32")
    return 4;
  if (t == "double" || t == "float64") return 8;
  return 0;
}

// A PLY header as far as the body check needs it.
struct PlyProperty {
  int bytes = 0;        // a scalar's size, or a list's count's size
  bool list = false;
  bool signed_count = false;
  int index_bytes = 0;  // a list item's size
};
struct PlyElement {
  std::string name;
  long long count = 0;
  std::vector<PlyProperty> properties;
};
struct PlyLayout {
  std::string encoding;  // ascii, binary_little_endian or binary_big_endian
  std::vector<PlyElement> elements;
};

bool ply_signed(const std::string& t) { return t == "char" || t == "int8" || t == "short" || t == "int16" || t == "int" || t == "int32"; }

// CGAL's PLY reader trusts its header: a property before any element crashes it, an
// element whose properties it does not know makes it loop over the announced count
// without reading, and counts are used as given. So the header is checked first: known
// types only, and every element's items must fit in the file (at least the size of their
// scalars, or two characters per property in ASCII), which bounds what reading allocates.
// Leaves `in` at the first byte of the body.
PlyLayout check_ply_header(const std::string& path, std::istream& in, std::uintmax_t file_size) {
  auto corrupt = [&](const std::string& what) {
    throw_input_error(path, "", fmt::format("the PLY header {} (corrupt file)", what));
  };
  PlyLayout layout;
  std::string line;
  bool binary = false;
  std::uintmax_t item_bytes = 0;
  auto finish_element = [&] {
    if (layout.elements.empty()) return;
    const PlyElement& e = layout.elements.back();
    if (e.count == 0) return;
    if (item_bytes == 0)
      corrupt(fmt::format("declares {} '{}' items without any property", e.count, e.name));
    if (static_cast<std::uintmax_t>(e.count) > (file_size + 1) / item_bytes)
      corrupt(fmt::format("announces {} '{}' items, more than the file can hold", e.count, e.name));
  };
  for (long long number = 1; std::getline(in, line); ++number) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (number == 1) {
      if (keyword != "ply") fail_unreadable(path, Format::ply);
      continue;
    }
    if (number == 2) {
      std::string encoding;
      words >> encoding;
      if (keyword != "format" || (encoding != "ascii" && encoding != "binary_little_endian" &&
                                  encoding != "binary_big_endian"))
        fail_unreadable(path, Format::ply);
      binary = encoding != "ascii";
      layout.encoding = encoding;
      continue;
    }
    if (keyword == "element") {
      finish_element();
      std::string count_text, element;
      words >> element >> count_text;
      std::size_t used = 0;
      long long count = 0;
      try {
        count = std::stoll(count_text, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (element.empty() || used == 0 || used != count_text.size() || count < 0)
        corrupt(fmt::format("has a malformed element line '{}'", line));
      layout.elements.push_back({element, count, {}});
      item_bytes = 0;
    } else if (keyword == "property") {
      if (layout.elements.empty()) corrupt(fmt::format("has the property '{}' before any element", line));
      std::string type, size_type, index_type;
      words >> type;
      PlyProperty property;
      if (type == "list") {
        words >> size_type >> index_type;
        const bool integer_size = size_type != "float" && size_type != "float32" &&
                                  size_type != "double" && size_type != "float64";
        property.list = true;
        property.bytes = integer_size && ply_type_size(index_type) > 0 ? ply_type_size(size_type) : 0;
        property.signed_count = ply_signed(size_type);
        property.index_bytes = ply_type_size(index_type);
      } else {
        property.bytes = ply_type_size(type);
      }
      if (property.bytes == 0) corrupt(fmt::format("has the property '{}' of an unknown type", line));
      item_bytes += binary ? static_cast<std::uintmax_t>(property.bytes) : 2;
      layout.elements.back().properties.push_back(property);
    } else if (keyword == "end_header") {
      finish_element();
      return layout;
    }
  }
  fail_unreadable(path, Format::ply);
}

// The body against the header, before CGAL reads it: every item present, and every list's
// count read and checked against what is left of the file before the list is skipped.
// CGAL's reader does not check its reads: in a truncated file it used a list count it never
// read (uninitialised memory) and allocated by it.
void check_ply_body(const std::string& path, std::istream& in, const PlyLayout& layout, std::uintmax_t file_size) {
  auto truncated = [&](const PlyElement& e, long long item, const std::string& why) {
    throw_input_error(path, "",
                      fmt::format("PLY '{}' item {} of {}: {} (truncated or corrupt file)", e.name, item, e.count, why));
  };
  const std::streamoff start = in.tellg();
  if (start < 0) fail_unreadable(path, Format::ply);
  std::uintmax_t left = file_size - static_cast<std::uintmax_t>(start);
  if (layout.encoding == "ascii") {
    std::string word;
    for (const PlyElement& e : layout.elements) {
      for (long long item = 0; item < e.count; ++item) {
        for (const PlyProperty& p : e.properties) {
          if (!(in >> word)) truncated(e, item, "the file ends inside it");
          double x = 0;
          if (!parse_decimal(word, x)) truncated(e, item, fmt::format("'{:.40}' is not a number", word));
          if (!p.list) continue;
          if (!(x >= 0) || x != std::floor(x) || x > static_cast<double>(file_size))
            truncated(e, item, fmt::format("the list count {:.40} is not a count the file can hold", word));
          for (long long k = 0; k < static_cast<long long>(x); ++k) {
            if (!(in >> word)) truncated(e, item, "the file ends inside a list");
            double entry = 0;
            if (!parse_decimal(word, entry))
              truncated(e, item, fmt::format("'{:.40}' is not a number", word));
          }
        }
      }
    }
    return;
  }
  const bool big = layout.encoding == "binary_big_endian";
  for (const PlyElement& e : layout.elements) {
    const bool scalars_only = std::none_of(e.properties.begin(), e.properties.end(),
                                           [](const PlyProperty& p) { return p.list; });
    if (scalars_only) {
      std::uintmax_t item = 0;
      for (const PlyProperty& p : e.properties) item += static_cast<std::uintmax_t>(p.bytes);
      const auto count = static_cast<std::uintmax_t>(e.count);
      if (item > 0 && count > left / item) truncated(e, static_cast<long long>(left / item), "the file ends inside it");
      left -= count * item;
      in.seekg(static_cast<std::streamoff>(count * item), std::ios::cur);
      continue;
    }
    for (long long item = 0; item < e.count; ++item) {
      for (const PlyProperty& p : e.properties) {
        const auto bytes = static_cast<std::uintmax_t>(p.bytes);
        if (bytes > left) truncated(e, item, "the file ends inside it");
        left -= bytes;
        if (!p.list) {
          in.seekg(static_cast<std::streamoff>(bytes), std::ios::cur);
          continue;
        }
        unsigned char b[8] = {};
        if (!in.read(reinterpret_cast<char*>(b), static_cast<std::streamsize>(bytes)))
          truncated(e, item, "the file ends inside it");
        std::uint64_t u = 0;
        for (std::size_t k = 0; k < bytes; ++k) {
          const std::size_t at = big ? k : bytes - 1 - k;
          u = (u << 8) | b[at];
        }
        const bool negative = p.signed_count && (b[big ? 0 : bytes - 1] & 0x80) != 0;
        if (negative) truncated(e, item, "a list count is negative");
        const auto index_bytes = static_cast<std::uint64_t>(p.index_bytes);
        if (u > left / index_bytes)
          truncated(e, item, fmt::format("a list of {} entries does not fit in the {} bytes left", u, left));
        left -= u * index_bytes;
        in.seekg(static_cast<std::streamoff>(u * index_bytes), std::ios::cur);
      }
    }
  }
}

}  // namespace

LoadedMesh load_mesh(const std::string& path) {
  const Format format = format_of(path);
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status))
    throw_input_error(path, "", ec && ec != std::errc::no_such_file_or_directory
                                    ? "the mesh file cannot be used: " + ec.message()
                                    : std::string("the mesh file does not exist"));
  if (fs::is_directory(status))
    throw_input_error(path, "", "the path is a folder, not a mesh file");
  const std::uintmax_t file_size = fs::file_size(path, ec);
  if (ec) throw_input_error(path, "", fmt::format("cannot read the file ({})", ec.message()));
  if (file_size == 0) throw_input_error(path, "", "the mesh file is empty");

  std::vector<Point> points;
  std::vector<Polygon> polygons;
  try {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw_input_error(path, "", "cannot open the mesh file for reading");
    auto np = CGAL::parameters::verbose(false);
    bool ok = false;
    switch (format) {
      case Format::obj: {
        // CGAL's OBJ reader separates face indices by spaces only; tabs are legal too.
        std::string text(static_cast<size_t>(file_size), '\0');
        in.read(text.data(), static_cast<std::streamsize>(text.size()));
        text.resize(static_cast<size_t>(in.gcount()));
        std::replace(text.begin(), text.end(), '\t', ' ');
        std::istringstream obj(std::move(text));
        CGAL::IO::set_mode(obj, CGAL::IO::ASCII);
        ok = CGAL::IO::read_OBJ(obj, points, polygons, np);
        break;
      }
      case Format::off:
        ok = read_off_text(path, in, file_size, points, polygons);
        if (!ok) {  // binary OFF: CGAL reads it, its header counts checked first
          in.clear();
          in.seekg(0);
          check_off_header(path, in, file_size);
          in.clear();
          in.seekg(0);
          ok = CGAL::IO::read_OFF(in, points, polygons, np);
        }
        break;
      case Format::ply: {
        const PlyLayout layout = check_ply_header(path, in, file_size);
        check_ply_body(path, in, layout, file_size);
        in.clear();
        in.seekg(0);
        CGAL::IO::set_mode(in, CGAL::IO::BINARY);
        ok = CGAL::IO::read_PLY(in, points, polygons, np);
        break;
      }
    }
    if (!ok) fail_unreadable(path, format);
  } catch (const Error&) {
    throw;
  } catch (const std::bad_alloc&) {
    throw_input_error(path, "", "the mesh file is too large to read into memory");
  } catch (const std::exception&) {
    fail_unreadable(path, format);
  }

  if (points.empty()) throw_input_error(path, "", "the mesh file has no vertices");
  if (points.size() > static_cast<size_t>(std::numeric_limits<int>::max()))
    throw_input_error(path, "",
                      fmt::format("the mesh has {} vertices, more than the supported {}",
                                  points.size(), std::numeric_limits<int>::max()));
  std::vector<Vec3> positions;
  positions.reserve(points.size());
  for (const Point& p : points) positions.emplace_back(p.x(), p.y(), p.z());
  points = {};

  std::vector<Face> faces;
  faces.reserve(polygons.size());
  for (size_t i = 0; i < polygons.size(); ++i) {
    const Polygon& poly = polygons[i];
    if (poly.size() < 3 && format == Format::obj) {
      // CGAL stops reading a face at an index it cannot read (2^31, say): name that line.
      const std::string line = diagnose_obj(path);
      if (!line.empty()) throw_input_error(path, "", line);
    }
    if (poly.size() < 3)
      throw_input_error(path, "",
                        fmt::format("polygon {} has {} corner{}; a face needs at least 3", i,
                                    poly.size(), poly.size() == 1 ? "" : "s"));
    for (std::size_t v : poly)
      if (v >= positions.size())
        throw_input_error(path, "",
                          fmt::format("polygon {} uses vertex {}, but the vertices are numbered "
                                      "0 to {}",
                                      i, static_cast<long long>(v), positions.size() - 1));
    // Fan triangulation (planar convex polygons are expected).
    for (size_t k = 1; k + 1 < poly.size(); ++k)
      faces.push_back(
          {static_cast<int>(poly[0]), static_cast<int>(poly[k]), static_cast<int>(poly[k + 1])});
  }
  polygons = {};

  LoadedMesh result;
  result.repairs = repair_triangle_soup(positions, faces);
  result.mesh = Mesh(std::move(positions), std::move(faces), path);
  return result;
}

void save_mesh(const Mesh& mesh, const std::string& path) {
  const Format format = format_of(path);
  std::vector<Point> points;
  points.reserve(static_cast<size_t>(mesh.num_vertices()));
  for (const Vec3& p : mesh.positions()) points.emplace_back(p.x(), p.y(), p.z());
  std::vector<std::array<int, 3>> polygons(mesh.faces().begin(), mesh.faces().end());

  write_file_atomically(path, [&](std::ostream& out) {
    // Enough digits that every double reads back exactly.
    out.precision(std::numeric_limits<double>::max_digits10);
    bool ok = false;
    switch (format) {
      case Format::obj:
        CGAL::IO::set_mode(out, CGAL::IO::ASCII);
        ok = CGAL::IO::write_OBJ(out, points, polygons);
        break;
      case Format::off:
        CGAL::IO::set_mode(out, CGAL::IO::ASCII);
        ok = CGAL::IO::write_OFF(out, points, polygons);
        break;
      case Format::ply:
        CGAL::IO::set_mode(out, CGAL::IO::BINARY);
        ok = CGAL::IO::write_PLY(out, points, polygons);
        break;
    }
    if (!ok) throw_input_error(path, "", "cannot write the mesh file");
  });
}

}  // namespace tvf
