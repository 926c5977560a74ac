#include "tvf/serve/http_server.h"

#include "tvf/core/json_text.h"

#include <fmt/format.h>
#include <httplib.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <fstream>
#include <map>
#include <mutex>
#include <new>
#include <set>
#include <sstream>
#include <string_view>
#include <thread>
#include <vector>

#include <dirent.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

namespace fs = std::filesystem;
using nlohmann::json;

namespace tvf::serve {

namespace {

// With a charset, cpp-httplib leaves the body uncompressed: on loopback, sending 100 kB
// takes microseconds, while its Brotli (quality 11) takes half a second for a frame.
constexpr const char* kJson = "application/json; charset=utf-8";

// Binary frames (GET /api/frame/J?format=f32): cpp-httplib does not compress this type.
constexpr const char* kBinary = "application/octet-stream";

// ?format=f32 asks for the binary form of a frame; no format (or "json") for JSON.
bool binary_format(const httplib::Request& req) {
  if (!req.has_param("format")) return false;
  const std::string f = req.get_param_value("format");
  if (f == "f32") return true;
  if (f == "json") return false;
  throw RequestError(400, fmt::format("format: \"{:.40}\" is not one of json, f32", f));
}

void send_json(httplib::Response& res, const json& body, int status = 200) {
  res.status = status;
  // Invalid UTF-8 (bytes of a user's file quoted in a message) is replaced, not thrown on.
  res.set_content(body.dump(-1, ' ', false, json::error_handler_t::replace), kJson);
}

// {"error": sentence} and, where the error has them, the place as fields (docs/serve_api.md):
// "file", "json_path", "line" and "column" (1-based, in the request body or file).
void send_error(httplib::Response& res, int status, const std::string& message, const ErrorLocation& where = {}) {
  json body = {{"error", message}};
  if (!where.file.empty()) body["file"] = where.file;
  if (!where.json_path.empty()) body["json_path"] = where.json_path;
  if (where.line > 0) {
    body["line"] = where.line;
    body["column"] = where.column;
  }
  send_json(res, body, status);
}

// An error's location completed with the line and column of its JSON path in the request
// body (a scene sent with PUT /api/scene names its own paths).
ErrorLocation in_body(ErrorLocation where, const std::string& body) {
  if (where.line == 0 && !where.json_path.empty()) {
    const JsonTextPosition p = json_path_position(body, where.json_path);
    where.line = p.line;
    where.column = p.column;
  }
  return where;
}

// Request bodies go through the shared JSON reader (tvf/core/json_text.h): nesting beyond
// 1,000 levels, NUL bytes and repeated keys are refused while parsing, with their line and
// column (and the key of a number out of range); no library's exception text is shown.
json parse_json(const std::string& text) {
  if (text.empty()) return json::object();
  try {
    return parse_json_text(text, "");
  } catch (const Error& e) {
    throw RequestError(400, fmt::format("request body: not valid JSON at {}", e.what()), location_of(e));
  }
}

// The revision a change names in its If-Match header (the ETag of GET /api/scene,
// "12"); none or "*": any revision.
long long if_match(const httplib::Request& req) {
  if (!req.has_header("If-Match")) return kAnyRevision;
  std::string v = req.get_header_value("If-Match");
  if (v == "*") return kAnyRevision;
  if (v.rfind("W/", 0) == 0) v = v.substr(2);
  if (v.size() >= 2 && v.front() == '"' && v.back() == '"') v = v.substr(1, v.size() - 2);
  if (!v.empty() && v.size() <= 18 && std::all_of(v.begin(), v.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return std::stoll(v);
  throw RequestError(400, "If-Match: expected the ETag of GET /api/scene, such as \"12\"");
}

std::string etag(long long revision) { return fmt::format("\"{}\"", revision); }

// A library's exception text without its "[json.exception.type_error.302] " prefix.
std::string plain_message(const char* what) {
  std::string m(what);
  if (m.rfind("[json.exception.", 0) == 0) {
    const auto end = m.find("] ");
    if (end != std::string::npos) m = m.substr(end + 2);
  }
  return m.size() <= 300 ? m : m.substr(0, 297) + "...";
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

namespace {

using Clock = std::chrono::steady_clock;

// The open connections and their deadlines: a watchdog thread shuts down the socket of a
// connection past its deadline (a client dripping its headers, or not reading its
// answer), so that no client holds a worker for long. Each connection is registered with
// a duplicate of its socket, closed only when the connection has ended, so the watchdog
// never touches a socket number that was reused.
class Connections {
public:
  Connections() : thread_([this] { watch(); }) {}
  ~Connections() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }
  // Registers the connection the server has just accepted on `port` (the one socket of
  // this process on that port that is neither listening nor registered yet), through a
  // duplicate of it; -1 when none is found. httplib 0.11 does not tell its task queue the
  // socket (the listener calls enqueue right after accept), hence the search.
  int adopt(int port) {
    std::lock_guard lock(mutex_);
    int found = -1;
    if (DIR* d = ::opendir("/proc/self/fd")) {
      while (const dirent* e = ::readdir(d)) {
        char* end = nullptr;
        const long fd = std::strtol(e->d_name, &end, 10);
        if (end == e->d_name || *end != '\0' || fd == ::dirfd(d)) continue;
        struct stat st {};
        if (::fstat(static_cast<int>(fd), &st) != 0 || !S_ISSOCK(st.st_mode) || inodes_.count(st.st_ino)) continue;
        sockaddr_storage a{};
        socklen_t len = sizeof a;
        if (::getsockname(static_cast<int>(fd), reinterpret_cast<sockaddr*>(&a), &len) != 0) continue;
        const int local = a.ss_family == AF_INET    ? ntohs(reinterpret_cast<sockaddr_in*>(&a)->sin_port)
                          : a.ss_family == AF_INET6 ? ntohs(reinterpret_cast<sockaddr_in6*>(&a)->sin6_port)
                                                    : -1;
        int listening = 1;
        socklen_t optlen = sizeof listening;
        if (local != port || ::getsockopt(static_cast<int>(fd), SOL_SOCKET, SO_ACCEPTCONN, &listening, &optlen) != 0 ||
            listening)
          continue;
        found = static_cast<int>(fd);
        const int copy = ::dup(found);
        if (copy >= 0) {
          entries_[copy] = {{}, false, true, st.st_ino};
          inodes_.insert(st.st_ino);
          if (closing_) ::shutdown(copy, SHUT_RDWR);
        }
        found = copy;
        break;
      }
      ::closedir(d);
    }
    return found;
  }
  void remove(int copy) {
    if (copy < 0) return;
    std::lock_guard lock(mutex_);
    const auto it = entries_.find(copy);
    if (it == entries_.end()) return;
    inodes_.erase(it->second.inode);
    entries_.erase(it);
    ::close(copy);
  }
  // A deadline for reading the request (`reading`) or for writing the answer.
  void arm(int copy, Clock::time_point deadline, bool reading) { set(copy, deadline, true, reading); }
  void disarm(int copy) { set(copy, {}, false, false); }
  // Stop: every connection still sending its request is cut, and new ones at once;
  // requests being handled (woken by Session::interrupt) still send their answer.
  void cut_all() {
    std::lock_guard lock(mutex_);
    closing_ = true;
    for (auto& [fd, e] : entries_)
      if (e.reading) ::shutdown(fd, SHUT_RDWR);
  }

private:
  struct Entry {
    Clock::time_point deadline;
    bool armed = false;
    bool reading = false;
    ino_t inode = 0;
  };
  void set(int copy, Clock::time_point deadline, bool armed, bool reading) {
    std::lock_guard lock(mutex_);
    const auto it = entries_.find(copy);
    if (it != entries_.end()) {
      it->second.deadline = deadline;
      it->second.armed = armed;
      it->second.reading = reading;
      if (closing_ && reading) ::shutdown(copy, SHUT_RDWR);
    }
  }
  void watch() {
    std::unique_lock lock(mutex_);
    while (!stop_) {
      wake_.wait_for(lock, std::chrono::milliseconds(250));
      const auto now = Clock::now();
      for (auto& [fd, e] : entries_)
        if (e.armed && e.deadline < now) {
          ::shutdown(fd, SHUT_RDWR);
          e.armed = false;
        }
    }
  }
  std::mutex mutex_;
  std::condition_variable wake_;
  std::map<int, Entry> entries_;
  std::set<ino_t> inodes_;
  bool stop_ = false;
  bool closing_ = false;
  std::thread thread_;
};

// The connection a worker thread is serving.
struct CurrentConnection {
  Connections* connections = nullptr;
  int copy = -1;  // Connections' duplicate of the socket
};
thread_local CurrentConnection t_connection;

Clock::time_point after(double seconds);

// Whether the request line and headers arriving on `fd` end within `limit` bytes. The
// bytes are only looked at (MSG_PEEK), not taken: cpp-httplib reads them afterwards. The
// Debian build of cpp-httplib (0.11, a shared library, so its CPPHTTPLIB_HEADER_MAX_LENGTH
// cannot be set here) reads a header line whole, however long, before it checks its
// length: a 10 MB header line was 10 MB in memory. A connection that closes, or the
// deadline (request_timeout, when the watchdog cuts the connection; bytes already sent
// stay readable after that, so the deadline is checked here too), ends the wait:
// cpp-httplib then reads what there is and finds the connection closed.
bool head_fits(int fd, std::size_t limit, Clock::time_point deadline) {
  std::vector<char> buf(limit + 1);
  ssize_t seen = -1;
  for (; Clock::now() < deadline;) {
    const ssize_t n = ::recv(fd, buf.data(), buf.size(), MSG_PEEK | MSG_DONTWAIT);
    if (n == 0) return true;
    if (n < 0) {
      if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) return true;
      pollfd p{fd, POLLIN, 0};
      ::poll(&p, 1, 100);
      continue;
    }
    const std::string_view v(buf.data(), static_cast<size_t>(n));
    if (v.find("\r\n\r\n") != std::string_view::npos || v.find("\n\n") != std::string_view::npos) return true;
    if (static_cast<size_t>(n) > limit) return false;
    // Nothing new since the last look: wait for more (poll would say "readable" at once).
    if (n == seen) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    seen = n;
  }
  return true;
}

// Answers 431 on `fd` and closes it for reading and writing; what the client is still
// sending is read and dropped for a moment first (up to 4 MiB or 250 ms), so that the
// answer is not lost to a reset.
void refuse_head(int fd, std::size_t limit) {
  const std::string body =
      json{{"error", fmt::format("the request line and headers are longer than {} KiB", limit >> 10)}}.dump();
  const std::string answer = fmt::format(
      "HTTP/1.1 431 Request Header Fields Too Large\r\nContent-Type: application/json\r\nContent-Length: "
      "{}\r\nConnection: close\r\n\r\n{}",
      body.size(), body);
  (void)::send(fd, answer.data(), answer.size(), MSG_NOSIGNAL);
  ::shutdown(fd, SHUT_WR);
  const auto end = Clock::now() + std::chrono::milliseconds(250);
  std::vector<char> sink(64u << 10);
  for (std::size_t drained = 0; drained < (4u << 20) && Clock::now() < end;) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 50) <= 0) continue;
    const ssize_t n = ::recv(fd, sink.data(), sink.size(), MSG_DONTWAIT);
    if (n <= 0) break;
    drained += static_cast<std::size_t>(n);
  }
  ::shutdown(fd, SHUT_RDWR);
}

// The server's task queue: a pool of `threads` workers, each connection registered with
// the watchdog while a worker serves it, with request_timeout to send its request and its
// request line and headers limited to max_head bytes (431 beyond, before cpp-httplib reads them).
class WatchedPool : public httplib::TaskQueue {
public:
  WatchedPool(size_t threads, Connections& connections, int port, double request_timeout, std::size_t max_head)
      : pool_(threads), connections_(connections), port_(port), request_timeout_(request_timeout),
        max_head_(max_head) {}
  void enqueue(std::function<void()> fn) override {
    const int copy = connections_.adopt(port_);  // the listener accepted it just now
    pool_.enqueue([this, copy, fn = std::move(fn)] {
      t_connection = {&connections_, copy};
      const Clock::time_point deadline = after(request_timeout_);
      connections_.arm(copy, deadline, true);
      if (copy >= 0 && !head_fits(copy, max_head_, deadline + std::chrono::milliseconds(300)))
        refuse_head(copy, max_head_);
      fn();
      connections_.remove(copy);
      t_connection = {};
    });
  }
  void shutdown() override { pool_.shutdown(); }

private:
  httplib::ThreadPool pool_;
  Connections& connections_;
  int port_;
  double request_timeout_;
  std::size_t max_head_;
};

Clock::time_point after(double seconds) {
  return Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

// Reads a request's body through the content reader, counting the bytes as they arrive
// (after decompression): at `limit` reading stops and the request is refused (413),
// whatever the body's transfer or content encoding.
std::string read_body(const httplib::ContentReader& reader, httplib::Response& res, std::size_t limit) {
  std::string body;
  bool over = false;
  const bool ok = reader([&](const char* data, size_t n) {
    if (n > limit - body.size()) {
      over = true;
      return false;
    }
    body.append(data, n);
    return true;
  });
  if (over || res.status == 413)
    throw RequestError(413, fmt::format("request body too large (the limit is {}, after decompression)",
                                        limit >= (1u << 20) ? fmt::format("{} MiB", limit >> 20)
                                                            : fmt::format("{} bytes", limit)));
  if (res.status == 415) throw RequestError(415, "request body: unsupported Content-Encoding (send it as it is, or gzip)");
  if (!ok) throw RequestError(400, "request body: could not be read whole (cut off, badly chunked or badly compressed)");
  if (t_connection.connections) t_connection.connections->disarm(t_connection.copy);  // the handler may take a while
  return body;
}

// Whether the client of `fd` has closed its end (or the connection broke): looked at
// without waiting and without taking any byte.
bool peer_gone(int fd) {
  if (fd < 0) return false;
  pollfd p{fd, POLLIN | POLLRDHUP, 0};
  if (::poll(&p, 1, 0) <= 0) return false;
  if (p.revents & (POLLRDHUP | POLLHUP | POLLERR)) return true;
  char c = 0;
  return ::recv(fd, &c, 1, MSG_PEEK | MSG_DONTWAIT) == 0;
}

// One GET /api/events stream: counts itself among the open streams while it lives (the
// content provider owns it, and cpp-httplib drops the provider when the answer ends).
struct EventStream {
  explicit EventStream(std::atomic<int>& open) : open_(open) {}
  ~EventStream() { open_.fetch_sub(1); }
  EventStream(const EventStream&) = delete;
  EventStream& operator=(const EventStream&) = delete;
  long long seen = 0;  // Session::wait_change's count when the last event was sent
  Clock::time_point end, heartbeat;
  bool started = false;

private:
  std::atomic<int>& open_;
};

}  // namespace

struct HttpServer::Impl {
  Session& session;
  ServerOptions options;
  Connections connections;
  std::atomic<int> streams{0};  // GET /api/events answers being streamed
  httplib::Server server;
  int port = 0;
  std::thread thread;

