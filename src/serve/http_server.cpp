#include "tvf/serve/http_server.h"

#include <fmt/format.h>
#include <httplib.h>

#include "tvf/core/json_text.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>

namespace fs = std::filesystem;
using nlohmann::json;

namespace tvf::serve {

namespace {

// With a charset, cpp-httplib leaves the body uncompressed: on loopback, sending 100 kB
// takes microseconds, while its Brotli (quality 11) takes half a second for a frame.
constexpr const char* kJson = "application/json; charset=utf-8";

void send_json(httplib::Response& res, const json& body, int status = 200) {
  res.status = status;
  res.set_content(body.dump(), kJson);
}

void send_error(httplib::Response& res, int status, const std::string& message) {
  send_json(res, {{"error", message}}, status);
}

// The shared JSON reader (tvf/core/json_text.h): nesting, NUL bytes and repeated keys
// are refused with their line and column.
json parse_body(const httplib::Request& req) {
  if (req.body.empty()) return json::object();
  try {
    return parse_json_text(req.body, "");
  } catch (const Error& e) {
    throw RequestError(400, fmt::format("request body: not valid JSON at {}", e.what()));
  }
}

// Host names compare case-insensitively (RFC 9110 §4.2.3): "LOCALHOST" is "localhost".
bool loopback_host(std::string host) {
  std::transform(host.begin(), host.end(), host.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return host == "127.0.0.1" || host == "localhost" || host == "::1" || host == "[::1]";
}

// The host part of a Host header ("localhost:8080" → "localhost", "[::1]:80" → "[::1]").
std::string host_name(const std::string& header) {
  if (!header.empty() && header.front() == '[') {
    const auto close = header.find(']');
    return close == std::string::npos ? header : header.substr(0, close + 1);
  }
  return header.substr(0, header.find(':'));
}

std::string mime_type(const fs::path& p) {
  const std::string ext = p.extension().string();
  if (ext == ".json") return kJson;
  if (ext == ".mp4") return "video/mp4";
  if (ext == ".png") return "image/png";
  if (ext == ".svg") return "image/svg+xml";
  if (ext == ".csv") return "text/csv";
  return "application/octet-stream";
}

const char* kNoFrontEnd =
    "<!doctype html><meta charset=utf-8><title>tvf serve</title>"
    "<p>The designer's front end was not built (npm was missing when tvf was built). "
    "Install Node.js and npm, rebuild tvf, and restart <code>tvf serve</code>. The JSON API "
    "works without it: see docs/serve_api.md.</p>";

}  // namespace

struct HttpServer::Impl {
  Session& session;
  ServerOptions options;
  httplib::Server server;
  int port = 0;
  std::thread thread;

  Impl(Session& s, ServerOptions o) : session(s), options(std::move(o)) {}

  // Runs a handler, turning every exception into a JSON error (never a crash).
  template <class F>
  httplib::Server::Handler wrap(F f) {
    return [f](const httplib::Request& req, httplib::Response& res) {
      try {
        f(req, res);
      } catch (const RequestError& e) {
        send_error(res, e.status(), e.what());
      } catch (const Error& e) {
        send_error(res, 400, e.what());
      } catch (const std::exception& e) {
        send_error(res, 500, fmt::format("internal error: {}", e.what()));
      }
    };
  }

