#include "tvf/core/json_text.h"

#include "tvf/core/error.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <utility>
#include <vector>

namespace tvf {
namespace {

using json = nlohmann::json;

std::string join_key(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

// Builds the DOM like nlohmann's own parser, refusing repeated keys and nesting deeper
// than kMaxJsonDepth, and remembers where a parse error happened. Each open container
// keeps only the key it was stored under: the JSON path is put together when it is
// reported, so memory stays linear in the text however deep it nests.
class DomBuilder : public nlohmann::json_sax<json> {
public:
  explicit DomBuilder(json& root) : root_(root) {}

  bool null() override { return add(nullptr); }
  bool boolean(bool v) override { return add(v); }
  bool number_integer(number_integer_t v) override { return add(v); }
  bool number_unsigned(number_unsigned_t v) override { return add(v); }
  bool number_float(number_float_t v, const string_t&) override { return add(v); }
  bool string(string_t& v) override { return add(std::move(v)); }
  bool binary(binary_t& v) override { return add(json::binary(std::move(v))); }
  bool start_object(std::size_t) override { return open(json::object()); }
  bool key(string_t& k) override {
    if (stack_.back().value->contains(k)) {
      duplicate_ = join_key(path(), k);
      return false;
    }
    key_ = k;
    return true;
  }
  bool end_object() override { return close(); }
  bool start_array(std::size_t) override { return open(json::array()); }
  bool end_array() override { return close(); }
  bool parse_error(std::size_t position, const std::string&,
                   const nlohmann::detail::exception& ex) override {
    error_position_ = position;
    error_id_ = ex.id;
    error_text_ = ex.what();
    error_path_ = value_path();
    return false;
  }

  const std::string& duplicate() const { return duplicate_; }
  bool too_deep() const { return too_deep_; }
  std::size_t error_position() const { return error_position_; }
  int error_id() const { return error_id_; }
  const std::string& error_text() const { return error_text_; }
  // The JSON path of the value being read when the error happened ("time.frames").
  const std::string& error_path() const { return error_path_; }

private:
  struct Open {
    json* value;
    std::string key;  // the key it is stored under in an object parent
  };
  json& root_;
  std::vector<Open> stack_;
  std::string key_;
  std::string duplicate_;
  bool too_deep_ = false;
  std::size_t error_position_ = 0;
  int error_id_ = 0;
  std::string error_text_;
  std::string error_path_;

  // The JSON path of the value being read: the innermost container's, with the key or
  // index the value would take there.
  std::string value_path() const {
    if (stack_.empty()) return "";
    const json& top = *stack_.back().value;
    return top.is_array() ? fmt::format("{}[{}]", path(), top.size()) : join_key(path(), key_);
  }

  // The JSON path of the innermost open container.
  std::string path() const {
    std::string p;
    for (std::size_t i = 1; i < stack_.size(); ++i) {
      const json& parent = *stack_[i - 1].value;
      if (parent.is_array())
        p += fmt::format("[{}]", parent.size() - 1);  // (not "[" + …: GCC 12 warns falsely there)
      else
        p = join_key(p, stack_[i].key);
    }
    return p;
  }
  json* insert(json&& v) {
    if (stack_.empty()) {
      root_ = std::move(v);
      return &root_;
    }
    json& parent = *stack_.back().value;
    if (parent.is_array()) {
      parent.push_back(std::move(v));
      return &parent.back();
    }
    json& slot = parent[key_];
    slot = std::move(v);
    return &slot;
  }
  bool add(json&& v) {
    insert(std::move(v));
    return true;
  }
  bool open(json&& v) {
    if (stack_.size() >= kMaxJsonDepth) {
      too_deep_ = true;
      return false;
    }
    const bool in_object = !stack_.empty() && stack_.back().value->is_object();
    std::string key = in_object ? key_ : std::string();
    stack_.push_back({insert(std::move(v)), std::move(key)});
    return true;
  }
  bool close() {
    stack_.pop_back();
    return true;
  }
};

// 1-based line and column (in code points) of the byte at `index` (0-based).
std::pair<std::size_t, std::size_t> line_and_column(const std::string& text, std::size_t index) {
  index = std::min(index, text.size());
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i < index; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == '\n') {
      ++line;
      column = 1;
    } else if ((c & 0xC0) != 0x80) {
      ++column;
    }
  }
  return {line, column};
}

// Index of the bracket that opens level kMaxJsonDepth + 1 (strings skipped).
std::size_t too_deep_index(const std::string& text) {
  std::size_t depth = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\')
        ++i;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxJsonDepth) return i;
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
  return text.size();
}

