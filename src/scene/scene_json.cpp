#include "tvf/scene/scene_json.h"

#include "tvf/core/atomic_output.h"
#include "tvf/core/error.h"
#include "tvf/core/json_text.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <optional>
#include <sstream>

#include <Eigen/LU>

// Reading is validation: every value is checked where it is read, and the first problem
// throws a tvf::Error "<label>: <json path>: <one sentence>". The checks, in the order a
// scene is read: the version, unknown keys, the domain (which fixes the arity of every
// position), the time range (which bounds every t), then the design.

namespace tvf {
namespace {

using json = nlohmann::json;

constexpr SingularType kSingularTypes[] = {
    SingularType::source,     SingularType::sink,           SingularType::saddle,
    SingularType::ccw_center, SingularType::cw_center,      SingularType::repelling_focus,
    SingularType::attracting_focus};
constexpr BifurcationType kBifurcationTypes[] = {
    BifurcationType::saddle_source_cancellation, BifurcationType::saddle_sink_creation,
    BifurcationType::saddle_source_creation, BifurcationType::saddle_sink_cancellation,
    BifurcationType::hopf_supercritical, BifurcationType::hopf_subcritical};

// Where a planar polyline (x, y of `p`) crosses or touches itself: the first points of
// two segments that meet although they are not neighbours, or of two neighbours that fold
// back onto each other (collinear, the second turning back along the first). Zero-length
// segments are skipped (the segments either side of one are neighbours), and a closed
// polyline's first and last segments are neighbours at the point they share. Orientation
// tests with a tolerance of 1e-12 of the polyline's extent.
std::optional<std::pair<size_t, size_t>> self_crossing(const std::vector<Vec3>& p) {
  std::vector<size_t> seg;  // segments seg[k] → seg[k] + 1
  for (size_t i = 0; i + 1 < p.size(); ++i)
    if (p[i].head<2>() != p[i + 1].head<2>()) seg.push_back(i);
  if (seg.size() < 2) return std::nullopt;
  double extent = 0;
  for (const Vec3& x : p) extent = std::max(extent, (x - p.front()).head<2>().norm());
  const double eps = 1e-12 * extent * extent;
  auto cross = [](const Eigen::Vector2d& u, const Eigen::Vector2d& v) { return u.x() * v.y() - u.y() * v.x(); };
  auto at = [&](size_t i) -> Eigen::Vector2d { return p[i].head<2>(); };
  // Whether c, known to be on the line through a and b, lies within the segment ab.
  auto within = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
    return (c - a).dot(b - a) >= -eps && (c - b).dot(a - b) >= -eps;
  };
  auto meet = [&](size_t i, size_t j) {
    const Eigen::Vector2d a = at(i), b = at(i + 1), c = at(j), d = at(j + 1);
    const double o1 = cross(b - a, c - a), o2 = cross(b - a, d - a), o3 = cross(d - c, a - c), o4 = cross(d - c, b - c);
    auto sign = [&](double o) { return std::abs(o) <= eps ? 0 : (o > 0 ? 1 : -1); };
    const int s1 = sign(o1), s2 = sign(o2), s3 = sign(o3), s4 = sign(o4);
    if (s1 * s2 < 0 && s3 * s4 < 0) return true;
    return (s1 == 0 && within(a, b, c)) || (s2 == 0 && within(a, b, d)) || (s3 == 0 && within(c, d, a)) ||
           (s4 == 0 && within(c, d, b));
  };
  const bool closed = p.front().head<2>() == p.back().head<2>();
  for (size_t k = 0; k + 1 < seg.size(); ++k) {
    const Eigen::Vector2d u = at(seg[k] + 1) - at(seg[k]), v = at(seg[k + 1] + 1) - at(seg[k + 1]);
    if (std::abs(cross(u, v)) <= 1e-12 * u.norm() * v.norm() && u.dot(v) < 0) return std::pair{seg[k], seg[k + 1]};
    for (size_t l = k + 2; l < seg.size(); ++l) {
      if (closed && k == 0 && l + 1 == seg.size()) continue;
      if (meet(seg[k], seg[l])) return std::pair{seg[k], seg[l]};
    }
  }
  return std::nullopt;
}

constexpr Generator kGenerators[] = {Generator::basis, Generator::constrained,
                                     Generator::spacetime, Generator::deform};
constexpr Weights kWeights[] = {Weights::cotan, Weights::uniform, Weights::mean_value};
constexpr SolverMethod kSolverMethods[] = {SolverMethod::automatic, SolverMethod::modes, SolverMethod::cg,
                                           SolverMethod::bicgstab};

constexpr FluxBoundary kFluxBoundaries[] = {FluxBoundary::no_flux, FluxBoundary::open};

constexpr int kMaxFrames = 100'000;
// The range of numbers a scene may give (docs/scene_reference.md, "Limits").
constexpr double kMaxMagnitude = 1e15;
constexpr double kMinPositive = 1e-12;
// A span (time range, grid cell) must be at least this fraction of the magnitude of its
// ends, so that its frame times or vertex positions stay distinct.
constexpr double kMinRelativeSpan = 1e-9;
constexpr double kMaxTemporalWeight = 1e6;
constexpr int kMaxSphereSubdivisions = 9;  // make_icosphere's limit

std::string join_key(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}
std::string join_index(const std::string& path, size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

// ---------------------------------------------------------------------------------------
// Compact and pretty printing (canonical key order, short containers on one line).

// Rank of a key in the canonical order; DESIGN §10's order for every object of the format
// is a subsequence of this list. Keys not listed follow, alphabetically.
int key_rank(const std::string& key) {
  static constexpr const char* kOrder[] = {
      "tvf", "description", "op", "frame", "kind", "t", "domain", "grid", "mesh", "sphere", "torus",
      "size", "min", "max", "subdivisions", "radius", "nu", "nv", "major_radius",
      "minor_radius", "time", "frames", "range", "generator", "solver", "weights",
      "temporal_weight", "tolerance", "region_radius", "method", "keyframe_topology", "links",
      "bifurcation_times", "path_separation", "falloff", "base", "type", "jacobian",
      "at", "from", "to", "vector", "path", "pathline", "attach", "elements", "keyframes", "matrix",
      "m", "transform", "sx", "sy", "theta", "translate", "rotate", "scale", "time_scale",
      "angle", "streamlines", "seed", "keys", "points", "speed", "field", "deform", "edits",
      "incompressible", "boundary", "pair", "strength", "window"};
  for (size_t i = 0; i < std::size(kOrder); ++i)
    if (key == kOrder[i]) return static_cast<int>(i);
  return static_cast<int>(std::size(kOrder));
}

std::vector<std::pair<const std::string*, const json*>> ordered_items(const json& object) {
  std::vector<std::pair<const std::string*, const json*>> items;
  for (auto it = object.begin(); it != object.end(); ++it) items.emplace_back(&it.key(), &it.value());
  std::stable_sort(items.begin(), items.end(), [](const auto& a, const auto& b) {
    return key_rank(*a.first) < key_rank(*b.first);
  });
  return items;
}

// Stops once `out` is longer than `limit` (the text is then cut by the caller): a value
// quoted in a message is written only as far as it is shown, and the recursion is no
// deeper than the characters written.
void write_compact(const json& v, std::string& out, size_t limit = std::string::npos) {
  if (out.size() > limit) return;
  if (v.is_array()) {
    out += '[';
    for (size_t i = 0; i < v.size() && out.size() <= limit; ++i) {
      if (i) out += ", ";
      write_compact(v[i], out, limit);
    }
    out += ']';
  } else if (v.is_object()) {
    out += '{';
    bool first = true;
    for (const auto& [k, x] : ordered_items(v)) {
      if (out.size() > limit) break;
      if (!first) out += ", ";
      first = false;
      out += json(*k).dump();
      out += ": ";
      write_compact(*x, out, limit);
    }
    out += '}';
  } else if (v.is_string() && limit != std::string::npos) {
    const std::string& text = v.get_ref<const std::string&>();
    out += json(text.substr(0, limit + 1)).dump();
  } else {
    out += v.dump();
  }
}

std::string compact(const json& v) {
  std::string s;
  write_compact(v, s);
  return s;
}

constexpr size_t kLineWidth = 96;

// `column` is where the value starts on its line (after the indent and any key).
void write_pretty(const json& v, size_t indent, size_t column, std::string& out) {
  const bool container = v.is_array() || v.is_object();
  if (container && !v.empty() && indent > 0) {
    std::string c = compact(v);
    if (column + c.size() + 1 <= kLineWidth) {  // + 1 for a trailing comma
      out += c;
      return;
    }
  }
  if (!container || v.empty()) {
    write_compact(v, out);
    return;
  }
  const std::string pad(indent + 2, ' ');
  out += v.is_array() ? "[\n" : "{\n";
  if (v.is_array()) {
    for (size_t i = 0; i < v.size(); ++i) {
      out += pad;
      write_pretty(v[i], indent + 2, pad.size(), out);
      out += i + 1 < v.size() ? ",\n" : "\n";
    }
  } else {
    const auto items = ordered_items(v);
    for (size_t i = 0; i < items.size(); ++i) {
      const std::string key = json(*items[i].first).dump() + ": ";
      out += pad;
      out += key;
      write_pretty(*items[i].second, indent + 2, pad.size() + key.size(), out);
      out += i + 1 < items.size() ? ",\n" : "\n";
    }
  }
  out += std::string(indent, ' ');
  out += v.is_array() ? ']' : '}';
}

// A value as messages quote it: numbers in their shortest form, strings quoted, long
// containers cut short.
std::string describe(const json& j) {
  if (j.is_number_float()) return fmt::format("{}", j.get<double>());
  if (j.is_null()) return "null";
  std::string s;
  write_compact(j, s, 60);
  if (s.size() > 60) s = s.substr(0, 56) + " ...";
  return s;
}

// ---------------------------------------------------------------------------------------
// The reader.

class Reader {
public:
  explicit Reader(std::string label) : label_(std::move(label)) {}

  Scene scene(const json& j, const std::string& source_path);

private:
  std::string label_;
  bool planar_ = true;
  std::optional<GridSpec> grid_;  // a grid domain's extent (edit positions must lie in it)
  TimeSampling time_;

  // An edit's position on a grid domain must lie on the grid: an edit names a feature of
  // the field there, and a move's target is where a bifurcation goes (issue 16).
  bool on_domain(const Vec3& p) const {
    if (!grid_) return true;
    const double eps = 1e-9 * (grid_->max - grid_->min).norm();
    return p.x() >= grid_->min.x() - eps && p.x() <= grid_->max.x() + eps && p.y() >= grid_->min.y() - eps &&
           p.y() <= grid_->max.y() + eps;
  }
  std::string domain_extent() const {
    return fmt::format("[{}, {}] × [{}, {}]", grid_->min.x(), grid_->max.x(), grid_->min.y(), grid_->max.y());
  }
  void check_on_domain(const Vec3& p, const std::string& where) const {
    if (!on_domain(p))
      fail(where, fmt::format("({}, {}) is outside the domain {}", p.x(), p.y(), domain_extent()));
  }
  // Whether the segment ab meets the grid's rectangle (clipped slab by slab).
  bool segment_meets_domain(const Vec3& a, const Vec3& b) const {
    const double eps = 1e-9 * (grid_->max - grid_->min).norm();
    double t0 = 0, t1 = 1;
    for (int k = 0; k < 2; ++k) {
      const double lo = grid_->min[k] - eps, hi = grid_->max[k] + eps, d = b[k] - a[k];
      if (d == 0) {
        if (a[k] < lo || a[k] > hi) return false;
        continue;
      }
      const double ta = (lo - a[k]) / d, tb = (hi - a[k]) / d;
      t0 = std::max(t0, std::min(ta, tb));
      t1 = std::min(t1, std::max(ta, tb));
      if (t0 > t1) return false;
    }
    return true;
  }
  // An element, streamline or path wholly off a grid domain constrains no vertex of it:
  // every generator would give the field without it (or none), so it is refused. A moving
  // element may enter, leave or cross the domain: its polyline of keys meeting it is enough.
  template <class Points, class Position>
  void check_reaches_domain(const Points& points, Position position, const std::string& where,
                            const char* what) const {
    if (!grid_) return;
    for (size_t i = 0; i < points.size(); ++i)
      if (on_domain(position(points[i])) ||
          (i > 0 && segment_meets_domain(position(points[i - 1]), position(points[i]))))
        return;
    fail(where, fmt::format("{} lies wholly outside the domain {}: it would constrain nothing there", what,
                            domain_extent()));
  }

  [[noreturn]] void fail(const std::string& where, const std::string& message) const {
    throw_input_error(label_, where, message);
  }

  // --- generic values
  void check_object(const json& j, const std::string& path, const char* what) const {
    if (!j.is_object()) fail(path, fmt::format("must be an object ({}), got {}", what, describe(j)));
  }
  // An object whose keys are all among `allowed`.
  void check_keys(const json& j, const std::string& path, const char* what,
                  std::initializer_list<const char*> allowed) const {
    check_object(j, path, what);
    for (auto it = j.begin(); it != j.end(); ++it) {
      const bool known = std::any_of(allowed.begin(), allowed.end(),
                                     [&](const char* k) { return it.key() == k; });
      if (!known) {
        std::string list;
        for (const char* k : allowed) list += (list.empty() ? "" : ", ") + std::string(k);
        fail(path, fmt::format("unknown key \"{}\" (expected one of {})", it.key(), list));
      }
    }
  }
  static const json* get(const json& obj, const char* key) {
    const auto it = obj.find(key);
    return it == obj.end() ? nullptr : &*it;
  }
  const json& need(const json& obj, const std::string& path, const char* key,
                   const std::string& hint) const {
    if (const json* v = get(obj, key)) return *v;
    fail(path, fmt::format("missing key \"{}\" ({})", key, hint));
  }

  // Every number: finite and of magnitude at most kMaxMagnitude, so that the products and
  // squares the computations form stay finite (1e200 squared is not).
  double number(const json& j, const std::string& path) const {
    if (!j.is_number()) fail(path, fmt::format("must be a number, got {}", describe(j)));
    const double x = j.get<double>();
    if (!std::isfinite(x)) fail(path, fmt::format("must be a finite number, got {}", x));
    if (std::abs(x) > kMaxMagnitude)
      fail(path, fmt::format("must be a number of magnitude at most {:g} (larger values overflow in the "
                             "computations), got {}",
                             kMaxMagnitude, x));
    return x;
  }
  // Sizes, scales and radii (what the computations divide by): at least kMinPositive.
  double positive(const json& j, const std::string& path) const {
    const double x = number(j, path);
    if (!(x > 0)) fail(path, fmt::format("must be a number > 0, got {}", x));
    if (x < kMinPositive)
      fail(path, fmt::format("must be at least {:g} (smaller values overflow what is divided by them), got {}",
                             kMinPositive, x));
    return x;
  }
  double non_negative(const json& j, const std::string& path) const {
    const double x = number(j, path);
    if (!(x >= 0)) fail(path, fmt::format("must be a number ≥ 0, got {}", x));
    return x;
  }
  // An integer in [lo, hi]; 3.0 counts as an integer (as in JSON Schema), 1e12 is refused
  // without overflow.
  long long integer(const json& j, const std::string& path, long long lo, long long hi) const {
    const std::string range = hi == std::numeric_limits<long long>::max()
                                  ? fmt::format("an integer ≥ {}", lo)
                                  : fmt::format("an integer in [{}, {}]", lo, hi);
    auto bad = [&] { fail(path, fmt::format("must be {}, got {}", range, describe(j))); };
    if (j.is_number_unsigned()) {
      const auto u = j.get<std::uint64_t>();
      if (u > static_cast<std::uint64_t>(hi)) bad();
      const auto v = static_cast<long long>(u);
      if (v < lo) bad();
      return v;
    }
    if (j.is_number_integer()) {
      const auto v = j.get<std::int64_t>();
      if (v < lo || v > hi) bad();
      return static_cast<long long>(v);
    }
    if (j.is_number_float()) {
      const double x = j.get<double>();
      if (!std::isfinite(x) || x != std::floor(x) || x < static_cast<double>(lo) ||
          x > static_cast<double>(hi))
        bad();
      return static_cast<long long>(x);
    }
    bad();
    return 0;
  }
  std::string string(const json& j, const std::string& path) const {
    if (!j.is_string()) fail(path, fmt::format("must be a string, got {}", describe(j)));
    return j.get<std::string>();
  }
  const json& array(const json& j, const std::string& path, size_t min_items,
                    const char* what) const {
    if (!j.is_array()) fail(path, fmt::format("must be an array of {}, got {}", what, describe(j)));
    if (j.size() < min_items)
      fail(path, fmt::format("needs at least {} {}, got {}", min_items, what, j.size()));
    return j;
  }
  template <class E, size_t N>
  E enumeration(const json& j, const std::string& path, const E (&all)[N], const char* what) const {
    const std::string s = string(j, path);
    std::string list;
    for (E e : all) {
      if (s == to_string(e)) return e;
      list += (list.empty() ? "" : ", ") + std::string(to_string(e));
    }
    fail(path, fmt::format("unknown {} \"{}\" (expected one of {})", what, s, list));
  }

  // --- positions and times
  const char* domain_words() const { return planar_ ? "on a grid domain" : "on a surface domain"; }
  const char* point_form() const { return planar_ ? "[x, y]" : "[x, y, z]"; }
  const char* path_point_form() const { return planar_ ? "[x, y, t]" : "[x, y, z, t]"; }

  // n numbers; `form` says what they mean.
  std::vector<double> numbers(const json& j, const std::string& path, size_t n,
                              const char* form) const {
    if (!j.is_array() || j.size() != n) {
      const std::string got =
          j.is_array() ? fmt::format("{} numbers: {}", j.size(), describe(j)) : describe(j);
      fail(path, fmt::format("must be {} ({} numbers) {}, got {}", form, n, domain_words(), got));
    }
    std::vector<double> x(n);
    for (size_t i = 0; i < n; ++i) x[i] = number(j[i], join_index(path, i));
    return x;
  }
  Vec3 position(const json& j, const std::string& path) const {
    const auto x = numbers(j, path, planar_ ? 2 : 3, point_form());
    return {x[0], x[1], planar_ ? 0.0 : x[2]};
  }
  void check_time(double t, const std::string& where) const {
    if (t < time_.t0 || t > time_.t1)
      fail(where, fmt::format("t = {} is outside the time range [{}, {}]", t, time_.t0, time_.t1));
  }
  PathPoint path_point(const json& j, const std::string& path) const {
    const auto x = numbers(j, path, planar_ ? 3 : 4, path_point_form());
    PathPoint p;
    p.position = {x[0], x[1], planar_ ? 0.0 : x[2]};
    p.t = x.back();
    check_time(p.t, path);
    return p;
  }
  double key_time(const json& obj, const std::string& path, const char* hint) const {
    const double t = number(need(obj, path, "t", hint), join_key(path, "t"));
    check_time(t, join_key(path, "t"));
    return t;
  }
  void check_after(double previous, double t, const std::string& where, const char* what) const {
    if (!(t > previous))
      fail(where, fmt::format("t = {} does not come after the previous {}'s t = {} ({})", t,
                              what, previous, "times must strictly increase"));
  }
  std::vector<PathPoint> path_points(const json& j, const std::string& path, size_t min_items) const {
    const std::string what = fmt::format("{} points", path_point_form());
    array(j, path, min_items, what.c_str());
    std::vector<PathPoint> points;
    for (size_t i = 0; i < j.size(); ++i) {
      const std::string where = join_index(path, i);
      points.push_back(path_point(j[i], where));
      if (i > 0) check_after(points[i - 1].t, points[i].t, where, "point");
    }
    return points;
  }
  Mat2 matrix2(const json& j, const std::string& path) const {
    auto bad = [&] {
      fail(path, fmt::format("must be a 2×2 matrix [[a, b], [c, d]], got {}", describe(j)));
    };
    if (!j.is_array() || j.size() != 2) bad();
    Mat2 m;
    for (size_t r = 0; r < 2; ++r) {
      if (!j[r].is_array() || j[r].size() != 2) bad();
      for (size_t c = 0; c < 2; ++c)
        m(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) =
            number(j[r][c], join_index(join_index(path, r), c));
    }
    return m;
  }
  // A singular element's Jacobian: invertible, so that the singularity is isolated and has
  // an index (the sign of det J).
  Mat2 jacobian_matrix(const json& j, const std::string& path) const {
    const Mat2 m = matrix2(j, path);
    if (m.determinant() == 0)
      fail(path, fmt::format("must be invertible (det ≠ 0) so that the singularity is isolated, "
                             "got {}",
                             describe(j)));
    return m;
  }
  std::vector<TransformKey> transform_keys(const json& j, const std::string& path) const {
    array(j, path, 0, "transform keys {\"t\", \"sx\", \"sy\", \"theta\"}");
    std::vector<TransformKey> keys;
    for (size_t i = 0; i < j.size(); ++i) {
      const std::string p = join_index(path, i);
      const json& k = j[i];
      check_keys(k, p, "a transform key", {"t", "sx", "sy", "theta"});
      TransformKey key;
      key.t = key_time(k, p, "the time of the key");
      if (i > 0) check_after(keys.back().t, key.t, join_key(p, "t"), "key");
      if (const json* v = get(k, "sx")) key.sx = positive(*v, join_key(p, "sx"));
      if (const json* v = get(k, "sy")) key.sy = positive(*v, join_key(p, "sy"));
      if (const json* v = get(k, "theta")) key.theta = number(*v, join_key(p, "theta"));
      keys.push_back(key);
    }
    return keys;
  }

  // --- parts of the scene
  Domain domain(const json& j) const;
  GridSpec grid(const json& j, const std::string& path) const;
  TimeSampling time(const json& j) const;
  SolverSettings solver(const json& j) const;
  Element element(const json& j, const std::string& path) const;
  SingularElement singular(const json& j, const std::string& path) const;
  RegularElement regular(const json& j, const std::string& path) const;
  BifurcationElement bifurcation(const json& j, const std::string& path) const;
  StreaklineElement streakline(const json& j, const std::string& path) const;
  std::vector<Element> elements(const json& j, const std::string& path) const;
  std::vector<Keyframe> keyframes(const json& j) const;
  void keyframe_topology(const json& solver, Scene& s) const;
  KeyframeElement keyframe_element(const json& j, const std::string& path) const;
  KeyframeStreamline keyframe_streamline(const json& j, const std::string& path) const;
  Deform deform(const json& j) const;
  std::vector<Edit> edits(const json& j) const;
  std::optional<FluxBoundary> incompressible(const json& j) const;
  Edit edit(const json& j, const std::string& path) const;
};

// ---------------------------------------------------------------------------------------
// Writing (canonical form). Planar scenes get 2-D points.

json point_json(const Vec3& p, bool planar) {
  return planar ? json::array({p.x(), p.y()}) : json::array({p.x(), p.y(), p.z()});
}
json path_point_json(const PathPoint& p, bool planar) {
  return planar ? json::array({p.position.x(), p.position.y(), p.t})
                : json::array({p.position.x(), p.position.y(), p.position.z(), p.t});
}
json path_json(const std::vector<PathPoint>& points, bool planar) {
  json a = json::array();
  for (const PathPoint& p : points) a.push_back(path_point_json(p, planar));
  return a;
}
json matrix_json(const Mat2& m) {
  return json::array({json::array({m(0, 0), m(0, 1)}), json::array({m(1, 0), m(1, 1)})});
}
json transform_json(const std::vector<TransformKey>& keys) {
  json a = json::array();
  for (const TransformKey& k : keys)
    a.push_back({{"t", k.t}, {"sx", k.sx}, {"sy", k.sy}, {"theta", k.theta}});
  return a;
}

json element_json(const Element& element, bool planar) {
  json j;
  if (const auto* s = std::get_if<SingularElement>(&element)) {
    j["kind"] = "singular";
    if (s->type)
      j["type"] = to_string(*s->type);
    else
      j["jacobian"] = matrix_json(s->jacobian);
    j["path"] = path_json(s->path, planar);
    j["transform"] = transform_json(s->transform);
  } else if (const auto* r = std::get_if<RegularElement>(&element)) {
    j["kind"] = "regular";
    j["pathline"] = path_json(r->pathline, planar);
    j["attach"] = r->attach;
  } else if (const auto* sl = std::get_if<StreaklineElement>(&element)) {
    j["kind"] = "streakline";
    j["points"] = json::array();
    for (const Vec3& p : sl->points) j["points"].push_back(point_json(p, planar));
    j["t"] = sl->t;
    j["from"] = sl->from;
    j["attach"] = sl->attach;
  } else {
    const auto& b = std::get<BifurcationElement>(element);
    j["kind"] = "bifurcation";
    j["type"] = to_string(b.type);
    j["at"] = path_point_json(b.at, planar);
    j["scale"] = b.scale;
    j["time_scale"] = b.time_scale;
    j["angle"] = b.angle;
  }
  return j;
}

json keyframe_json(const Keyframe& k, bool planar) {
  json j;
  j["t"] = k.t;
  if (!k.field.empty()) {
    j["field"] = k.field;
    if (k.elements.empty() && k.streamlines.empty()) return j;
  }
  j["elements"] = json::array();
  for (const KeyframeElement& e : k.elements) {
    json x;
    x["kind"] = e.kind;
    if (e.kind == "singular") {
      if (e.type)
        x["type"] = to_string(*e.type);
      else
        x["jacobian"] = matrix_json(e.jacobian);
    }
    x["at"] = point_json(e.at, planar);
    if (e.kind == "regular") x["vector"] = point_json(e.vector, planar);
    j["elements"].push_back(x);
  }
  j["streamlines"] = json::array();
  for (const KeyframeStreamline& s : k.streamlines) {
    json points = json::array();
    for (const Vec3& p : s.points) points.push_back(point_json(p, planar));
    j["streamlines"].push_back({{"points", points}, {"speed", s.speed}});
  }
  return j;
}

json deform_json(const Deform& d, bool planar) {
  json out;
  out["base"]["elements"] = json::array();
  for (const Element& e : d.base) out["base"]["elements"].push_back(element_json(e, planar));
  if (d.matrix) {
    out["matrix"] = json::array();
    for (const MatrixKey& k : *d.matrix) out["matrix"].push_back({{"t", k.t}, {"m", matrix_json(k.m)}});
  }
  if (d.transform) out["transform"] = transform_json(*d.transform);
  out["streamlines"] = json::array();
  for (const DeformStreamline& line : d.streamlines) {
    json keys = json::array();
    for (const StreamlineKey& k : line.keys)
      keys.push_back({{"t", k.t}, {"translate", point_json(k.translate, planar)}, {"rotate", k.rotate}, {"scale", k.scale}});
    out["streamlines"].push_back({{"seed", point_json(line.seed, planar)}, {"keys", std::move(keys)}});
  }
  return out;
}

// The solver block: every key of SolverSettings, written here and read by Reader::solver.
// The key-frame topology keys (solver.keyframe_topology, links, bifurcation_times,
// path_separation) are read by Reader::keyframe_topology once the key frames are known.
json solver_json(const SolverSettings& s) {
  json j = {{"weights", to_string(s.weights)},
            {"temporal_weight", s.temporal_weight},
            {"tolerance", s.tolerance},
            {"region_radius", s.region_radius},
            {"method", to_string(s.method)}};
  if (s.keyframe_topology == KeyframeTopology::matched) {
    j["keyframe_topology"] = "matched";
    json links = json::array();
    for (const KeyframeLink& l : s.links)
      links.push_back({{"from", {l.from_keyframe, l.from_element}}, {"to", {l.to_keyframe, l.to_element}}});
    if (!links.empty()) j["links"] = links;
    if (!s.bifurcation_times.empty()) j["bifurcation_times"] = s.bifurcation_times;
    if (s.path_separation) j["path_separation"] = *s.path_separation;
  }
  return j;
}

// ---------------------------------------------------------------------------------------
// Reading, part by part.

GridSpec Reader::grid(const json& j, const std::string& path) const {
  check_keys(j, path, "a grid {\"size\": [nx, ny], \"min\": [x, y], \"max\": [x, y]}",
             {"size", "min", "max"});
  GridSpec g;
  if (const json* size = get(j, "size")) {
    const std::string p = join_key(path, "size");
    if (!size->is_array() || size->size() != 2)
      fail(p, fmt::format("must be [nx, ny] (2 integers), got {}", describe(*size)));
    constexpr long long kNoBound = std::numeric_limits<long long>::max();
    const long long nx = integer((*size)[0], join_index(p, 0), 2, kNoBound);
    const long long ny = integer((*size)[1], join_index(p, 1), 2, kNoBound);
    // Each factor is bounded first, so the product cannot overflow.
    if (nx > kMaxGridVertices || ny > kMaxGridVertices || nx * ny > kMaxGridVertices)
      fail(p, fmt::format("{} × {} vertices is more than the {} a grid may have", nx, ny,
                          kMaxGridVertices));
    g.nx = static_cast<int>(nx);
    g.ny = static_cast<int>(ny);
  }
  auto corner = [&](const char* key, Vec2& out) {
    if (const json* c = get(j, key)) {
      const std::string p = join_key(path, key);
      if (!c->is_array() || c->size() != 2)
        fail(p, fmt::format("must be a point [x, y] (2 numbers), got {}", describe(*c)));
      out = {number((*c)[0], join_index(p, 0)), number((*c)[1], join_index(p, 1))};
    }
  };
  corner("min", g.min);
  corner("max", g.max);
  if (!(g.max.x() > g.min.x() && g.max.y() > g.min.y()))
    fail(join_key(path, "max"),
         fmt::format("must be greater than min in both coordinates, got min [{}, {}] and max [{}, {}]",
                     g.min.x(), g.min.y(), g.max.x(), g.max.y()));
  // Cells must stay distinct in floating point: a box of [-1, 1e14] × [-1, 1] on 65 × 65
  // vertices has cells, one of [1e14, 1e14 + 1e-6] has not.
  for (int axis = 0; axis < 2; ++axis) {
    const double cell = (g.max[axis] - g.min[axis]) / ((axis == 0 ? g.nx : g.ny) - 1);
    const double magnitude = std::max({1.0, std::abs(g.min[axis]), std::abs(g.max[axis])});
    if (cell < kMinRelativeSpan * magnitude)
      fail(join_key(path, "max"),
           fmt::format("the box [{}, {}] × [{}, {}] is too narrow for its magnitude along {}: a cell must span at "
                       "least {:g} × max(1, |min|, |max|)",
                       g.min.x(), g.max.x(), g.min.y(), g.max.y(), axis == 0 ? "x" : "y", kMinRelativeSpan));
  }
  // Nor may its triangles be too thin for the mesh's own check (area ≥ 1e-14 of the
  // squared diagonal, mesh_validate.h), which would name no key.
  {
    const double cx = (g.max.x() - g.min.x()) / (g.nx - 1), cy = (g.max.y() - g.min.y()) / (g.ny - 1);
    const double ex = g.max.x() - g.min.x(), ey = g.max.y() - g.min.y();
    if (0.5 * (cx / ex) * (cy / ex) / (1 + (ey / ex) * (ey / ex)) < 2e-14)
      fail(join_key(path, "max"),
           fmt::format("the box [{}, {}] × [{}, {}] is too elongated for a grid of {} × {} vertices: its cells would "
                       "be degenerate (zero-area) triangles",
                       g.min.x(), g.max.x(), g.min.y(), g.max.y(), g.nx, g.ny));
  }
  return g;
}

Domain Reader::domain(const json& j) const {
  const std::string path = "domain";
  check_keys(j, path, "one of grid, mesh, sphere, torus", {"grid", "mesh", "sphere", "torus"});
  if (j.size() != 1) {
    std::string given;
    for (auto it = j.begin(); it != j.end(); ++it)
      given += (given.empty() ? "" : " and ") + it.key();
    fail(path, fmt::format("must name exactly one domain (grid, mesh, sphere or torus), got {}",
                           given.empty() ? std::string("none") : given));
  }
  Domain d;
  if (const json* g = get(j, "grid")) d.grid = grid(*g, "domain.grid");
  if (const json* m = get(j, "mesh")) {
    d.mesh = string(*m, "domain.mesh");
    if (d.mesh.empty())
      fail("domain.mesh", "must be the path of an OBJ, PLY or OFF file, got an empty string");
  }
  if (const json* s = get(j, "sphere")) {
    const std::string p = "domain.sphere";
    check_keys(*s, p, "a sphere {\"subdivisions\", \"radius\"}", {"subdivisions", "radius"});
    SphereSpec sphere;
    if (const json* v = get(*s, "subdivisions"))
      sphere.subdivisions =
          static_cast<int>(integer(*v, join_key(p, "subdivisions"), 0, kMaxSphereSubdivisions));
    if (const json* v = get(*s, "radius")) sphere.radius = positive(*v, join_key(p, "radius"));
    d.sphere = sphere;
  }
  if (const json* t = get(j, "torus")) {
    const std::string p = "domain.torus";
    check_keys(*t, p, "a torus {\"nu\", \"nv\", \"major_radius\", \"minor_radius\"}",
               {"nu", "nv", "major_radius", "minor_radius"});
    TorusSpec torus;
    constexpr long long kNoBound = std::numeric_limits<long long>::max();
    long long nu = torus.nu, nv = torus.nv;
    if (const json* v = get(*t, "nu")) nu = integer(*v, join_key(p, "nu"), 3, kNoBound);
    if (const json* v = get(*t, "nv")) nv = integer(*v, join_key(p, "nv"), 3, kNoBound);
    if (nu > kMaxGridVertices || nv > kMaxGridVertices || nu * nv > kMaxGridVertices)
      fail(p, fmt::format("nu × nv = {} × {} vertices is more than the {} a torus may have", nu,
                          nv, kMaxGridVertices));
    torus.nu = static_cast<int>(nu);
    torus.nv = static_cast<int>(nv);
    if (const json* v = get(*t, "major_radius"))
      torus.major_radius = positive(*v, join_key(p, "major_radius"));
    if (const json* v = get(*t, "minor_radius"))
      torus.minor_radius = positive(*v, join_key(p, "minor_radius"));
    if (!(torus.minor_radius < torus.major_radius))
      fail(join_key(p, "minor_radius"),
           fmt::format("must be less than major_radius ({}) so that the torus does not cross "
                       "itself, got {}",
                       torus.major_radius, torus.minor_radius));
    d.torus = torus;
  }
  return d;
}

TimeSampling Reader::time(const json& j) const {
  check_keys(j, "time", "{\"frames\": N, \"range\": [t0, t1]}", {"frames", "range"});
  TimeSampling s;
  if (const json* f = get(j, "frames"))
    s.frames = static_cast<int>(integer(*f, "time.frames", 2, kMaxFrames));
  if (const json* r = get(j, "range")) {
    if (!r->is_array() || r->size() != 2)
      fail("time.range", fmt::format("must be [t0, t1] (2 numbers), got {}", describe(*r)));
    s.t0 = number((*r)[0], "time.range[0]");
    s.t1 = number((*r)[1], "time.range[1]");
    if (!(s.t0 < s.t1))
      fail("time.range", fmt::format("must have t0 < t1, got [{}, {}]", s.t0, s.t1));
    if (s.t1 - s.t0 < kMinRelativeSpan * std::max({1.0, std::abs(s.t0), std::abs(s.t1)}))
      fail("time.range", fmt::format("[{}, {}] is too short for its magnitude: t1 − t0 must be at least {:g} × "
                                     "max(1, |t0|, |t1|) so that frame times stay distinct",
                                     s.t0, s.t1, kMinRelativeSpan));
  }
  return s;
}

SolverSettings Reader::solver(const json& j) const {
  check_keys(j, "solver", "solver settings",
             {"weights", "temporal_weight", "tolerance", "region_radius", "method", "keyframe_topology", "links",
              "bifurcation_times", "path_separation"});
  SolverSettings s;
  if (const json* v = get(j, "weights")) s.weights = enumeration(*v, "solver.weights", kWeights, "weights");
  if (const json* v = get(j, "temporal_weight")) {
    s.temporal_weight = non_negative(*v, "solver.temporal_weight");
    if (s.temporal_weight > kMaxTemporalWeight)
      fail("solver.temporal_weight",
           fmt::format("must be at most {:g} (a larger weight makes the space-time system too ill-conditioned to "
                       "solve), got {}",
                       kMaxTemporalWeight, s.temporal_weight));
  }
  if (const json* v = get(j, "tolerance")) {
    s.tolerance = number(*v, "solver.tolerance");
    if (!(s.tolerance > 0 && s.tolerance < 1))
      fail("solver.tolerance", fmt::format("must be in (0, 1), got {}", s.tolerance));
  }
  if (const json* v = get(j, "region_radius")) s.region_radius = positive(*v, "solver.region_radius");
  if (const json* v = get(j, "method"))
    s.method = enumeration(*v, "solver.method", kSolverMethods, "solver method");
  return s;
}

SingularElement Reader::singular(const json& j, const std::string& path) const {
  check_keys(j, path, "a singular element", {"kind", "type", "jacobian", "path", "transform"});
  SingularElement e;
  const json* type = get(j, "type");
  const json* jacobian = get(j, "jacobian");
  if (type && jacobian) fail(path, "give either \"type\" or \"jacobian\", not both");
  if (!type && !jacobian)
    fail(path, "a singular element needs a \"type\" (source, sink, saddle, ccw_center, cw_center, "
               "repelling_focus or attracting_focus) or a \"jacobian\" [[a, b], [c, d]]");
  if (type) {
    e.type = enumeration(*type, join_key(path, "type"), kSingularTypes, "singular type");
    e.jacobian = jacobian_of(*e.type);
  } else {
    e.jacobian = jacobian_matrix(*jacobian, join_key(path, "jacobian"));
  }
  const std::string hint = fmt::format("a singular element needs a path of {} points; one point "
                                       "makes a fixed element",
                                       path_point_form());
  e.path = path_points(need(j, path, "path", hint), join_key(path, "path"), 1);
  check_reaches_domain(e.path, [](const PathPoint& p) { return p.position; }, join_key(path, "path"),
                       e.path.size() == 1 ? "the element" : "the element's path");
  if (const json* t = get(j, "transform")) e.transform = transform_keys(*t, join_key(path, "transform"));
  return e;
}

RegularElement Reader::regular(const json& j, const std::string& path) const {
  check_keys(j, path, "a regular element", {"kind", "pathline", "attach"});
  RegularElement e;
  const std::string hint =
      fmt::format("a regular element needs a pathline of at least 2 {} points", path_point_form());
  e.pathline = path_points(need(j, path, "pathline", hint), join_key(path, "pathline"), 2);
  check_reaches_domain(e.pathline, [](const PathPoint& p) { return p.position; }, join_key(path, "pathline"),
                       "the pathline");
  if (const json* a = get(j, "attach")) e.attach = non_negative(*a, join_key(path, "attach"));
  return e;
}

BifurcationElement Reader::bifurcation(const json& j, const std::string& path) const {
  check_keys(j, path, "a bifurcation element",
             {"kind", "type", "at", "scale", "time_scale", "angle"});
  BifurcationElement e;
  e.type = enumeration(need(j, path, "type", "the bifurcation's normal form"),
                       join_key(path, "type"), kBifurcationTypes, "bifurcation type");
  e.at = path_point(need(j, path, "at", fmt::format("the place and time {} of the bifurcation",
                                                    path_point_form())),
                    join_key(path, "at"));
  check_on_domain(e.at.position, join_key(path, "at"));
  if (const json* v = get(j, "scale")) e.scale = positive(*v, join_key(path, "scale"));
  if (const json* v = get(j, "time_scale")) e.time_scale = positive(*v, join_key(path, "time_scale"));
  if (const json* v = get(j, "angle")) e.angle = number(*v, join_key(path, "angle"));
  return e;
}

// A sketched streakline (issue 20): the polyline it has at t, seed first, for dye
// released over [from, t]. Its points lie in a grid domain (snapped to a surface).
StreaklineElement Reader::streakline(const json& j, const std::string& path) const {
  check_keys(j, path, "a streakline element", {"kind", "points", "t", "from", "attach"});
  StreaklineElement e;
  const std::string what = fmt::format("{} points", point_form());
  const std::string points_path = join_key(path, "points");
  const json& points = need(j, path, "points",
                            fmt::format("the streakline's shape at t: at least 2 {} points, the seed first", point_form()));
  array(points, points_path, 2, what.c_str());
  double length = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const std::string where = join_index(points_path, i);
    e.points.push_back(position(points[i], where));
    check_on_domain(e.points.back(), where);
    if (i > 0) length += (e.points[i] - e.points[i - 1]).norm();
  }
  if (!(length > 0)) fail(points_path, "must have a length > 0 (its points are all the same)");
  // At t the dye released at τ is one particle at one point, and tvf carries it along the
  // sketch away from the seed (streakline_design.h): two parts of the sketch at one point
  // would be two particles there at once, which no field can carry (they would be one).
  if (planar_)
    if (const auto crossing = self_crossing(e.points))
      fail(points_path, fmt::format("the sketch crosses or folds back onto itself (its segments from points[{}] "
                                    "and points[{}]): two parts of the dye cannot be at one point at t; sketch a "
                                    "streakline that does not meet itself",
                                    crossing->first, crossing->second));
  e.t = key_time(j, path, "the time at which the dye has the sketched shape");
  const std::string from_path = join_key(path, "from");
  e.from = number(need(j, path, "from", "the time the dye's release starts, before t"), from_path);
  check_time(e.from, from_path);
  if (!(e.from < e.t))
    fail(from_path, fmt::format("from = {} must come before t = {} (the dye is released over [from, t])", e.from, e.t));
  if (const json* a = get(j, "attach")) e.attach = non_negative(*a, join_key(path, "attach"));
  return e;
}

Element Reader::element(const json& j, const std::string& path) const {
  check_object(j, path, "a design element with a \"kind\"");
  const std::string kind = string(
      need(j, path, "kind", "singular, regular, bifurcation or streakline"), join_key(path, "kind"));
  if (kind == "singular") return singular(j, path);
  if (kind == "regular") return regular(j, path);
  if (kind == "bifurcation") return bifurcation(j, path);
  if (kind == "streakline") return streakline(j, path);
  fail(join_key(path, "kind"),
       fmt::format("unknown element kind \"{}\" (expected one of singular, regular, bifurcation, streakline)", kind));
}

std::vector<Element> Reader::elements(const json& j, const std::string& path) const {
  array(j, path, 0, "design elements");
  std::vector<Element> out;
  for (size_t i = 0; i < j.size(); ++i) out.push_back(element(j[i], join_index(path, i)));
  return out;
}

KeyframeElement Reader::keyframe_element(const json& j, const std::string& path) const {
  check_object(j, path, "a key-frame element with a \"kind\"");
  KeyframeElement e;
  e.kind = string(need(j, path, "kind", "singular or regular"), join_key(path, "kind"));
  const std::string at_hint = fmt::format("the element's position {}", point_form());
  if (e.kind == "singular") {
    check_keys(j, path, "a key-frame singular element", {"kind", "type", "jacobian", "at"});
    const json* type = get(j, "type");
    const json* jacobian = get(j, "jacobian");
    if (type && jacobian) fail(path, "give either \"type\" or \"jacobian\", not both");
    if (!type && !jacobian)
      fail(path, "a singular element needs a \"type\" (source, sink, saddle, ccw_center, "
                 "cw_center, repelling_focus or attracting_focus) or a \"jacobian\" [[a, b], [c, d]]");
    if (type) {
      e.type = enumeration(*type, join_key(path, "type"), kSingularTypes, "singular type");
      e.jacobian = jacobian_of(*e.type);
    } else {
      e.jacobian = jacobian_matrix(*jacobian, join_key(path, "jacobian"));
    }
    e.at = position(need(j, path, "at", at_hint), join_key(path, "at"));
    check_on_domain(e.at, join_key(path, "at"));
  } else if (e.kind == "regular") {
    check_keys(j, path, "a key-frame regular element", {"kind", "at", "vector"});
    e.at = position(need(j, path, "at", at_hint), join_key(path, "at"));
    check_on_domain(e.at, join_key(path, "at"));
    e.vector = position(need(j, path, "vector", fmt::format("the field's vector {} there", point_form())),
                        join_key(path, "vector"));
    if (e.vector.isZero(0.0))
      fail(join_key(path, "vector"), "must not be zero (a regular element gives the field a direction)");
  } else {
    fail(join_key(path, "kind"),
         fmt::format("unknown key-frame element kind \"{}\" (expected one of singular, regular)", e.kind));
  }
  return e;
}

KeyframeStreamline Reader::keyframe_streamline(const json& j, const std::string& path) const {
  check_keys(j, path, "a streamline {\"points\", \"speed\"}", {"points", "speed"});
  KeyframeStreamline s;
  const std::string form = fmt::format("{} points", point_form());
  const json& points = array(need(j, path, "points", "at least 2 " + form),
                             join_key(path, "points"), 2, form.c_str());
  for (size_t i = 0; i < points.size(); ++i) {
    const std::string p = join_index(join_key(path, "points"), i);
    s.points.push_back(position(points[i], p));
    if (i > 0 && s.points[i] == s.points[i - 1])
      fail(p, "repeats the previous point (a streamline's direction would be undefined)");
  }
  check_reaches_domain(s.points, [](const Vec3& p) { return p; }, join_key(path, "points"), "the streamline");
  if (const json* v = get(j, "speed")) s.speed = positive(*v, join_key(path, "speed"));
  return s;
}

std::vector<Keyframe> Reader::keyframes(const json& j) const {
  array(j, "keyframes", 0, "key frames {\"t\", \"elements\", \"streamlines\", \"field\"}");
  std::vector<Keyframe> out;
  for (size_t i = 0; i < j.size(); ++i) {
    const std::string path = join_index("keyframes", i);
    const json& k = j[i];
    check_keys(k, path, "a key frame", {"t", "elements", "streamlines", "field"});
    Keyframe key;
    key.t = key_time(k, path, "the time of the key frame");
    if (i > 0) check_after(out.back().t, key.t, join_key(path, "t"), "key frame");
    if (const json* e = get(k, "elements")) {
      const std::string p = join_key(path, "elements");
      array(*e, p, 0, "key-frame elements");
      for (size_t m = 0; m < e->size(); ++m)
        key.elements.push_back(keyframe_element((*e)[m], join_index(p, m)));
    }
    if (const json* s = get(k, "streamlines")) {
      const std::string p = join_key(path, "streamlines");
      array(*s, p, 0, "streamlines");
      for (size_t m = 0; m < s->size(); ++m)
        key.streamlines.push_back(keyframe_streamline((*s)[m], join_index(p, m)));
    }
    if (const json* f = get(k, "field")) {
      key.field = string(*f, join_key(path, "field"));
      if (key.field.empty())
        fail(join_key(path, "field"), "must be the path of a field file, got an empty string");
      if (!key.elements.empty() || !key.streamlines.empty())
        fail(path, "give either a \"field\" file or \"elements\" and \"streamlines\", not both");
    }
    if (key.field.empty() && key.elements.empty() && key.streamlines.empty())
      fail(path, "a key frame needs at least one element or streamline, or a \"field\" file");
    out.push_back(std::move(key));
  }
  return out;
}

// solver.keyframe_topology, solver.links and solver.bifurcation_times (DESIGN §12;
// tvf/design/keyframe_topology.h), read once the key frames are known.
void Reader::keyframe_topology(const json& solver, Scene& s) const {
  constexpr KeyframeTopology kinds[] = {KeyframeTopology::free, KeyframeTopology::matched};
  if (const json* v = get(solver, "keyframe_topology"))
    s.solver.keyframe_topology = enumeration(*v, "solver.keyframe_topology", kinds, "key-frame topology");
  const bool matched = s.solver.keyframe_topology == KeyframeTopology::matched;
  for (const char* key : {"links", "bifurcation_times", "path_separation"})
    if (get(solver, key) && !matched)
      fail(join_key("solver", key), "applies only with \"keyframe_topology\": \"matched\"");
  if (!matched) return;
  if (s.generator != Generator::spacetime)
    fail("solver.keyframe_topology", fmt::format("\"matched\" applies to the spacetime generator, not \"{}\"",
                                                 to_string(s.generator)));
  if (s.keyframes.size() < 2)
    fail("solver.keyframe_topology",
         fmt::format("\"matched\" needs at least two key frames to match, got {}", s.keyframes.size()));
  const auto nk = static_cast<long long>(s.keyframes.size());
  if (const json* links = get(solver, "links")) {
    array(*links, "solver.links", 0, "links {\"from\": [k, i], \"to\": [k + 1, j]}");
    // (side, key frame, element): an element is carried from at most once and into at most
    // once, so a middle key frame's element may be linked both ways (a chain k−1 → k → k+1).
    std::vector<std::tuple<int, long long, long long>> used;
    for (size_t m = 0; m < links->size(); ++m) {
      const std::string path = join_index("solver.links", m);
      const json& l = (*links)[m];
      check_keys(l, path, "a link {\"from\": [k, i], \"to\": [k + 1, j]}", {"from", "to"});
      long long ends[2][2];
      std::string where[2];
      for (int e = 0; e < 2; ++e) {
        const char* key = e == 0 ? "from" : "to";
        const std::string p = join_key(path, key);
        const json& pair = need(l, path, key, "[key frame, element] indices");
        if (!pair.is_array() || pair.size() != 2)
          fail(p, fmt::format("must be [key frame, element] (two indices), got {}", describe(pair)));
        ends[e][0] = integer(pair[0], join_index(p, 0), 0, nk - 1);
        const auto ne = static_cast<long long>(s.keyframes[static_cast<size_t>(ends[e][0])].elements.size());
        if (ne == 0)
          fail(join_index(p, 0), fmt::format("keyframes[{}] has no elements to link", ends[e][0]));
        ends[e][1] = integer(pair[1], join_index(p, 1), 0, ne - 1);
        where[e] = fmt::format("keyframes[{}].elements[{}]", ends[e][0], ends[e][1]);
        if (s.keyframes[static_cast<size_t>(ends[e][0])].elements[static_cast<size_t>(ends[e][1])].kind != "singular")
          fail(p, fmt::format("{} is a regular element; only singular elements are linked", where[e]));
        for (const auto& u : used)
          if (u == std::tuple(e, ends[e][0], ends[e][1]))
            fail(p, fmt::format("{} is already linked {} by an earlier link", where[e],
                                e == 0 ? "into the next key frame" : "from the previous key frame"));
      }
      if (ends[1][0] != ends[0][0] + 1)
        fail(join_key(path, "to"), fmt::format("links key frame {} with key frame {}; a link joins a key frame "
                                               "with the next one (k and k + 1)",
                                               ends[0][0], ends[1][0]));
      const KeyframeElement& a = s.keyframes[static_cast<size_t>(ends[0][0])].elements[static_cast<size_t>(ends[0][1])];
      const KeyframeElement& b = s.keyframes[static_cast<size_t>(ends[1][0])].elements[static_cast<size_t>(ends[1][1])];
      auto name = [](const KeyframeElement& e) {
        return e.type ? std::string(to_string(*e.type))
                      : std::string(e.jacobian.determinant() < 0 ? "Jacobian of index −1" : "Jacobian of index +1");
      };
      const bool same = a.type && b.type ? *a.type == *b.type
                                         : (a.jacobian.determinant() < 0) == (b.jacobian.determinant() < 0);
      if (!same)
        fail(path, fmt::format("links a {} ({}) with a {} ({}); linked singularities must have the same type", name(a),
                               where[0], name(b), where[1]));
      used.emplace_back(0, ends[0][0], ends[0][1]);
      used.emplace_back(1, ends[1][0], ends[1][1]);
      s.solver.links.push_back({static_cast<int>(ends[0][0]), static_cast<int>(ends[0][1]),
                                static_cast<int>(ends[1][0]), static_cast<int>(ends[1][1])});
    }
  }
  if (const json* times = get(solver, "bifurcation_times")) {
    array(*times, "solver.bifurcation_times", 0, "times, one per interval between consecutive key frames");
    if (static_cast<long long>(times->size()) != nk - 1)
      fail("solver.bifurcation_times",
           fmt::format("needs one time per interval between consecutive key frames ({}), got {}", nk - 1,
                       times->size()));
    for (size_t k = 0; k < times->size(); ++k) {
      const std::string p = join_index("solver.bifurcation_times", k);
      const double t = number((*times)[k], p);
      const double t0 = s.keyframes[k].t, t1 = s.keyframes[k + 1].t;
      if (!(t > t0 && t < t1))
        fail(p, fmt::format("t = {} is not inside the interval ({}, {}) between keyframes[{}] and keyframes[{}]", t,
                            t0, t1, k, k + 1));
      s.solver.bifurcation_times.push_back(t);
    }
  }
  if (const json* v = get(solver, "path_separation"))
    s.solver.path_separation = non_negative(*v, "solver.path_separation");
}

Deform Reader::deform(const json& j) const {
  check_keys(j, "deform", "the deformation {\"base\", \"matrix\" or \"transform\", \"streamlines\"}",
             {"base", "matrix", "transform", "streamlines"});
  Deform out;
  const json& base = need(j, "deform", "base", "the field V(t0) to deform: {\"elements\": [...]}");
  check_keys(base, "deform.base", "the base field {\"elements\": [...]}", {"elements"});
  if (const json* e = get(base, "elements")) {
    out.base = elements(*e, "deform.base.elements");
    for (size_t i = 0; i < out.base.size(); ++i)
      if (std::holds_alternative<StreaklineElement>(out.base[i]))
        fail(join_key(join_index("deform.base.elements", i), "kind"),
             "a streakline needs the dye's time-varying flow, which a deform base (one static field) cannot hold; "
             "put it in the scene's elements with the constrained or spacetime generator");
  }
  const json* matrix = get(j, "matrix");
  const json* transform = get(j, "transform");
  if (matrix && transform) fail("deform", "give either \"matrix\" or \"transform\" keys, not both");
  if (matrix) {
    array(*matrix, "deform.matrix", 0, "matrix keys {\"t\", \"m\"}");
    out.matrix.emplace();
    double previous = 0;
    for (size_t i = 0; i < matrix->size(); ++i) {
      const std::string p = join_index("deform.matrix", i);
      const json& k = (*matrix)[i];
      check_keys(k, p, "a matrix key {\"t\", \"m\"}", {"t", "m"});
      const double t = key_time(k, p, "the time of the key");
      if (i > 0) check_after(previous, t, join_key(p, "t"), "key");
      previous = t;
      out.matrix->push_back({t, matrix2(need(k, p, "m", "the 2×2 matrix [[a, b], [c, d]] at t"), join_key(p, "m"))});
    }
  }
  if (transform) out.transform = transform_keys(*transform, "deform.transform");
  if (const json* s = get(j, "streamlines")) {
    array(*s, "deform.streamlines", 0, "streamlines {\"seed\", \"keys\"}");
    for (size_t i = 0; i < s->size(); ++i) {
      const std::string p = join_index("deform.streamlines", i);
      const json& line = (*s)[i];
      check_keys(line, p, "a streamline {\"seed\", \"keys\"}", {"seed", "keys"});
      DeformStreamline moved;
      moved.seed = position(need(line, p, "seed", fmt::format("where the streamline starts, {}", point_form())),
                            join_key(p, "seed"));
      const std::string kp = join_key(p, "keys");
      const json& keys = array(need(line, p, "keys", "its keyed motion [{\"t\", \"translate\", \"rotate\", \"scale\"}]"),
                               kp, 1, "keys {\"t\", \"translate\", \"rotate\", \"scale\"}");
      double previous = 0;
      for (size_t m = 0; m < keys.size(); ++m) {
        const std::string q = join_index(kp, m);
        const json& k = keys[m];
        check_keys(k, q, "a streamline key", {"t", "translate", "rotate", "scale"});
        StreamlineKey key;
        key.t = key_time(k, q, "the time of the key");
        if (m > 0) check_after(previous, key.t, join_key(q, "t"), "key");
        previous = key.t;
        if (const json* v = get(k, "translate")) key.translate = position(*v, join_key(q, "translate"));
        if (const json* v = get(k, "rotate")) key.rotate = number(*v, join_key(q, "rotate"));
        if (const json* v = get(k, "scale")) key.scale = positive(*v, join_key(q, "scale"));
        moved.keys.push_back(key);
      }
      out.streamlines.push_back(std::move(moved));
    }
  }
  return out;
}

Edit Reader::edit(const json& j, const std::string& path) const {
  check_object(j, path, "an edit with an \"op\"");
  const std::string op = string(
      need(j, path, "op", "cancel, smooth, remove_bifurcation or move_bifurcation"), join_key(path, "op"));
  // Half-width of the time window re-solved around the edit, as a fraction of the time
  // range (DESIGN §7; docs/scene_reference.md).
  auto window = [&] {
    double w = kDefaultEditWindow;
    if (const json* v = get(j, "window")) {
      const std::string p = join_key(path, "window");
      w = number(*v, p);
      if (!(w >= 0 && w <= 1)) fail(p, fmt::format("must be in [0, 1] (a fraction of the time range), got {}", w));
    }
    return w;
  };
  const std::string at_hint = fmt::format("the bifurcation's place and time {}", path_point_form());
  if (op == "cancel") {
    check_keys(j, path, "a cancel edit", {"op", "frame", "pair", "window"});
    CancelEdit out;
    out.frame = static_cast<int>(
        integer(need(j, path, "frame", "the frame to edit"), join_key(path, "frame"), 0, time_.frames - 1));
    const std::string p = join_key(path, "pair");
    const std::string form = fmt::format("positions {}", point_form());
    const json& pair = need(j, path, "pair", fmt::format("the two singularities to cancel, [{0}, {0}]", point_form()));
    if (!pair.is_array() || pair.size() != 2)
      fail(p, fmt::format("must be two positions [{0}, {0}], got {1}", point_form(), describe(pair)));
    const Vec3 a = position(pair[0], join_index(p, 0));
    const Vec3 b = position(pair[1], join_index(p, 1));
    check_on_domain(a, join_index(p, 0));
    check_on_domain(b, join_index(p, 1));
    if (a == b) fail(p, "names the same position twice (a pair is two different singularities)");
    out.pair = {a, b};
    out.window = window();
    return out;
  }
  if (op == "smooth") {
    check_keys(j, path, "a smooth edit", {"op", "strength"});
    const std::string p = join_key(path, "strength");
    const double s = number(need(j, path, "strength", "how much to smooth, in (0, 1]"), p);
    if (!(s > 0 && s <= 1)) fail(p, fmt::format("must be in (0, 1], got {}", s));
    return SmoothEdit{s};
  }
  if (op == "remove_bifurcation") {
    check_keys(j, path, "a remove_bifurcation edit", {"op", "at", "window"});
    const PathPoint at = path_point(need(j, path, "at", at_hint), join_key(path, "at"));
    check_on_domain(at.position, join_key(path, "at"));
    return RemoveBifurcationEdit{at, window()};
  }
  if (op == "move_bifurcation") {
    check_keys(j, path, "a move_bifurcation edit", {"op", "at", "to", "window"});
    const PathPoint at = path_point(need(j, path, "at", at_hint), join_key(path, "at"));
    const PathPoint to =
        path_point(need(j, path, "to", fmt::format("where the bifurcation goes, {}", path_point_form())),
                   join_key(path, "to"));
    check_on_domain(at.position, join_key(path, "at"));
    check_on_domain(to.position, join_key(path, "to"));
    return MoveBifurcationEdit{at, to, window()};
  }
  fail(join_key(path, "op"),
       fmt::format("unknown edit \"{}\" (expected one of cancel, smooth, remove_bifurcation, "
                   "move_bifurcation)",
                   op));
}

std::vector<Edit> Reader::edits(const json& j) const {
  array(j, "edits", 0, "edits");
  std::vector<Edit> out;
  for (size_t i = 0; i < j.size(); ++i) out.push_back(edit(j[i], join_index("edits", i)));
  return out;
}

// "incompressible": true | false | {"boundary": "no_flux" | "open"}.
std::optional<FluxBoundary> Reader::incompressible(const json& j) const {
  if (j.is_boolean()) return j.get<bool>() ? std::optional(FluxBoundary::no_flux) : std::nullopt;
  if (!j.is_object())
    fail("incompressible", fmt::format("must be true, false or an object {{\"boundary\": \"no_flux\" | \"open\"}}, "
                                       "got {}",
                                       describe(j)));
  check_keys(j, "incompressible", "{\"boundary\"}", {"boundary"});
  FluxBoundary b = FluxBoundary::no_flux;
  if (const json* v = get(j, "boundary")) b = enumeration(*v, "incompressible.boundary", kFluxBoundaries, "boundary");
  return b;
}

Scene Reader::scene(const json& j, const std::string& source_path) {
  if (!j.is_object())
    fail("", fmt::format("a scene must be a JSON object {{\"tvf\": 1, ...}}, got {}", describe(j)));
  // The version first: a newer file should say so rather than fail on a new key.
  const json& version = need(j, "", "tvf", "a tvf scene starts with \"tvf\": 1, the format version");
  if (!version.is_number())
    fail("tvf", fmt::format("must be the number 1 (the format version), got {}", describe(version)));
  if (version != 1)
    fail("tvf", fmt::format("version {} is not supported (this tvf reads version 1)", describe(version)));
  check_keys(j, "", "a scene",
             {"tvf", "description", "domain", "time", "generator", "solver", "falloff", "elements",
              "keyframes", "deform", "edits", "incompressible"});
  Scene s;
  s.version = 1;
  s.source_path = source_path;
  if (const json* d = get(j, "description")) s.description = string(*d, "description");
  s.domain = domain(need(j, "", "domain", "grid, mesh, sphere or torus"));
  planar_ = s.domain.is_planar();
  grid_ = s.domain.grid;
  if (const json* t = get(j, "time")) s.time = time(*t);
  time_ = s.time;
  if (const json* g = get(j, "generator")) s.generator = enumeration(*g, "generator", kGenerators, "generator");
  if (const json* v = get(j, "solver")) s.solver = solver(*v);
  if (const json* f = get(j, "falloff")) s.falloff = positive(*f, "falloff");
  if (const json* e = get(j, "elements")) s.elements = elements(*e, "elements");
  if (const json* k = get(j, "keyframes")) s.keyframes = keyframes(*k);
  if (const json* v = get(j, "solver")) keyframe_topology(*v, s);
  if (const json* d = get(j, "deform")) s.deform = deform(*d);
  if (const json* e = get(j, "edits")) s.edits = edits(*e);
  if (const json* i = get(j, "incompressible")) s.incompressible = incompressible(*i);
  if (s.generator == Generator::deform && !s.deform)
    fail("", "missing key \"deform\" (the deform generator needs a deform block with its base field)");
  return s;
}

// Errors about the scene's values get the line and column of their JSON path in `text`.
Scene parse_with_source(const std::string& text, const std::string& label,
                        const std::string& source_path) {
  const json j = parse_json_text(text, label, "a scene is a JSON object {\"tvf\": 1, ...}");
  try {
    return scene_from_json(j, label, source_path);
  } catch (const Error& e) {
    rethrow_with_position(e, text);
  }
}

}  // namespace

