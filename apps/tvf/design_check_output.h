#pragma once
// `tvf analyze`'s design check (docs/analysis.md, "Design check"): which of the scene's
// designed features the analysis found, and what it found beyond them, written as
// STEM_design.json beside the analysis JSON. (The scene of a generated field is found by
// tvf::Design::open, api/design.h.)
#include <string>

namespace tvf::cli {

// The design-check file written beside `analysis_json`: STEM_design.json.
std::string design_check_path(const std::string& analysis_json);

}  // namespace tvf::cli