bool is_word_char(char c) { return std::isalpha(static_cast<unsigned char>(c)) != 0; }

[[noreturn]] void fail_at(const std::string& text, std::size_t index, const std::string& label,
                          const std::string& message, const std::string& json_path = "") {
  const auto [line, col] = line_and_column(text, index);
  ErrorLocation location;
  location.file = label;
  location.json_path = json_path;
  location.line = static_cast<int>(line);
  location.column = static_cast<int>(col);
  const std::string where = json_path.empty() ? fmt::format("line {}, column {}", line, col)
                                              : fmt::format("{} (line {}, column {})", json_path, line, col);
  throw_located_error(where, message, std::move(location));
}

// One step of a JSON path: a key, or an index.
struct PathStep {
  std::string key;
  std::size_t index = 0;
  bool is_index = false;
};

// Splits "a.b[2].c" into steps; false for a path tvf would not write.
bool split_path(const std::string& path, std::vector<PathStep>& steps) {
  std::size_t i = 0;
  while (i < path.size()) {
    if (path[i] == '[') {
      const std::size_t close = path.find(']', i);
      if (close == std::string::npos || close == i + 1) return false;
      PathStep s;
      s.is_index = true;
      for (std::size_t k = i + 1; k < close; ++k) {
        if (path[k] < '0' || path[k] > '9') return false;
        s.index = s.index * 10 + static_cast<std::size_t>(path[k] - '0');
      }
      steps.push_back(s);
      i = close + 1;
      if (i < path.size() && path[i] == '.') ++i;
      continue;
    }
    std::size_t end = i;
    while (end < path.size() && path[end] != '.' && path[end] != '[') ++end;
    if (end == i) return false;
    steps.push_back({path.substr(i, end - i), 0, false});
    i = end < path.size() && path[end] == '.' ? end + 1 : end;
  }
  return true;
}

// A scanner over JSON text that has already parsed: it finds where values start.
class PathScanner {
public:
  explicit PathScanner(const std::string& text) : t_(text) {}

  // Index of the value at `steps` (from the value starting at `i`), or npos.
  std::size_t find(std::size_t i, const std::vector<PathStep>& steps, std::size_t depth) {
    i = skip_space(i);
    if (depth == steps.size()) return i;
    if (i >= t_.size()) return std::string::npos;
    const PathStep& step = steps[depth];
    if (t_[i] == '{' && !step.is_index) {
      i = skip_space(i + 1);
      while (i < t_.size() && t_[i] == '"') {
        const std::size_t key_end = skip_string(i);
        const std::string key = unescaped(i, key_end);
        i = skip_space(key_end);
        if (i >= t_.size() || t_[i] != ':') return std::string::npos;
        i = skip_space(i + 1);
        if (key == step.key) return find(i, steps, depth + 1);
        i = skip_space(skip_value(i));
        if (i < t_.size() && t_[i] == ',') i = skip_space(i + 1);
      }
      return std::string::npos;
    }
    if (t_[i] == '[' && step.is_index) {
      i = skip_space(i + 1);
      for (std::size_t k = 0; i < t_.size() && t_[i] != ']'; ++k) {
        if (k == step.index) return find(i, steps, depth + 1);
        i = skip_space(skip_value(i));
        if (i < t_.size() && t_[i] == ',') i = skip_space(i + 1);
      }
    }
    return std::string::npos;
  }

private:
  const std::string& t_;

