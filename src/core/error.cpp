#include "tvf/core/error.h"

#include "tvf/core/error_location.h"
#include "tvf/core/json_text.h"

namespace tvf {
namespace {

std::string message_text(const std::string& file, const std::string& where, const std::string& message) {
  std::string text;
  for (const std::string* part : {&file, &where}) {
    if (part->empty()) continue;
    text.append(*part);
    text.append(": ");
  }
  text.append(message);
  // A NUL byte (from a "\u0000" in a JSON string, say) would end the message where a
  // client prints what(): write it visibly instead.
  std::string::size_type nul = 0;
  while ((nul = text.find('\0', nul)) != std::string::npos) {
    text.replace(nul, 1, "\\u0000");
    nul += 6;
  }
  // Messages quote the user's bytes; JSON answers (the server's, Python's) hold UTF-8 only.
  return valid_utf8(text);
}

}  // namespace

void throw_input_error(const std::string& file, const std::string& where,
                       const std::string& message) {
  ErrorLocation location;
  location.file = file;
  location.json_path = where;
  throw LocatedError(message_text(file, where, message), location);
}

void throw_located_error(const std::string& where, const std::string& message, ErrorLocation location) {
  std::string text = message_text(location.file, where, message);  // before location is moved from
  throw LocatedError(text, std::move(location));
}

ErrorLocation location_of(const Error& e) {
  if (const auto* located = dynamic_cast<const LocatedError*>(&e)) return located->location();
  return {};
}

void throw_internal_error(const char* condition, const char* file, int line,
                          const std::string& message) {
  throw InternalError(fmt::format("internal error at {}:{}: check '{}' failed{}{}", file, line,
                                  condition, message.empty() ? "" : ": ", message));
}

}  // namespace tvf
