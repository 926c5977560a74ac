#pragma once
// The designer's HTTP server (cpp-httplib, Debian package libcpp-httplib-dev): the JSON
// API of docs/serve_api.md over a Session, and the built front end (web/dist) as static
// files. Lives in the tvf_serve library, outside libtvf (STYLE 14: the core opens no
// socket).
//
// Safety: binds to 127.0.0.1 unless told otherwise; request bodies are limited
// (ServerOptions::max_body, counted as they are read, after decompression, whatever the
// transfer encoding: reading stops at the limit and the connection is closed after the
// 413); slow clients are cut off (a request's headers and body must arrive within
// request_timeout of the connection or the last answer, and each answer is written
// within answer_timeout); one request per connection (no keep-alive: an unread body is
// never read as a next request); the worker pool (threads) is larger than the bursts of
// waiting requests, and waits for a field are bounded and hold no lock, so status
// answers while edits and renders wait; API writes need Content-Type application/json (a page of
// another site cannot send that without a CORS preflight, which is never granted); on a
// loopback address, requests whose Host header is not a loopback name are refused (DNS
// rebinding); every error is a JSON body {"error": "..."} with a 4xx status, and an
// unexpected exception a 500, never a crash.
#include "tvf/serve/session.h"

#include <filesystem>
#include <memory>
#include <string>

namespace tvf::serve {

struct ServerOptions {
  std::string host = "127.0.0.1";
  int port = 8080;                       // 0: any free port (see HttpServer::port())
  std::filesystem::path web_root;        // the built front end; empty or missing: a note page
  std::size_t max_body = 64u << 20;      // bytes, after decoding (uploaded meshes are the large requests)
  std::size_t max_head = 32u << 10;      // bytes of the request line and headers together (more: 431)
  double request_timeout = 10;           // seconds to send a request (headers and body)
  double answer_timeout = 60;            // seconds for a client to take an answer
  int threads = 32;                      // requests served at once
  // GET /api/events: status pushed as server-sent events. At most max_streams at once
  // (503 beyond, so streams never take the whole pool), each ended after stream_seconds
  // (the browser's EventSource reconnects), with a comment line every heartbeat_seconds.
  int max_streams = 8;
  double stream_seconds = 300;
  double heartbeat_seconds = 15;
};

class HttpServer {
public:
  // Binds the port; throws tvf::Error naming host and port when that fails.
  HttpServer(Session& session, ServerOptions options);
  ~HttpServer();  // stops and joins
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  int port() const;
  std::string url() const;  // http://host:port/
  // Serves until stop() (from another thread or a signal handler's thread).
  void run();
  // Serves in a background thread (tests).
  void start();
  // Stops listening, cuts open connections, wakes requests waiting for a field (they
  // answer 503) and joins the workers: prompt (a video being rendered is finished first).
  void stop();

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tvf::serve
