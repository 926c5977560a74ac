// How fast the designer follows a change (issue 7's interactive targets: a 65×65×100
// design in under 100 ms, a 20,000-vertex surface × 100 frames in about a second),
// measured through the session the server runs (tvf/serve/session.h): from put_scene()
// of a slightly changed scene to wait_idle() returning with its field solved (its
// analysis follows on the session's analysis thread since issue 15; the "picture" column
// is the median time to the first picture: the shown frame (frame 0 here) of a per-frame
// generator, GET /api/preview, or the whole field). The change
// moves one element (or key-frame element) by 0.02 and back, alternately, so every
// re-solve is the designer's "nudge an element" case. Reports wall and process CPU time
// (CLOCK_PROCESS_CPUTIME_ID, all threads) of the first solve (cold) and the median and
// best of the re-solves (warm: the session keeps its GenerateCache). A second line splits
// a warm re-solve into its parts, called directly: generate() with a kept GenerateCache,
// and analyze_topology() (singularities, paths, bifurcations), median wall times.
//
//   build/release/bench/tvf_serve_latency [--repeats N] [--only NAME]
//   build/release/bench/tvf_serve_latency --parts [--repeats N]
//
// --parts: what the server does for the designer's change of web/e2e/latency.e2e.mjs (the
// 65² × 100 design New makes, one more fixed source added to four), each step timed alone
// (median wall and process CPU over the repeats): parsing and saving the scene (PUT),
// generate() with a warm GenerateCache, the topology of all frames, the periodic orbits,
// and the answers the page downloads (the frame, the mesh, the analysis) built and printed.
#include "tvf/analysis/topology.h"
#include "tvf/field/world_vectors.h"
#include "tvf/integrate/periodic_orbits.h"
#include "tvf/scene/design_space.h"
#include "tvf/design/generate.h"
#include "tvf/scene/scene_json.h"
#include "tvf/mesh/mesh_io.h"
#include "tvf/mesh/primitives.h"
#include "tvf/serve/session.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <string>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
}
double wall_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

struct Case {
  std::string name;
  json scene;
  // Where the nudged coordinate is: a JSON pointer to a number.
  json::json_pointer nudge;
};

// The demo's kind of design on the paper's 65×65 grid × 100 frames: a moving centre, a
// fixed source, a bifurcation and a regular element.
json grid_design(const std::string& generator) {
  json j = json::parse(R"({"tvf": 1, "domain": {"grid": {"size": [65, 65], "min": [-1, -1], "max": [1, 1]}},
    "time": {"frames": 100, "range": [0, 1]}, "falloff": 40,
    "elements": [
      {"kind": "singular", "type": "ccw_center", "path": [[-0.6, 0.45, 0], [0, 0.6, 0.5], [0.6, 0.45, 1]]},
      {"kind": "singular", "type": "source", "path": [[-0.55, -0.2, 0]]},
      {"kind": "bifurcation", "type": "saddle_sink_creation", "at": [0.55, -0.2, 0.4], "scale": 0.2},
      {"kind": "regular", "pathline": [[-0.6, -0.8, 0], [0.6, -0.8, 1]], "attach": 2}]})");
  j["generator"] = generator;
  return j;
}

// Key frames (the storms of Fig. 9: two vortices, then one), spacetime generator.
json keyframe_design(json domain) {
  return {{"tvf", 1},
          {"domain", std::move(domain)},
          {"time", {{"frames", 100}, {"range", {0, 1}}}},
          {"generator", "spacetime"},
          {"falloff", 20},
          {"keyframes",
           {{{"t", 0},
             {"elements",
              {{{"kind", "singular"}, {"type", "ccw_center"}, {"at", {-0.4, 0.2, 0.9}}},
               {{"kind", "singular"}, {"type", "ccw_center"}, {"at", {0.4, -0.2, 0.9}}}}}},
            {{"t", 1}, {"elements", {{{"kind", "singular"}, {"type", "ccw_center"}, {"at", {0, 0, 1}}}}}}}}};
}

