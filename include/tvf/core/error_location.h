#pragma once
// Where in the user's input a tvf::Error is, as fields (issue 18): the file, the JSON
// path, the line and the column. what() stays the sentence the command line prints; the
// fields let a client point at the place (the designer selects the value, the server
// answers them beside "error", Python sets them on its ValueError).
//
// Every error thrown by throw_input_error (error.h) is a LocatedError: its location has
// the file and, as its JSON path, the place the sentence names ("elements[2].path[1]", or
// a key such as "subdivisions"). The line and column are added where the text is known:
// by the JSON reader for syntax errors, and by rethrow_with_position (json_text.h) for an
// error about a value found after parsing.
#include "tvf/core/error.h"

#include <string>
#include <utility>

namespace tvf {

// Each part is empty (0) when not known.
struct ErrorLocation {
  std::string file;       // the file or label the sentence names first ("scene.json")
  std::string json_path;  // "elements[2].path[1]"
  int line = 0;           // 1-based line of the value in the file's text
  int column = 0;         // 1-based column, in code points
};

class LocatedError : public Error {
public:
  LocatedError(const std::string& message, ErrorLocation location)
      : Error(message), location_(std::move(location)) {}
  const ErrorLocation& location() const { return location_; }

private:
  ErrorLocation location_;
};

// The location of any tvf::Error: its fields when it has them, else all empty.
ErrorLocation location_of(const Error& e);

// Throws LocatedError "file: where: message" (empty parts left out) with `location`;
// `where` is the place as the sentence writes it (e.g. "line 3, column 7").
[[noreturn]] void throw_located_error(const std::string& where, const std::string& message,
                                      ErrorLocation location);

}  // namespace tvf