  Impl(Session& s, ServerOptions o) : session(s), options(std::move(o)) {}

  // Runs a handler, turning every exception into a JSON error (never a crash).
  template <class F>
  httplib::Server::Handler wrap(F f) {
    return [f](const httplib::Request& req, httplib::Response& res) { guarded(res, [&] { f(req, res); }); };
  }
  // The same for handlers of requests with a body: the body is read first, within
  // max_body, and handed to the handler as a string.
  template <class F>
  httplib::Server::HandlerWithContentReader wrap_body(F f) {
    const std::size_t limit = options.max_body;
    return [f, limit](const httplib::Request& req, httplib::Response& res, const httplib::ContentReader& reader) {
      guarded(res, [&] {
        const std::string body = read_body(reader, res, limit);
        f(req, res, body);
      });
    };
  }
  template <class F>
  static void guarded(httplib::Response& res, F&& f) {
    try {
      f();
    } catch (const RequestError& e) {
      send_error(res, e.status(), e.what(), e.location());
    } catch (const Error& e) {
      send_error(res, 400, e.what(), location_of(e));
    } catch (const std::bad_alloc&) {
      send_error(res, 503, "the server has not enough memory for this request");
    } catch (const json::exception& e) {
      send_error(res, 400, fmt::format("request: {}", plain_message(e.what())));
    } catch (const std::exception& e) {
      send_error(res, 500, fmt::format("internal error: {}", plain_message(e.what())));
    }
  }

