#include "serve_command.h"

#include "default_scene.h"

#include "tvf/core/error.h"
#include "tvf/serve/http_server.h"
#include "tvf/serve/session.h"

#include <fmt/format.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <thread>

namespace fs = std::filesystem;

namespace tvf::cli {

namespace {
std::atomic<bool> g_stop_requested{false};
static_assert(std::atomic<bool>::is_always_lock_free);  // safe to set in a signal handler
extern "C" void on_signal(int) { g_stop_requested.store(true); }
}  // namespace

ServeCommand::ServeCommand(CLI::App& app) {
  cmd_ = app.add_subcommand("serve", "The interactive designer in the browser: serves it and its JSON API locally");
  cmd_->add_option("scene", scene_,
                   "Scene file to design, inside the working folder (default: WORKDIR/scene.json, created from "
                   "the demo scene when missing)");
  cmd_->add_option("--dir", dir_,
                   "Working folder: the scene, uploads, exports and videos live here and nothing outside it is "
                   "read or written (default: the scene's folder, else the current folder)");
  cmd_->add_option("--host", host_, "Address to listen on (default 127.0.0.1: this machine only)");
  cmd_->add_option("--port", port_, "Port (default 8080; 0: any free port)")->check(CLI::Range(0, 65535));
  cmd_->add_option("--web", web_, "Folder of the built front end (default: the one this tvf was built with)");
  cmd_->add_flag("-q,--quiet", quiet_, "Print nothing but the address and errors");
  cmd_->add_flag("--solve-while-saving,!--save-before-solve", solve_while_saving_,
                 "Start a new scene's solve while the scene is saved, publishing nothing of it before the save "
                 "succeeded (the default); --save-before-solve starts it only once saved (docs/serve_api.md)");
}

int ServeCommand::run() {
  serve::SessionOptions so;
  if (scene_.empty()) {
    so.dir = dir_.empty() ? fs::path(".") : fs::path(dir_);
  } else {
    const fs::path scene = fs::absolute(scene_);
    if (!fs::exists(scene)) throw Error(fmt::format("{}: no such scene file", scene_));
    so.dir = dir_.empty() ? scene.parent_path() : fs::path(dir_);
    const fs::path rel = fs::weakly_canonical(scene).lexically_relative(fs::weakly_canonical(so.dir));
    if (rel.empty() || *rel.begin() == "..")
      throw Error(fmt::format("{}: the scene must lie inside the working folder {}", scene_, so.dir.string()));
    so.scene = rel.generic_string();
  }
  so.initial_scene = default_scene_text();
  so.solve_while_saving = solve_while_saving_;

  serve::Session session(so);
  serve::ServerOptions ho;
  ho.host = host_;
  ho.port = port_;
  ho.web_root = web_.empty() ? fs::path(TVF_WEB_DIST) : fs::path(web_);
  serve::HttpServer server(session, ho);
  if (host_ != "127.0.0.1" && host_ != "localhost" && host_ != "::1")
    std::fprintf(stderr, "tvf serve: warning: listening on %s: other machines can reach the designer\n", host_.c_str());
  std::printf("tvf serve: designing %s\n  open %s in a browser (Ctrl-C stops)\n", session.scene_path().c_str(),
              server.url().c_str());
  std::fflush(stdout);
  // Ctrl-C and SIGTERM stop the server: the handler only sets a flag (all it may do), and
  // a thread of ours watches it. (Blocking the signals and sigwait() would not do: the
  // threads OpenBLAS starts when the program loads would still take them.) The scene is
  // saved after every change anyway.
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  std::atomic<bool> finished{false};
  std::thread watcher([&] {
    while (!g_stop_requested.load() && !finished.load()) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    server.stop();
  });
  server.run();
  finished = true;  // run() also returns when the server fails
  watcher.join();
  if (!quiet_) std::printf("tvf serve: stopped; the design is in %s\n", session.scene_path().c_str());
  return 0;
}

}  // namespace tvf::cli
