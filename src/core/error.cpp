#include "tvf/core/error.h"

namespace tvf {

void throw_input_error(const std::string& file, const std::string& where,
                       const std::string& message) {
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
  throw Error(text);
}

void throw_internal_error(const char* condition, const char* file, int line,
                          const std::string& message) {
  throw InternalError(fmt::format("internal error at {}:{}: check '{}' failed{}{}", file, line,
                                  condition, message.empty() ? "" : ": ", message));
}

}  // namespace tvf
