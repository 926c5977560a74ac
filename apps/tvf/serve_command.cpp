#include "serve_command.h"

#include "default_scene.h"

#include "tvf/core/error.h"
#include "tvf/serve/http_server.h"
#include "tvf/serve/session.h"

#include <fmt/format.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <thread>

namespace fs = std::filesystem;

namespace tvf::cli {

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

  // Ctrl-C and SIGTERM stop the server from a thread of their own (the scene is saved
  // after every change anyway); blocked here before any other thread starts.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

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
  std::atomic<bool> signalled{false};
  std::thread waiter([&] {
    int sig = 0;
    sigwait(&signals, &sig);
    signalled = true;
    server.stop();
  });
  server.run();
  // run() also returns when the server fails; wake the waiter then.
  if (!signalled) pthread_kill(waiter.native_handle(), SIGTERM);
  waiter.join();
  if (!quiet_) std::printf("tvf serve: stopped; the design is in %s\n", session.scene_path().c_str());
  return 0;
}

}  // namespace tvf::cli
