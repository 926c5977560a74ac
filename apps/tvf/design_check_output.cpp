#include "design_check_output.h"

#include <filesystem>

namespace fs = std::filesystem;

namespace tvf::cli {

std::string design_check_path(const std::string& analysis_json) {
  const fs::path out(analysis_json);
  return ((out.parent_path() / out.stem()).string() + "_design.json");
}

}  // namespace tvf::cli
