#pragma once
// `tvf serve [SCENE] [--port N] [--host ADDR] [--dir WORKDIR]`: the interactive designer in
// the browser (issue 7; docs/serve_api.md). A thin client of tvf_serve (tvf/serve/*.h).
#include <CLI/CLI.hpp>

#include <string>

namespace tvf::cli {

class ServeCommand {
public:
  explicit ServeCommand(CLI::App& app);  // registers `serve`
  bool selected() const { return cmd_->parsed(); }
  // Serves until interrupted (Ctrl-C). Throws tvf::Error on bad input.
  int run();

private:
  CLI::App* cmd_ = nullptr;
  std::string scene_;
  std::string dir_;
  std::string host_ = "127.0.0.1";
  int port_ = 8080;
  std::string web_;
  bool quiet_ = false;
  bool solve_while_saving_ = true;
};

}  // namespace tvf::cli