  void routes() {
    Session& s = session;
    server.Get("/api/scene", wrap([&s](const auto&, auto& res) { send_json(res, s.scene()); }));
    server.Put("/api/scene", wrap([&s](const auto& req, auto& res) {
                 json body = parse_body(req);
                 if (!body.is_object()) throw RequestError(400, "request body: expected a scene object");
                 send_json(res, s.put_scene(body));
               }));
    server.Post("/api/edit", wrap([&s](const auto& req, auto& res) { send_json(res, s.edit(parse_body(req))); }));
    server.Post("/api/undo", wrap([&s](const auto&, auto& res) { send_json(res, s.undo()); }));
    server.Post("/api/redo", wrap([&s](const auto&, auto& res) { send_json(res, s.redo()); }));
    server.Get("/api/status", wrap([&s](const auto&, auto& res) { send_json(res, s.status()); }));
    server.Get("/api/mesh", wrap([&s](const auto&, auto& res) { send_json(res, s.mesh()); }));
    server.Get(R"(/api/frame/(-?\d{1,9}))", wrap([&s](const auto& req, auto& res) {
                 send_json(res, s.frame(std::stoi(req.matches[1].str())));
               }));
    server.Get("/api/analysis", wrap([&s](const auto&, auto& res) { send_json(res, s.analysis()); }));
    server.Post("/api/export", wrap([&s](const auto& req, auto& res) {
                  send_json(res, s.export_field(parse_body(req)));
                }));
    server.Post("/api/render", wrap([&s](const auto& req, auto& res) {
                  send_json(res, s.render_video(parse_body(req)));
                }));
    server.Post("/api/seed_translation", wrap([&s](const auto& req, auto& res) {
                  send_json(res, s.seed_translation(parse_body(req)));
                }));
    server.Post("/api/upload", wrap([&s](const auto& req, auto& res) {
                  if (!req.has_param("name")) throw RequestError(400, "upload: say the file name (?name=mesh.obj)");
                  send_json(res, s.upload_mesh(req.get_param_value("name"), req.body));
                }));
    server.Get(R"(/api/files/(.+))", wrap([&s](const auto& req, auto& res) {
                 const fs::path p = s.resolve(req.matches[1].str());
                 if (!fs::is_regular_file(p))
                   throw RequestError(404, fmt::format("{}: no such file in the working folder", req.matches[1].str()));
                 std::ifstream in(p, std::ios::binary);
                 std::ostringstream bytes;
                 bytes << in.rdbuf();
                 res.set_content(bytes.str(), mime_type(p).c_str());
               }));

    const bool loopback = loopback_host(options.host);
    server.set_pre_routing_handler([loopback](const httplib::Request& req, httplib::Response& res) {
      if (loopback && !loopback_host(host_name(req.get_header_value("Host")))) {
        send_error(res, 403, "this server answers requests for localhost only");
        return httplib::Server::HandlerResponse::Handled;
      }
      if ((req.method == "POST" || req.method == "PUT") && req.path.rfind("/api/", 0) == 0) {
        const std::string type = req.get_header_value("Content-Type");
        const char* want = req.path == "/api/upload" ? "application/octet-stream" : "application/json";
        if (type.rfind(want, 0) != 0) {
          send_error(res, 415, fmt::format("{} {}: send the body as {}", req.method, req.path, want));
          return httplib::Server::HandlerResponse::Handled;
        }
      }
      return httplib::Server::HandlerResponse::Unhandled;
    });
    server.set_error_handler([](const httplib::Request& req, httplib::Response& res) {
      if (!res.body.empty()) return;
      std::string message;
      switch (res.status) {
        case 404: message = fmt::format("{} {}: no such resource", req.method, req.path); break;
        case 413: message = "request body too large"; break;
        default: message = fmt::format("{} {}: request failed with HTTP status {}", req.method, req.path, res.status);
      }
      send_error(res, res.status, message);
    });
    server.set_exception_handler([](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
      std::string what = "unknown exception";
      try {
        if (ep) std::rethrow_exception(ep);
      } catch (const std::exception& e) {
        what = e.what();
      } catch (...) {
      }
      send_error(res, 500, "internal error: " + what);
    });
    server.set_payload_max_length(options.max_body);

    std::error_code ec;
    if (!options.web_root.empty() && fs::is_regular_file(options.web_root / "index.html", ec)) {
      // The bundle is served as it is (see kJson: compressing it would cost seconds).
      server.set_file_extension_and_mimetype_mapping("js", "application/javascript; charset=utf-8");
      server.set_mount_point("/", options.web_root.string());
    } else {
      server.Get("/", [](const httplib::Request&, httplib::Response& res) {
        res.set_content(kNoFrontEnd, "text/html; charset=utf-8");
      });
    }
  }
};

HttpServer::HttpServer(Session& session, ServerOptions options)
    : impl_(std::make_unique<Impl>(session, std::move(options))) {
  impl_->routes();
  const auto& o = impl_->options;
  if (o.port < 0 || o.port > 65535) throw Error(fmt::format("--port {}: expected a port in [0, 65535]", o.port));
  if (o.port == 0) {
    impl_->port = impl_->server.bind_to_any_port(o.host);
  } else {
    impl_->port = impl_->server.bind_to_port(o.host, o.port) ? o.port : -1;
  }
  if (impl_->port <= 0)
    throw Error(fmt::format("cannot listen on {}:{} (in use, or not an address of this machine)", o.host, o.port));
}

HttpServer::~HttpServer() { stop(); }

int HttpServer::port() const { return impl_->port; }

std::string HttpServer::url() const {
  const std::string& h = impl_->options.host;
  const std::string shown = h == "0.0.0.0" ? "127.0.0.1" : h;
  return fmt::format("http://{}:{}/", shown.find(':') != std::string::npos ? "[" + shown + "]" : shown, impl_->port);
}

void HttpServer::run() { impl_->server.listen_after_bind(); }

void HttpServer::start() {
  impl_->thread = std::thread([this] { impl_->server.listen_after_bind(); });
  while (!impl_->server.is_running()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

void HttpServer::stop() {
  impl_->server.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

}  // namespace tvf::serve