// The design New makes in the designer (web/src/scene.ts emptyScene) with `sources` fixed
// sources placed as latency.e2e.mjs places them (deform: a turned vortex, then the sources).
json designer_scene(const std::string& generator, int sources) {
  json j = json::parse(R"({"tvf": 1, "domain": {"grid": {"size": [65, 65], "min": [-1, -1], "max": [1, 1]}},
    "time": {"frames": 100, "range": [0, 1]}, "falloff": 8, "elements": [], "keyframes": [], "edits": []})");
  j["generator"] = generator;
  if (generator == "deform")
    j["deform"] = json::parse(R"({"base": {"elements": [{"kind": "singular", "type": "ccw_center", "path": [[0, 0, 0]]}]},
      "streamlines": [], "transform": [{"t": 0, "sx": 1, "sy": 1, "theta": 0}, {"t": 1, "sx": 1, "sy": 1, "theta": 0.5}]})");
  for (int k = 0; k < sources; ++k)
    j["elements"].push_back({{"kind", "singular"},
                             {"type", "source"},
                             {"path", {{-0.7 + 1.4 * k / 6.0, k % 2 ? 0.4 : -0.4, 0}}}});
  return j;
}

struct Timed {
  std::vector<double> wall, cpu;
  template <class F>
  void run(F&& f) {
    const double w = wall_seconds(), c = cpu_seconds();
    f();
    wall.push_back(wall_seconds() - w);
    cpu.push_back(cpu_seconds() - c);
  }
  static double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  }
  std::string text() const { return fmt::format("{:6.1f} /{:6.1f}", 1e3 * median(wall), 1e3 * median(cpu)); }
};