  std::size_t skip_space(std::size_t i) const {
    while (i < t_.size() && (t_[i] == ' ' || t_[i] == '\t' || t_[i] == '\n' || t_[i] == '\r')) ++i;
    return i;
  }
  // From an opening quote to the index after the closing one.
  std::size_t skip_string(std::size_t i) const {
    for (++i; i < t_.size(); ++i) {
      if (t_[i] == '\\')
        ++i;
      else if (t_[i] == '"')
        return i + 1;
    }
    return t_.size();
  }
  // The key between the quotes at [begin, end) with the simple escapes undone (keys tvf
  // names in paths are plain words; anything else only has to compare unequal).
  std::string unescaped(std::size_t begin, std::size_t end) const {
    std::string out;
    for (std::size_t i = begin + 1; i + 1 < end; ++i) {
      if (t_[i] == '\\' && i + 2 < end) ++i;
      out += t_[i];
    }
    return out;
  }
  // Past one value; containers are skipped by counting brackets outside strings (no
  // recursion: the text nests at most kMaxJsonDepth deep, and this needs no stack).
  std::size_t skip_value(std::size_t i) const {
    if (i >= t_.size()) return i;
    if (t_[i] == '"') return skip_string(i);
    if (t_[i] == '{' || t_[i] == '[') {
      std::size_t depth = 0;
      for (; i < t_.size(); ++i) {
        const char c = t_[i];
        if (c == '"') {
          i = skip_string(i) - 1;
        } else if (c == '{' || c == '[') {
          ++depth;
        } else if (c == '}' || c == ']') {
          if (--depth == 0) return i + 1;
        }
      }
      return i;
    }
    while (i < t_.size() && std::strchr(",]} \t\r\n", t_[i]) == nullptr) ++i;
    return i;
  }
};

}  // namespace

json parse_json_text(const std::string& text, const std::string& label, const std::string& empty_hint) {
  if (text.size() > kMaxJsonBytes)
    throw_input_error(label, "",
                      fmt::format("the text is {} bytes long, more than the {} bytes tvf reads as JSON",
                                  text.size(), kMaxJsonBytes));
  if (text.find_first_not_of(" \t\r\n") == std::string::npos)
    throw_input_error(label, "", "the text is empty; " + empty_hint);
  if (const auto nul = text.find('\0'); nul != std::string::npos)
    fail_at(text, nul, label, "the text contains a NUL byte, which JSON text cannot (write \\u0000 inside a string)");

  json root;
  DomBuilder builder(root);
  if (json::sax_parse(text, &builder)) return root;
  if (!builder.duplicate().empty())
    throw_input_error(label, builder.duplicate(),
                      "the key appears twice in the same object (JSON keys must be unique)");
  if (builder.too_deep())
    fail_at(text, too_deep_index(text), label,
            fmt::format("arrays and objects nest more than {} deep, more than tvf reads", kMaxJsonDepth));
  // nlohmann's position counts the characters read, the last one being where it stopped.
  std::size_t index = builder.error_position() > 0 ? builder.error_position() - 1 : 0;
  index = std::min(index, text.size());
  std::string message;
  if (builder.error_id() == 406) {
    // Number overflow (e.g. 1e999): point at the start of the number.
    std::size_t start = std::min(index + 1, text.size());
    while (start > 0 && std::strchr("0123456789+-.eE", text[start - 1]) != nullptr) --start;
    std::size_t end = start;
    while (end < text.size() && end - start < 40 && std::strchr("0123456789+-.eE", text[end]) != nullptr)
      ++end;
    index = start;
    message = fmt::format("the number {} is out of range (numbers must be finite)", text.substr(start, end - start));
    if (!builder.error_path().empty()) {
      // Name the key too, as every other check of a value does.
      fail_at(text, index, label, message, builder.error_path());
    }
  } else {
    // NaN, Infinity and friends are not JSON: say so plainly.
    std::size_t start = index;
    while (start > 0 && index - start < 16 && is_word_char(text[start - 1])) --start;
    std::size_t end = start;
    while (end < text.size() && end - start < 16 && is_word_char(text[end])) ++end;
    std::string word = text.substr(start, end - start);
    std::transform(word.begin(), word.end(), word.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (index < text.size() && text[index] == '/') {
      message = "comments are not allowed in JSON";
    } else if (word == "nan" || word == "inf" || word == "infinity") {
      index = start > 0 && (text[start - 1] == '-' || text[start - 1] == '+') ? start - 1 : start;
      message = fmt::format("{} is not a JSON number (numbers must be finite)", text.substr(index, end - index));
    } else {
      // "[json.exception.parse_error.101] parse error at line 1, column 7: syntax error ..."
      const std::string& what = builder.error_text();
      const std::size_t column = what.find("column ");
      const std::size_t colon = column == std::string::npos ? std::string::npos : what.find(": ", column);
      if (colon != std::string::npos) {
        message = what.substr(colon + 2);
      } else {
        const std::size_t bracket = what.find("] ");
        message = bracket == std::string::npos ? what : what.substr(bracket + 2);
      }
      // nlohmann quotes the last token read: keep the sentence bounded.
      if (message.size() > 200) message = message.substr(0, 196) + " ...";
    }
  }
  fail_at(text, index, label, message);
}

JsonTextPosition json_path_position(const std::string& text, const std::string& json_path) {
  std::vector<PathStep> steps;
  if (!split_path(json_path, steps)) return {};
  const std::size_t index = PathScanner(text).find(0, steps, 0);
  if (index == std::string::npos || index >= text.size()) return {};
  const auto [line, col] = line_and_column(text, index);
  return {static_cast<int>(line), static_cast<int>(col)};
}

void rethrow_with_position(const Error& e, const std::string& text) {
  ErrorLocation location = location_of(e);
  if (location.line == 0 && !location.json_path.empty()) {
    const JsonTextPosition p = json_path_position(text, location.json_path);
    location.line = p.line;
    location.column = p.column;
  }
  throw LocatedError(e.what(), std::move(location));
}

std::string read_text_file(const std::string& path, const std::string& what, std::size_t max_bytes) {
  namespace fs = std::filesystem;
  auto fail = [&](const std::string& why) {
    throw_input_error("", "", fmt::format("cannot read {} '{}': {}", what, path, why));
  };
  std::error_code ec;
  const auto status = fs::status(path, ec);
  if (!fs::exists(status)) fail("it does not exist");
  if (fs::is_directory(status)) fail("it is a folder");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(std::strerror(errno));
  // Read in pieces up to the limit, so that /dev/zero or an endless pipe is refused
  // rather than read until memory runs out.
  std::string text;
  std::vector<char> buffer(std::size_t{1} << 16);
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    const auto got = static_cast<std::size_t>(in.gcount());
    if (text.size() + got > max_bytes)
      fail(fmt::format("it is longer than {} bytes, the limit for a JSON file", max_bytes));
    text.append(buffer.data(), got);
  }
  if (in.bad()) fail("a read error occurred");
  return text;
}

