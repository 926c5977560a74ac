#include "tvf/render/surface_crowd.h"

#include "crowd_file_reader.h"

#include "tvf/core/atomic_output.h"
#include "tvf/core/error.h"
#include "tvf/core/json_text.h"
#include "tvf/integrate/streamline.h"
#include "tvf/integrate/surface_walk.h"
#include "tvf/mesh/heat_distance.h"
#include "tvf/render/frame_output.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>
#include <unordered_map>

namespace tvf {

using nlohmann::json;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Reader : CrowdFileReader {
  std::vector<SurfaceRegion> regions(const json& j, const std::string& path) const {
    if (!j.is_array()) fail(path, "expected a list of regions");
    std::vector<SurfaceRegion> out;
    for (size_t i = 0; i < j.size(); ++i) {
      const std::string p = fmt::format("{}[{}]", path, i);
      if (!j[i].is_object() || !j[i].contains("ball"))
        fail(p, "expected {\"ball\": {\"center\": [x, y, z], \"radius\": r}} (regions of a surface are balls)");
      keys(j[i], p, {"ball"});
      const json& b = j[i]["ball"];
      keys(b, p + ".ball", {"center", "radius"});
      if (!b.contains("center") || !b.contains("radius")) fail(p + ".ball", "needs center and radius");
      const json& c = b["center"];
      if (!c.is_array() || c.size() != 3) fail(p + ".ball.center", "expected a point [x, y, z]");
      SurfaceRegion r;
      for (size_t k = 0; k < 3; ++k)
        r.center[static_cast<Eigen::Index>(k)] = number(c[k], fmt::format("{}.ball.center[{}]", p, k), -1e12, 1e12);
      r.radius = number(b["radius"], p + ".ball.radius", 1e-12, 1e12);
      out.push_back(r);
    }
    return out;
  }
};

}  // namespace

