#pragma once
// The one reader of JSON text (scenes, edits, crowd files, .tvff headers, the server's
// request bodies). On top of nlohmann's parser it refuses, with one sentence naming the
// line and column (or the JSON path):
//  - nesting deeper than kMaxJsonDepth arrays and objects (as simdjson does), so that no
//    later recursion over the value (printing, copying, checking) can exhaust the stack;
//  - a key that appears twice in one object (nlohmann would keep the last silently);
//  - NUL bytes (a C string would end there) and text longer than kMaxJsonBytes;
//  - non-finite numbers (1e999, NaN, Infinity) and comments, said plainly.
// Memory is linear in the text: the JSON path of an error is built only when one is
// reported (each open container keeps its key, nothing more).
#include "tvf/core/error.h"
#include "tvf/core/error_location.h"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <string>

namespace tvf {

inline constexpr std::size_t kMaxJsonDepth = 1000;
// 64 MiB: far above any scene or request (the largest example scene is a few kB), far
// below what would exhaust memory once parsed.
inline constexpr std::size_t kMaxJsonBytes = std::size_t{64} << 20;

// `text` as valid UTF-8: every byte that is not part of a well-formed UTF-8 sequence
// (RFC 3629) is written as \xNN. Error messages quote the user's bytes (a word of a mesh
// file, an upload's name), and JSON, which the server and the Python module answer with,
// holds UTF-8 only: a mesh word with bytes 0xFF made the server's status unserialisable.
// Every message of throw_input_error and throw_located_error (error.h) goes through it.
std::string valid_utf8(const std::string& text);

// Parses `text`; throws tvf::Error "<label>: line L, column C: <sentence>" (or
// "<label>: <json path>: ..." for a repeated key). `empty_hint` completes the sentence
// for empty text ("the text is empty; <empty_hint>").
nlohmann::json parse_json_text(const std::string& text, const std::string& label,
                               const std::string& empty_hint = "expected a JSON value");

// The 1-based line and column of the value at `json_path` ("elements[2].path[1]", "" for
// the root; keys joined by '.', indices in brackets, as tvf's messages write them) in
// JSON `text`; {0, 0} when the text has no value there. Used when an error is reported
// (a scan of the text), so that parsed values carry no positions.
struct JsonTextPosition {
  int line = 0;
  int column = 0;
};
JsonTextPosition json_path_position(const std::string& text, const std::string& json_path);

// Completes an error about JSON `text` with the line and column of its JSON path, when
// it has one and none yet: throws a LocatedError with e's message and the fields set.
[[noreturn]] void rethrow_with_position(const Error& e, const std::string& text);

// Reads a whole file of at most `max_bytes` bytes (a larger file, a device like
// /dev/zero or a FIFO that never ends is refused with one sentence naming the file and
// the limit). `what` names the file's role in messages ("the scene file").
std::string read_text_file(const std::string& path, const std::string& what,
                           std::size_t max_bytes = kMaxJsonBytes);

}  // namespace tvf