  // The designer's Lagrangian overlays (docs/serve_api.md): GET /api/ftle?t=&horizon=&direction=,
  // POST /api/streakline and /api/timeline.
  void lcs_routes() {
    Session& s = session;
    server.Get("/api/ftle", wrap([&s](const auto& req, auto& res) {
                 // Query parameters as JSON: numbers where the whole value reads as one.
                 json q = json::object();
                 for (const auto& [key, value] : req.params) {
                   char* end = nullptr;
                   const double x = std::strtod(value.c_str(), &end);
                   q[key] = !value.empty() && end == value.c_str() + value.size() ? json(x) : json(value);
                 }
                 send_json(res, s.ftle(q));
               }));
    server.Post("/api/streakline", wrap_body([&s](const auto&, auto& res, const std::string& text) {
                  send_json(res, s.streakline(parse_json(text)));
                }));
    server.Post("/api/timeline", wrap_body([&s](const auto&, auto& res, const std::string& text) {
                  send_json(res, s.timeline(parse_json(text)));
                }));
  }

  void routes() {
    Session& s = session;
    // The scene's revision is its ETag; a change sends it back in If-Match (412 when the
    // scene has moved on since).
    auto with_etag = [](httplib::Response& res, const json& answer) {
      res.set_header("ETag", etag(answer.at("revision").get<long long>()));
      send_json(res, answer);
    };
    server.Get("/api/scene", wrap([&s, with_etag](const auto&, auto& res) { with_etag(res, s.scene()); }));
    server.Put("/api/scene", wrap_body([&s, with_etag](const auto& req, auto& res, const std::string& text) {
                 json body = parse_json(text);
                 if (!body.is_object()) throw RequestError(400, "request body: expected a scene object");
                 try {
                   with_etag(res, s.put_scene(body, if_match(req)));
                 } catch (const RequestError& e) {
                   throw RequestError(e.status(), e.what(), in_body(e.location(), text));
                 }
               }));
    server.Post("/api/edit", wrap_body([&s, with_etag](const auto& req, auto& res, const std::string& text) {
                  with_etag(res, s.edit(parse_json(text), if_match(req)));
                }));
    server.Post("/api/undo", wrap_body([&s, with_etag](const auto& req, auto& res, const std::string&) {
                  with_etag(res, s.undo(if_match(req)));
                }));
    server.Post("/api/redo", wrap_body([&s, with_etag](const auto& req, auto& res, const std::string&) {
                  with_etag(res, s.redo(if_match(req)));
                }));
    server.Get("/api/status", wrap([&s](const auto&, auto& res) { send_json(res, s.status()); }));
    // Server-sent events: `event: status` with the JSON of /api/status, sent at once and
    // whenever the revision, the generation state or the result changes; a comment line
    // as a heartbeat. The provider waits at most a second at a time, so that a stopping
    // server (Session::interrupt ends the wait at once), a client gone away (peer_gone)
    // or the stream's end (stream_seconds) frees the worker within a second.
    server.Get("/api/events", wrap([this, &s](const auto&, auto& res) {
                 if (streams.fetch_add(1) >= options.max_streams) {
                   streams.fetch_sub(1);
                   throw RequestError(503, fmt::format("too many event streams open (the limit is {}): poll "
                                                       "GET /api/status instead",
                                                       options.max_streams));
                 }
                 auto stream = std::make_shared<EventStream>(streams);
                 const ServerOptions& o = options;
                 res.set_header("Cache-Control", "no-store");
                 res.set_chunked_content_provider("text/event-stream", [stream, &s, &o](size_t, httplib::DataSink& sink) {
                   EventStream& e = *stream;
                   const auto send = [&sink](const std::string& text) {
                     return sink.write(text.data(), text.size());
                   };
                   if (!e.started) {
                     // The watchdog's deadline for the answer does not apply: the stream
                     // ends by itself; each write is bounded by the socket's write timeout.
                     if (t_connection.connections) t_connection.connections->disarm(t_connection.copy);
                     e.started = true;
                     e.end = after(o.stream_seconds);
                     e.heartbeat = after(o.heartbeat_seconds);
                     if (!send("retry: 1000\n\n")) return false;
                   }
                   const long long now = s.wait_change(e.seen, 1.0);
                   if (now < 0 || Clock::now() >= e.end || peer_gone(t_connection.copy)) {
                     sink.done();
                     return true;
                   }
                   if (now != e.seen) {
                     e.seen = now;
                     e.heartbeat = after(o.heartbeat_seconds);
                     return send(fmt::format("event: status\ndata: {}\n\n", s.status().dump(-1, ' ', false, json::error_handler_t::replace)));
                   }
                   if (Clock::now() >= e.heartbeat) {
                     e.heartbeat = after(o.heartbeat_seconds);
                     return send(": heartbeat\n\n");
                   }
                   return true;
                 });
               }));
    server.Get("/api/mesh", wrap([&s](const auto&, auto& res) { send_json(res, s.mesh()); }));
    // A frame (and the preview) as JSON, or with ?format=f32 in binary (docs/serve_api.md,
    // "Binary frames": float32 vectors after a JSON head; errors are JSON either way).
    server.Get(R"(/api/frame/(-?\d{1,9}))", wrap([&s](const auto& req, auto& res) {
                 const int j = std::stoi(req.matches[1].str());
                 if (binary_format(req)) res.set_content(s.frame_f32(j), kBinary);
                 else send_json(res, s.frame(j));
               }));
    server.Get("/api/analysis", wrap([&s](const auto&, auto& res) { send_json(res, s.analysis()); }));
    server.Get("/api/preview", wrap([&s](const auto& req, auto& res) {
                 if (binary_format(req)) res.set_content(s.preview_f32(), kBinary);
                 else send_json(res, s.preview());
               }));
    server.Post("/api/export", wrap_body([&s](const auto& req, auto& res, const std::string& text) {
                  send_json(res, s.export_field(parse_json(text), if_match(req)));
                }));
    server.Post("/api/render", wrap_body([&s](const auto& req, auto& res, const std::string& text) {
                  send_json(res, s.render_video(parse_json(text), if_match(req)));
                }));
    server.Post("/api/seed_translation", wrap_body([&s](const auto&, auto& res, const std::string& text) {
                  send_json(res, s.seed_translation(parse_json(text)));
                }));
    server.Post("/api/chart_coordinates", wrap_body([&s](const auto&, auto& res, const std::string& text) {
                  send_json(res, s.chart_coordinates(parse_json(text)));
                }));
    server.Post("/api/upload", wrap_body([&s](const auto& req, auto& res, const std::string& bytes) {
                  if (!req.has_param("name")) throw RequestError(400, "upload: say the file name (?name=mesh.obj)");
                  send_json(res, s.upload_mesh(req.get_param_value("name"), bytes));
                }));
    lcs_routes();
    // Every other request with a body: read within the limit too (httplib would read it
    // whole into memory), then 404.
    const auto no_such = wrap_body([](const auto& req, auto& res, const std::string&) {
      throw RequestError(404, fmt::format("{} {}: no such resource", req.method, req.path.substr(0, 200)));
      (void)res;
    });
    server.Post(".*", no_such);
    server.Put(".*", no_such);
    server.Patch(".*", no_such);
    server.Delete(".*", no_such);
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
    Connections& conns = connections;
    const ServerOptions& o = options;
    server.set_pre_routing_handler([loopback, &conns, &o](const httplib::Request& req, httplib::Response& res) {
      // The headers are in. A body must follow within request_timeout (read_body disarms
      // the deadline once it is read); a request without one is answered without a
      // deadline (edits and renders may take a while).
      const bool has_body = req.has_header("Transfer-Encoding") ||
                            (req.has_header("Content-Length") && req.get_header_value("Content-Length") != "0");
      if (has_body) {
        conns.arm(t_connection.copy, after(o.request_timeout), true);
      } else {
        conns.disarm(t_connection.copy);
      }
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
    // The answer is being written: the client has answer_timeout to take it.
    server.set_post_routing_handler([&conns, &o](const httplib::Request&, httplib::Response&) {
      conns.arm(t_connection.copy, after(o.answer_timeout), false);
    });
    // One request per connection: a body left unread (refused before reading it, or cut
    // at the limit) is never read as a next request, and no idle connection holds a
    // worker. (On loopback a new connection costs tens of microseconds.)
    server.set_keep_alive_max_count(1);
    const auto microseconds = [](double x) {
      return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::duration<double>(x));
    };
    server.set_read_timeout(microseconds(std::min(5.0, o.request_timeout)));
    server.set_write_timeout(microseconds(std::min(5.0, o.answer_timeout)));
    const size_t threads = static_cast<size_t>(std::max(2, o.threads));
    server.new_task_queue = [this, threads] {
      return new WatchedPool(threads, connections, port, options.request_timeout, options.max_head);
    };

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
  impl_->session.interrupt();
  impl_->connections.cut_all();
  impl_->server.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

}  // namespace tvf::serve