nlohmann::json keyframe_to_json(const Keyframe& keyframe, bool planar) { return keyframe_json(keyframe, planar); }

Scene scene_from_json(const nlohmann::json& j, const std::string& label,
                      const std::string& source_path) {
  return Reader(label).scene(j, source_path);
}

Scene parse_scene(const std::string& text, const std::string& label) {
  return parse_with_source(text, label, "");
}

Scene load_scene(const std::string& path) {
  return parse_with_source(read_text_file(path, "the scene file"), path, path);
}

nlohmann::json scene_to_json(const Scene& scene) {
  const bool planar = scene.domain.is_planar();
  json j;
  j["tvf"] = 1;
  j["description"] = scene.description;
  const Domain& d = scene.domain;
  if (d.grid) {
    j["domain"]["grid"] = {{"size", {d.grid->nx, d.grid->ny}},
                           {"min", {d.grid->min.x(), d.grid->min.y()}},
                           {"max", {d.grid->max.x(), d.grid->max.y()}}};
  } else if (d.sphere) {
    j["domain"]["sphere"] = {{"subdivisions", d.sphere->subdivisions}, {"radius", d.sphere->radius}};
  } else if (d.torus) {
    j["domain"]["torus"] = {{"nu", d.torus->nu},
                            {"nv", d.torus->nv},
                            {"major_radius", d.torus->major_radius},
                            {"minor_radius", d.torus->minor_radius}};
  } else if (!d.mesh.empty()) {
    j["domain"]["mesh"] = d.mesh;
  } else {
    j["domain"] = json::object();
  }
  j["time"] = {{"frames", scene.time.frames}, {"range", {scene.time.t0, scene.time.t1}}};
  j["generator"] = to_string(scene.generator);
  j["solver"] = solver_json(scene.solver);
  j["falloff"] = scene.falloff;
  j["elements"] = json::array();
  for (const Element& e : scene.elements) j["elements"].push_back(element_json(e, planar));
  j["keyframes"] = json::array();
  for (const Keyframe& k : scene.keyframes) j["keyframes"].push_back(keyframe_json(k, planar));
  if (scene.deform) j["deform"] = deform_json(*scene.deform, planar);
  j["edits"] = json::array();
  for (const Edit& e : scene.edits) j["edits"].push_back(edit_to_json(e, planar));
  if (scene.incompressible) j["incompressible"] = {{"boundary", to_string(*scene.incompressible)}};
  return j;
}

std::string scene_to_text(const Scene& scene) {
  std::string text;
  write_pretty(scene_to_json(scene), 0, 0, text);
  text += '\n';
  return text;
}

void save_scene(const Scene& scene, const std::string& path) {
  const std::string text = scene_to_text(scene);
  try {
    // Never write a file that would not load again.
    (void)parse_scene(text, "");
  } catch (const Error& e) {
    throw Error(fmt::format("cannot save the scene to '{}': {}", path, e.what()));
  }
  write_file_atomically(path, text);
}

}  // namespace tvf