SurfaceCrowdSpec load_surface_crowd_spec(const std::string& path) {
  return read_crowd_file(path, [&](const json& j) {
    const Reader r{{path}};
    r.keys(j, "", {"agents", "speed", "weights", "steps_per_frame", "seed", "avoidance", "start", "goals", "obstacles"});
    SurfaceCrowdSpec s;
    r.shared_keys(j, s, {"distance"});
    if (j.contains("seed")) s.seed = static_cast<std::uint64_t>(r.integer(j["seed"], "seed", 0, 1'000'000'000));
    if (!j.contains("start")) r.fail("start", "missing: give the regions the agents start in");
    if (!j.contains("goals")) r.fail("goals", "missing: give at least one goal region");
    s.starts = r.regions(j["start"], "start");
    s.goals = r.regions(j["goals"], "goals");
    if (j.contains("obstacles")) s.obstacles = r.regions(j["obstacles"], "obstacles");
    if (s.starts.empty()) r.fail("start", "give at least one region");
    if (s.goals.empty()) r.fail("goals", "give at least one region");
    return s;
  });
}

SurfaceCrowdResult simulate_surface_crowd(const TangentBundle& bundle, const Field& field, const SurfaceCrowdSpec& spec,
                                          int frames) {
  if (bundle.is_flat()) throw Error("surface crowd: the domain is planar (simulate_crowd steers crowds on planes)");
  const Mesh& mesh = bundle.mesh();
  if (field.num_vertices() != mesh.num_vertices()) throw Error("surface crowd: the field does not belong to this mesh");
  const int total = frames > 0 ? frames : field.frames();
  if (total < 1 || total > 1'000'000) throw Error(fmt::format("crowd: frames {} is outside [1, 1000000]", total));
  if (spec.agents < 1) throw Error("crowd: agents must be at least 1");
  if (spec.steps_per_frame < 1) throw Error("crowd: steps_per_frame must be at least 1");
  if (!(spec.weight_goal >= 0) || !(spec.weight_field >= 0) || !(spec.speed >= 0))
    throw Error("crowd: weights and speed must not be negative");
  const int nf = mesh.num_faces();
  SurfaceCrowdResult res;
  res.obstacle_face.assign(static_cast<size_t>(nf), 0);
  res.goal_face.assign(static_cast<size_t>(nf), 0);
  std::vector<int> start_faces;
  for (int f = 0; f < nf; ++f) {
    const Face& t = mesh.face(f);
    const Vec3 c = (mesh.position(t[0]) + mesh.position(t[1]) + mesh.position(t[2])) / 3.0;
    for (const auto& o : spec.obstacles) res.obstacle_face[static_cast<size_t>(f)] |= o.contains(c);
    if (res.obstacle_face[static_cast<size_t>(f)]) continue;
    for (const auto& g : spec.goals) res.goal_face[static_cast<size_t>(f)] |= g.contains(c);
    bool start = false;
    for (const auto& s : spec.starts) start |= s.contains(c);
    if (start && !res.goal_face[static_cast<size_t>(f)]) start_faces.push_back(f);
  }
  if (std::count(res.goal_face.begin(), res.goal_face.end(), 1) == 0)
    throw Error("crowd: the goals hold no face of the mesh outside the obstacles (regions are balls of world space)");
  if (start_faces.empty())
    throw Error("crowd: the start regions hold no face of the mesh outside the obstacles and goals");

  // φ: geodesic distance to the goal faces' centres on the mesh without the obstacles.
  std::vector<int> new_index(static_cast<size_t>(mesh.num_vertices()), -1);
  std::vector<Vec3> sub_positions;
  std::vector<Face> sub_faces;
  std::vector<int> sub_face_of;  // submesh face → mesh face
  for (int f = 0; f < nf; ++f) {
    if (res.obstacle_face[static_cast<size_t>(f)]) continue;
    Face t = mesh.face(f);
    for (auto& v : t) {
      int& n = new_index[static_cast<size_t>(v)];
      if (n < 0) {
        n = static_cast<int>(sub_positions.size());
        sub_positions.push_back(mesh.position(v));
      }
      v = n;
    }
    sub_faces.push_back(t);
    sub_face_of.push_back(f);
  }
  std::vector<double> sub_distance;
  {
    Mesh sub;
    try {
      sub = Mesh(sub_positions, sub_faces, mesh.source());
    } catch (const Error& e) {
      throw Error(fmt::format("crowd: the mesh without the obstacles is not a valid surface ({}); move the obstacle "
                              "balls apart or make them larger",
                              e.what()));
    }
    const TangentBundle sb(sub);
    const HeatDistance map(sb);
    std::vector<SurfacePoint> sources;
    for (size_t k = 0; k < sub_face_of.size(); ++k)
      if (res.goal_face[static_cast<size_t>(sub_face_of[k])]) sources.push_back({static_cast<int>(k), Vec3::Constant(1.0 / 3)});
    sub_distance = map.distance(sources);
  }
  res.distance.assign(static_cast<size_t>(mesh.num_vertices()), kInf);
  for (int v = 0; v < mesh.num_vertices(); ++v)
    if (new_index[static_cast<size_t>(v)] >= 0) res.distance[static_cast<size_t>(v)] = sub_distance[static_cast<size_t>(new_index[static_cast<size_t>(v)])];

  // G per face: −∇φ/|∇φ| in the face's frame (0 in obstacle faces or without a finite φ).
  std::vector<cplx> goal_dir(static_cast<size_t>(nf), cplx(0, 0));
  for (int f = 0; f < nf; ++f) {
    const Face& t = mesh.face(f);
    if (res.obstacle_face[static_cast<size_t>(f)]) continue;
    bool finite = true;
    for (int v : t) finite &= std::isfinite(res.distance[static_cast<size_t>(v)]);
    if (!finite) continue;
    const Vec3& n = bundle.face_normal(f);
    Vec3 grad = Vec3::Zero();
    for (int c = 0; c < 3; ++c) {
      const Vec3 e = mesh.position(t[static_cast<size_t>((c + 2) % 3)]) - mesh.position(t[static_cast<size_t>((c + 1) % 3)]);
      grad += res.distance[static_cast<size_t>(t[static_cast<size_t>(c)])] * n.cross(e);
    }
    const double g = grad.norm();
    if (g > 0) goal_dir[static_cast<size_t>(f)] = bundle.world_to_face(f, -grad / g);
  }

  // The goal term's least speed: a quarter of the typical speed of the field.
  double speed = spec.speed;
  if (speed <= 0) {
    std::vector<double> s;
    for (const cplx& z : field.data()) s.push_back(std::abs(z));
    auto mid = s.begin() + static_cast<long>(0.9 * static_cast<double>(s.size() - 1));
    std::nth_element(s.begin(), mid, s.end());
    const TimeSampling& ts = field.time();
    const double span = std::max(std::abs(ts.t1 - ts.t0), 1e-12);
    speed = *mid > 0 ? 0.25 * *mid : 1.5 * mesh.diameter() / span;
  }

  // Agents placed uniformly by area over the start faces.
  std::mt19937_64 rng(spec.seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> cumulative;
  double area = 0;
  for (int f : start_faces) cumulative.push_back(area += mesh.face_area(f));
  const int na = spec.agents;
  std::vector<SurfacePoint> agents(static_cast<size_t>(na));
  for (auto& a : agents) {
    const size_t k = std::min(static_cast<size_t>(std::lower_bound(cumulative.begin(), cumulative.end(), u(rng) * area) -
                                                  cumulative.begin()),
                              cumulative.size() - 1);
    double x = u(rng), y = u(rng);
    if (x + y > 1) x = 1 - x, y = 1 - y;
    a = SurfacePoint{start_faces[k], Vec3(1 - x - y, x, y)};
  }
  res.where.assign(static_cast<size_t>(na), {});
  res.positions.assign(static_cast<size_t>(na), {});
  res.arrived.assign(static_cast<size_t>(na), -1);
  const TimeSampling& ts = field.time();
  auto time_of = [&](int k) { return total > 1 ? ts.t0 + (ts.t1 - ts.t0) * k / (total - 1) : ts.t0; };
  const auto blocked = [&](int f) { return res.obstacle_face[static_cast<size_t>(f)] != 0; };
  std::vector<char> done(static_cast<size_t>(na), 0);
  std::vector<long> contacts(static_cast<size_t>(na), 0);
  auto record = [&](int k) {
    res.times.push_back(time_of(k));
    for (size_t a = 0; a < agents.size(); ++a) {
      res.where[a].push_back(agents[a]);
      res.positions[a].push_back(surface_position(mesh, agents[a]));
      if (!done[a] && res.goal_face[static_cast<size_t>(agents[a].face)]) {
        done[a] = 1;
        res.arrived[a] = k;
      }
    }
  };
  // Avoidance: pairs of active agents closer than the separation pushed apart along the
  // surface, each by half the overlap, in the direction away from the other projected
  // onto its face (neighbours found in a hash grid of cells one separation wide).
  const double sep = spec.separation;
  auto separate = [&]() {
    if (!(sep > 0)) return;
    for (int sweep = 0; sweep < 16; ++sweep) {
      std::unordered_map<std::int64_t, std::vector<int>> cells;
      std::vector<Vec3> x(agents.size());
      auto key = [&](long i, long j, long k) { return (i * 73856093L) ^ (j * 19349663L) ^ (k * 83492791L); };
      for (size_t a = 0; a < agents.size(); ++a) {
        if (done[a]) continue;
        x[a] = surface_position(mesh, agents[a]);
        cells[key(std::lround(std::floor(x[a].x() / sep)), std::lround(std::floor(x[a].y() / sep)),
                  std::lround(std::floor(x[a].z() / sep)))]
            .push_back(static_cast<int>(a));
      }
      bool moved = false;
      for (size_t a = 0; a < agents.size(); ++a) {
        if (done[a]) continue;
        const long ci = std::lround(std::floor(x[a].x() / sep)), cj = std::lround(std::floor(x[a].y() / sep)),
                   ck = std::lround(std::floor(x[a].z() / sep));
        Vec3 push = Vec3::Zero();
        for (long i = ci - 1; i <= ci + 1; ++i)
          for (long jj = cj - 1; jj <= cj + 1; ++jj)
            for (long k = ck - 1; k <= ck + 1; ++k) {
              const auto it = cells.find(key(i, jj, k));
              if (it == cells.end()) continue;
              for (int b : it->second) {
                if (static_cast<size_t>(b) == a) continue;
                Vec3 d = x[a] - x[static_cast<size_t>(b)];
                double r = d.norm();
                if (r >= (1 - 1e-3) * sep) continue;
                // Coincident agents: apart along the face's first axis, the lower index the other way.
                if (r < 1e-12 * sep) d = (static_cast<size_t>(b) < a ? 1.0 : -1.0) * bundle.face_e1(agents[a].face), r = 0;
                else d /= r;
                push += 0.5 * (sep - r) * d;
              }
            }
        if (push.squaredNorm() == 0) continue;
        const SurfaceWalk w = walk_surface(bundle, agents[a], bundle.world_to_face(agents[a].face, push), blocked);
        agents[a] = w.end;
        x[a] = surface_position(mesh, agents[a]);
        moved = true;
      }
      if (!moved) break;
    }
  };
  separate();
  record(0);
  for (int k = 1; k < total; ++k) {
    const double t0 = time_of(k - 1), t1 = time_of(k);
    const double dt = (t1 - t0) / spec.steps_per_frame;
    for (int s = 0; s < spec.steps_per_frame; ++s) {
      const double ta = t0 + s * dt, tm = ta + 0.5 * dt;
      const std::vector<cplx> va = values_at(field, ta), vm = values_at(field, tm);
      // The velocity at p (its face's frame): ω_G·max(|F|, speed)·G + ω_F·F.
      auto velocity = [&](const std::vector<cplx>& values, const SurfacePoint& p) {
        const cplx F = interpolate_in_face(bundle, values, p);
        const cplx G = goal_dir[static_cast<size_t>(p.face)];
        return spec.weight_goal * std::max(std::abs(F), speed) * G + spec.weight_field * F;
      };
      tbb::parallel_for(size_t{0}, agents.size(), [&](size_t a) {
        if (done[a]) return;
        const SurfacePoint& p = agents[a];
        const SurfaceWalk half = walk_surface(bundle, p, 0.5 * dt * velocity(va, p), blocked);
        const cplx vmid = velocity(vm, half.end) * std::conj(half.transport);
        const SurfaceWalk w = walk_surface(bundle, p, dt * vmid, blocked);
        if (w.stopped || w.hit_boundary) ++contacts[a];
        agents[a] = w.end;
      });
      // Arrivals first: an agent that reached a goal leaves the crowd before the projection.
      for (size_t a = 0; a < agents.size(); ++a)
        if (!done[a] && res.goal_face[static_cast<size_t>(agents[a].face)]) done[a] = 2;
      separate();
      for (auto& d : done)
        if (d == 2) d = 0;
    }
    record(k);
  }
  for (long c : contacts) res.contacts += c;
  return res;
}

void write_surface_crowd_csv(const std::string& path, const SurfaceCrowdResult& result) {
  std::string text = "agent,frame,t,x,y,z,arrived\n";
  for (size_t a = 0; a < result.positions.size(); ++a)
    for (size_t k = 0; k < result.positions[a].size(); ++k) {
      const Vec3& p = result.positions[a][k];
      const bool arrived = result.arrived[a] >= 0 && static_cast<size_t>(result.arrived[a]) <= k;
      text += fmt::format("{},{},{:.17g},{:.17g},{:.17g},{:.17g},{}\n", a, k, result.times[k], p.x(), p.y(), p.z(),
                          arrived ? 1 : 0);
    }
  write_file_atomically(path, text);
}

AnimationReport write_surface_crowd_animation(const TangentBundle& bundle, const Field& field,
                                              const SurfaceCrowdSpec& spec, const SurfaceCrowdAnimationOptions& options,
                                              SurfaceCrowdResult* result) {
  const auto start = std::chrono::steady_clock::now();
  if (options.size < 16 || options.size > 8192)
    throw Error(fmt::format("crowd: a picture of {} pixels is outside [16, 8192]", options.size));
  if (options.frames_dir.empty() && options.video.empty() && options.csv.empty())
    throw Error("crowd: give a folder for the PNG frames, an MP4 file or a CSV file to write");
  const SurfaceCrowdResult res = simulate_surface_crowd(bundle, field, spec, options.frames);
  const int total = static_cast<int>(res.times.size());
  AnimationReport report;
  report.frames = total;
  if (!options.csv.empty()) write_surface_crowd_csv(options.csv, res);
  if (options.frames_dir.empty() && options.video.empty()) {
    report.files.push_back(options.csv);
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (result) *result = res;
    return report;
  }
  const Mesh& mesh = bundle.mesh();
  MeshRenderer renderer;
  renderer.set_mesh(mesh);
  // Vertex colours: a vertex of an obstacle face dark grey, of a goal face green, else pale.
  std::vector<std::uint32_t> colours(static_cast<size_t>(mesh.num_vertices()), 0xE8E4D8u);
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int v : mesh.face(f)) {
      if (res.goal_face[static_cast<size_t>(f)]) colours[static_cast<size_t>(v)] = 0x5FB85Fu;
    }
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int v : mesh.face(f))
      if (res.obstacle_face[static_cast<size_t>(f)]) colours[static_cast<size_t>(v)] = 0x606060u;
  renderer.set_colors(colours);
  const Camera camera = Camera::framing(mesh.positions(), options.view.direction, options.view.up, 1.0, options.view.fov);
  RenderOptions ro;
  ro.width = ro.height = options.size;
  ro.lighting = options.view.lighting;
  ro.ambient = 0.5;
  FrameOutput out(options.frames_dir, options.video, ro.width, ro.height, options.fps);
  const double width = std::max(1.5, options.size / 400.0), radius = std::max(3.0, options.size / 160.0);
  for (int k = 0; k < total; ++k) {
    std::vector<RenderLine> lines;
    std::vector<RenderMarker> markers;
    for (size_t a = 0; a < res.positions.size(); ++a) {
      const auto& path = res.positions[a];
      if (k > 0) lines.push_back({std::vector<Vec3>(path.begin(), path.begin() + k + 1), 0x8B5A2Bu, width, false});
      const bool arrived = res.arrived[a] >= 0 && res.arrived[a] <= k;
      markers.push_back({path[static_cast<size_t>(k)], arrived ? 0x1E6E1Eu : 0x202020u, radius});
    }
    out.add(renderer.render(camera, ro, lines, markers));
    if (options.progress) options.progress(k + 1, total);
  }
  report.files = out.finish();
  if (!options.csv.empty()) report.files.push_back(options.csv);
  report.width = report.height = options.size;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (result) *result = res;
  return report;
}

}  // namespace tvf