int parts(const fs::path& root, int repeats) {
  std::printf("the designer's change (one more source) on 65² × 100: median wall / CPU ms over %d repeats\n", repeats);
  std::printf("%-12s %15s %15s %15s %15s %15s %15s %15s | bytes frame, mesh, analysis\n", "generator", "scene (PUT)",
              "generate", "topology", "orbits", "frame JSON", "mesh JSON", "analysis JSON");
  for (const std::string generator : {"basis", "constrained", "spacetime", "deform"}) {
    const fs::path dir = root / ("parts-" + generator);
    fs::create_directories(dir);
    const std::string file = (dir / "scene.json").string();
    const json before = designer_scene(generator, 4), after = designer_scene(generator, 5);
    const tvf::Scene base = tvf::scene_from_json(before, "scene.json", file);
    const auto space = tvf::make_design_space(base);
    tvf::GenerateCache cache;
    tvf::GenerateOptions go;
    go.cache = &cache;
    Timed put, gen, topo, orbits, frame, mesh, analysis;
    size_t frame_bytes = 0, mesh_bytes = 0, analysis_bytes = 0;
    for (int k = 0; k < repeats; ++k) {
      tvf::generate(*space, base, go);  // the cache holds the design before the change
      tvf::Scene next;
      put.run([&] {
        next = tvf::scene_from_json(after, "scene.json", file);
        tvf::save_scene(next, file);
      });
      tvf::Field f;
      gen.run([&] { f = tvf::generate(*space, next, go); });
      tvf::Topology t;
      topo.run([&] { t = tvf::analyze_topology(space->bundle(), f); });
      tvf::PeriodicOrbits o;
      orbits.run([&] { o = tvf::find_periodic_orbits(space->bundle(), f, t); });
      frame.run([&] {
        const std::vector<float> v = tvf::world_vectors_f32(space->bundle(), f, 0);
        frame_bytes = json({{"vectors", v}}).dump().size();
      });
      mesh.run([&] {
        std::vector<float> p;
        for (const tvf::Vec3& x : space->mesh().positions())
          for (int c = 0; c < 3; ++c) p.push_back(static_cast<float>(x[c]));
        std::vector<int> faces;
        for (const tvf::Face& face : space->mesh().faces()) faces.insert(faces.end(), face.begin(), face.end());
        mesh_bytes = json({{"vertices", p}, {"faces", faces}}).dump().size();
      });
      analysis.run([&] {
        json a = tvf::topology_to_json(t);
        tvf::add_periodic_orbits_to_json(a, o);
        analysis_bytes = a.dump().size();
      });
    }
    std::printf("%-12s %15s %15s %15s %15s %15s %15s %15s | %zu, %zu, %zu\n", generator.c_str(), put.text().c_str(),
                gen.text().c_str(), topo.text().c_str(), orbits.text().c_str(), frame.text().c_str(),
                mesh.text().c_str(), analysis.text().c_str(), frame_bytes, mesh_bytes, analysis_bytes);
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  int repeats = 6;
  std::string only;
  bool split = false;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--repeats") && i + 1 < argc) repeats = std::max(1, std::atoi(argv[++i]));
    else if (!std::strcmp(argv[i], "--parts")) split = true;
    else if (!std::strcmp(argv[i], "--only") && i + 1 < argc) only = argv[++i];
    else {
      std::fprintf(stderr, "usage: %s [--repeats N] [--only NAME] [--parts]\n", argv[0]);
      return 2;
    }
  }
  const fs::path root = fs::temp_directory_path() / fmt::format("tvf-serve-latency-{}", ::getpid());
  fs::create_directories(root);
  if (split) {
    const int rc = parts(root, repeats);
    fs::remove_all(root);
    return rc;
  }
  // The 20,252-vertex geodesic sphere of the benchmarks, as a mesh file in the folder.
  tvf::save_mesh(tvf::make_geodesic_sphere(45), (root / "sphere20k.off").string());

  json planar_keys = keyframe_design({{"grid", {{"size", {65, 65}}, {"min", {-1, -1}}, {"max", {1, 1}}}}});
  for (auto& k : planar_keys["keyframes"])
    for (auto& e : k["elements"]) e["at"] = {e["at"][0], e["at"][1]};
  json sphere_keys = keyframe_design({{"mesh", "sphere20k.off"}});
  json sphere_constrained = json::parse(R"({"tvf": 1, "domain": {"mesh": "sphere20k.off"},
    "time": {"frames": 100, "range": [0, 1]}, "generator": "constrained", "falloff": 20,
    "elements": [
      {"kind": "singular", "type": "ccw_center", "path": [[1, 0, 0, 0], [0, 1, 0, 0.5], [-1, 0, 0, 1]]},
      {"kind": "singular", "type": "source", "path": [[0, 0.3, 0.95, 0]]}]})");
  const std::vector<Case> cases = {
      {"grid65x100_basis", grid_design("basis"), json::json_pointer("/elements/1/path/0/0")},
      {"grid65x100_constrained", grid_design("constrained"), json::json_pointer("/elements/1/path/0/0")},
      {"grid65x100_spacetime_keyframes", planar_keys, json::json_pointer("/keyframes/0/elements/0/at/0")},
      {"sphere20k_x100_spacetime_keyframes", sphere_keys, json::json_pointer("/keyframes/0/elements/0/at/0")},
      {"sphere20k_x100_constrained", sphere_constrained, json::json_pointer("/elements/1/path/0/0")},
  };

  std::printf("%-36s %9s %9s | %9s %9s %9s %9s | %s\n", "case (change → ready)", "cold wall", "cold cpu", "picture",
              "warm wall", "warm cpu", "best wall", "method of the last solve");
  for (const Case& c : cases) {
    if (!only.empty() && c.name.find(only) == std::string::npos) continue;
    const fs::path dir = root / c.name;
    fs::create_directories(dir);
    fs::copy_file(root / "sphere20k.off", dir / "sphere20k.off", fs::copy_options::overwrite_existing);
    tvf::serve::SessionOptions o;
    o.dir = dir;
    o.initial_scene = c.scene.dump();
    double w0 = wall_seconds(), c0 = cpu_seconds();
    tvf::serve::Session session(o);
    if (!session.wait_idle(600) || session.status()["state"] != "ready") {
      std::fprintf(stderr, "%s: %s\n", c.name.c_str(), session.status().dump().c_str());
      return 1;
    }
    const double cold_wall = wall_seconds() - w0, cold_cpu = cpu_seconds() - c0;
    std::vector<double> walls, cpus, pictures;
    json scene = c.scene;
    const double x = scene[c.nudge].get<double>();
    for (int k = 0; k < repeats; ++k) {
      scene[c.nudge] = k % 2 == 0 ? x + 0.02 : x;
      w0 = wall_seconds();
      c0 = cpu_seconds();
      const long long revision = session.put_scene(scene)["revision"];
      // The first picture: the shown frame ready (GET /api/preview: per-frame generators),
      // or the whole field.
      for (long long seen = 0;;) {
        seen = session.wait_change(seen, 1.0);
        const json st = session.status();
        if (st["result_revision"] == revision || st.value("preview_revision", 0LL) == revision || st["state"] == "failed") break;
      }
      pictures.push_back(wall_seconds() - w0);
      if (!session.wait_idle(600) || session.status()["state"] != "ready") {
        std::fprintf(stderr, "%s: %s\n", c.name.c_str(), session.status().dump().c_str());
        return 1;
      }
      walls.push_back(wall_seconds() - w0);
      cpus.push_back(cpu_seconds() - c0);
    }
    std::vector<double> sorted = walls;
    std::sort(sorted.begin(), sorted.end());
    std::vector<double> sorted_cpu = cpus;
    std::sort(sorted_cpu.begin(), sorted_cpu.end());
    const auto ms = [](double s) { return fmt::format("{:.0f} ms", 1e3 * s); };
    std::sort(pictures.begin(), pictures.end());
    std::printf("%-36s %9s %9s | %9s %9s %9s %9s | %s\n", c.name.c_str(), ms(cold_wall).c_str(), ms(cold_cpu).c_str(),
                ms(pictures[pictures.size() / 2]).c_str(), ms(sorted[sorted.size() / 2]).c_str(),
                ms(sorted_cpu[sorted_cpu.size() / 2]).c_str(), ms(sorted.front()).c_str(),
                session.status()["method"].get<std::string>().c_str());
    // The parts of a warm re-solve, through the library directly.
    {
      const tvf::Scene base = tvf::scene_from_json(c.scene, c.name, (dir / "scene.json").string());
      json moved_json = c.scene;
      moved_json[c.nudge] = x + 0.02;
      const tvf::Scene moved = tvf::scene_from_json(moved_json, c.name, (dir / "scene.json").string());
      const auto space = tvf::make_design_space(base);
      tvf::GenerateCache cache;
      tvf::GenerateOptions go;
      go.cache = &cache;
      tvf::generate(*space, base, go);
      std::vector<double> gen, topo;
      for (int k = 0; k < repeats; ++k) {
        double t0 = wall_seconds();
        const tvf::Field f = tvf::generate(*space, k % 2 == 0 ? moved : base, go);
        gen.push_back(wall_seconds() - t0);
        t0 = wall_seconds();
        const tvf::Topology top = tvf::analyze_topology(space->bundle(), f);
        topo.push_back(wall_seconds() - t0);
      }
      std::sort(gen.begin(), gen.end());
      std::sort(topo.begin(), topo.end());
      std::printf("%-36s   of which generate() %s, analyze_topology() %s\n", "", ms(gen[gen.size() / 2]).c_str(),
                  ms(topo[topo.size() / 2]).c_str());
    }
    std::fflush(stdout);
  }
  fs::remove_all(root);
  return 0;
}