std::string valid_utf8(const std::string& text) {
  // The length of the well-formed sequence at i (RFC 3629: no overlong forms, no
  // surrogates, nothing above U+10FFFF), or 0.
  auto sequence = [&](size_t i) -> size_t {
    const auto byte = [&](size_t k) { return static_cast<unsigned char>(text[k]); };
    const unsigned char b = byte(i);
    if (b < 0x80) return 1;
    size_t n = 0;
    unsigned char lo = 0x80, hi = 0xBF;  // the range of the second byte
    if (b >= 0xC2 && b <= 0xDF) {
      n = 2;
    } else if (b >= 0xE0 && b <= 0xEF) {
      n = 3;
      if (b == 0xE0) lo = 0xA0;
      if (b == 0xED) hi = 0x9F;
    } else if (b >= 0xF0 && b <= 0xF4) {
      n = 4;
      if (b == 0xF0) lo = 0x90;
      if (b == 0xF4) hi = 0x8F;
    } else {
      return 0;
    }
    if (i + n > text.size() || byte(i + 1) < lo || byte(i + 1) > hi) return 0;
    for (size_t k = 2; k < n; ++k)
      if (byte(i + k) < 0x80 || byte(i + k) > 0xBF) return 0;
    return n;
  };
  std::string out;
  out.reserve(text.size());
  for (size_t i = 0; i < text.size();) {
    const size_t n = sequence(i);
    if (n == 0) {
      out += fmt::format("\\x{:02X}", static_cast<unsigned char>(text[i]));
      ++i;
    } else {
      out.append(text, i, n);
      i += n;
    }
  }
  return out;
}

}  // namespace tvf
