#pragma once
// Two error channels (STYLE 7):
//  - tvf::Error: bad user input. The message is one sentence that already names the
//    file and the place in it ("scene.json: elements[2].path[1]: t = 7 is outside the
//    time range [0, 1]"). Clients print what() and exit non-zero.
//  - TVF_CHECK: an internal invariant. A failure is a bug in tvf; it throws
//    tvf::InternalError carrying the condition, the values and the source location.
#include <fmt/format.h>

#include <stdexcept>
#include <string>

namespace tvf {

class Error : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

class InternalError : public std::logic_error {
public:
  using std::logic_error::logic_error;
};

// Builds "file: where: message" (parts that are empty are left out) and throws Error.
[[noreturn]] void throw_input_error(const std::string& file, const std::string& where,
                                    const std::string& message);

[[noreturn]] void throw_internal_error(const char* condition, const char* file, int line,
                                       const std::string& message);

}  // namespace tvf

#define TVF_CHECK(cond, ...)                                                               \
  do {                                                                                     \
    if (!(cond)) ::tvf::throw_internal_error(#cond, __FILE__, __LINE__,                    \
                                             ::fmt::format("" __VA_ARGS__));               \
  } while (false)

#ifdef NDEBUG
#define TVF_DCHECK(cond, ...) \
  do {                        \
  } while (false)
#else
#define TVF_DCHECK(cond, ...) TVF_CHECK(cond, __VA_ARGS__)
#endif
