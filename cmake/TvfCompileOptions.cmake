# Warnings and sanitizers are per-target settings carried by two interface libraries,
# not global flags: every tvf target links tvf_options.
add_library(tvf_options INTERFACE)
target_compile_options(tvf_options INTERFACE
  $<$<CXX_COMPILER_ID:GNU,Clang>:-Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
    -Wcast-align -Woverloaded-virtual -Wnull-dereference -Wimplicit-fallthrough>
  # Debug info names source files relative to the clone, so objects do not depend on where
  # it lies (ccache hits across clones; see CMakeLists.txt).
  $<$<CXX_COMPILER_ID:GNU,Clang>:-fdebug-prefix-map=${PROJECT_SOURCE_DIR}=.>)
if(TVF_SANITIZE)
  target_compile_options(tvf_options INTERFACE
    -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer)
  target_link_options(tvf_options INTERFACE -fsanitize=address,undefined)
endif()
# The fuzz build (fuzz/, preset "fuzz"): everything instrumented for libFuzzer's coverage
# and checked by ASan + UBSan; the fuzz programs add libFuzzer's main at link time.
if(TVF_FUZZ)
  target_compile_options(tvf_options INTERFACE
    -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer)
  target_link_options(tvf_options INTERFACE -fsanitize=address,undefined)
endif()
