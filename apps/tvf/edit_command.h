#pragma once
// `tvf edit SCENE --cancel FRAME X1 Y1 X2 Y2 | --remove-bifurcation T X Y |
//  --move-bifurcation T X Y T2 X2 Y2 | --smooth S | --undo`: appends one edit to the scene's
// `edits` list (or drops the last one), after checking on the generated field that the edit
// can be applied. A refused edit leaves the scene file as it was.
#include <CLI/CLI.hpp>

#include <limits>
#include <string>
#include <vector>

namespace tvf::cli {

struct EditArgs {
  std::string scene;
  std::vector<double> cancel;              // FRAME X1 Y1 [Z1] X2 Y2 [Z2]
  std::vector<double> remove_bifurcation;  // T X Y [Z]
  std::vector<double> move_bifurcation;    // T X Y [Z] T2 X2 Y2 [Z2]
  double smooth = std::numeric_limits<double>::quiet_NaN();  // NaN: not given
  double window = std::numeric_limits<double>::quiet_NaN();  // NaN: not given (the default)
  bool undo = false;
  bool quiet = false;
};

// Registers the `edit` subcommand on `app`, filling `args`.
CLI::App* add_edit_command(CLI::App& app, EditArgs& args);
// Runs it; throws tvf::Error for bad input or a refused edit.
int run_edit(const EditArgs& args);

}  // namespace tvf::cli
