// The Python module `tvf` (DESIGN §12; docs/user_guide.md, "Python"): a thin client of
// the library's facade (tvf/api/design.h). Scenes come in as dicts or paths, results go
// out as numpy arrays and plain Python objects (the JSON of DESIGN §9 through `json`).
// Long calls run on a worker thread while the calling thread keeps the GIL free, shows
// progress and watches for Ctrl-C: a KeyboardInterrupt cancels the solve
// (GenerateOptions::cancel) and is raised once the worker has stopped.
#include "tvf/analysis/topology.h"
#include "tvf/api/design.h"
#include "tvf/core/error.h"
#include "tvf/core/error_location.h"
#include "tvf/design/keyframe_topology.h"
#include "tvf/scene/scene_json.h"
#include "tvf/field/animation_export.h"
#include "tvf/field/world_vectors.h"
#include "tvf/integrate/ftle.h"
#include "tvf/integrate/pathline.h"
#include "tvf/integrate/streakline.h"
#include "tvf/integrate/streamline.h"
#include "tvf/mesh/mesh.h"
#include "tvf/render/texture_animation.h"

#include <pybind11/complex.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <atomic>
#include <climits>
#include <map>
#include <set>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

namespace py = pybind11;
using namespace tvf;

namespace {

// Raised when a `cancel` object asked a solve to stop (tvf.Cancelled).
PyObject* cancelled_type = nullptr;

// ---- JSON <-> Python (through the json module: exact and short) ----
nlohmann::json to_json(const py::handle& obj) {
  const std::string text = py::module_::import("json").attr("dumps")(obj).cast<std::string>();
  return nlohmann::json::parse(text);
}
py::object to_python(const nlohmann::json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

// ---- a long call off the Python thread ----
// Runs `work(options)` on a worker thread. The calling thread waits with the GIL released,
// every 50 ms takes it back to call `progress(done, total)` when it changed, to check
// `cancel.is_set()` (any object with that method, e.g. threading.Event) and to let Python
// handle signals. Ctrl-C (KeyboardInterrupt) or an exception from `progress` cancels the
// work and is raised once it stopped; a set `cancel`, or `progress` returning False,
// cancels it and raises tvf.Cancelled (work that finished first returns as usual).
// `stage(text)` is called, the same way, with what the work does before its frames' count
// starts (GenerateOptions::stage: "planning the topology between key frames (interval 1
// of 2)"), when it changed: only the newest of those set within 50 ms is seen.
template <class Work>
void run_interruptible(const py::object& progress, const py::object& cancel, Work&& work,
                       const py::object& stage = py::none()) {
  std::atomic<bool> flag{false};
  std::atomic<int> done{0}, total{0};
  std::mutex stage_m;
  std::string stage_text;
  int stage_set = 0, stage_shown = 0;  // under stage_m
  std::mutex m;
  std::condition_variable cv;
  bool finished = false;
  std::exception_ptr failure;
  GenerateOptions options;
  options.cancel = &flag;
  options.progress = [&](int d, int t) {
    done.store(d);
    total.store(t);
  };
  if (!stage.is_none())
    options.stage = [&](const std::string& text) {
      std::lock_guard lock(stage_m);
      stage_text = text;
      ++stage_set;
    };
  // A `cancel` already set stops the work before it starts.
  if (!cancel.is_none() && cancel.attr("is_set")().cast<bool>()) flag.store(true);
  std::thread worker([&] {
    try {
      work(options);
    } catch (...) {
      failure = std::current_exception();
    }
    std::lock_guard lock(m);
    finished = true;
    cv.notify_all();
  });
  std::optional<py::error_already_set> raised;
  int shown_done = -1, shown_total = -1;
  for (;;) {
    bool over = false;
    {
      py::gil_scoped_release release;
      std::unique_lock lock(m);
      over = cv.wait_for(lock, std::chrono::milliseconds(50), [&] { return finished; });
    }
    if (!raised) {
      try {
        if (PyErr_CheckSignals() != 0) throw py::error_already_set();
        if (!stage.is_none()) {
          std::optional<std::string> text;
          {
            std::lock_guard lock(stage_m);
            if (stage_set != stage_shown) text = stage_text, stage_shown = stage_set;
          }
          // Like progress: returning False (not None) asks to stop.
          if (text && stage(*text).is(py::bool_(false))) flag.store(true);
        }
        if (!progress.is_none() && (done.load() != shown_done || total.load() != shown_total)) {
          shown_done = done.load();
          shown_total = total.load();
          // progress returning False (not None) asks to stop, as a set `cancel` does.
          const py::object answer = progress(shown_done, shown_total);
          if (answer.is(py::bool_(false))) flag.store(true);
        }
        if (!cancel.is_none() && cancel.attr("is_set")().cast<bool>()) flag.store(true);
      } catch (py::error_already_set& e) {
        raised.emplace(std::move(e));
        flag.store(true);
      }
    }
    if (over) break;
  }
  {
    py::gil_scoped_release release;
    worker.join();
  }
  if (raised) throw std::move(*raised);
  if (failure) {
    try {
      std::rethrow_exception(failure);
    } catch (const GenerationCancelled&) {
      PyErr_SetString(cancelled_type, "generation cancelled");
      throw py::error_already_set();
    } catch (const RenderCancelled&) {
      PyErr_SetString(cancelled_type, "rendering cancelled");
      throw py::error_already_set();
    } catch (const AnalysisCancelled&) {
      PyErr_SetString(cancelled_type, "analysis cancelled");
      throw py::error_already_set();
    }
  }
}

// ---- arrays ----
// A read-only numpy view of `data`, kept alive by `owner`.
template <class T>
py::array view(const T* data, std::vector<py::ssize_t> shape, const py::object& owner) {
  py::array a(py::dtype::of<T>(), std::move(shape), {}, data, owner);
  a.attr("setflags")(py::arg("write") = false);
  return a;
}

Scene scene_of(const py::object& scene) {
  if (py::isinstance<py::str>(scene) || py::hasattr(scene, "__fspath__"))
    return load_scene(py::str(py::module_::import("os").attr("fspath")(scene)).cast<std::string>());
  if (py::isinstance<py::dict>(scene)) return scene_from_json(to_json(scene), "scene");
  throw py::type_error("a scene is a dict (the scene JSON) or the path of a scene file");
}

// ---- domains from numpy ----
// What names a mesh given as arrays in messages and in the scene's domain ({"mesh": ...}).
const char* const kArrayMesh = "vertices/faces";

// A scene dict for a mesh given as arrays: a copy with {"mesh": "vertices/faces"} as its
// domain, so that its points are read as on a mesh ([x, y, z, t]); Design(Scene, Mesh)
// sets that domain on a scene read from a file too.
py::object with_array_domain(const py::object& scene) {
  if (!py::isinstance<py::dict>(scene)) return scene;
  py::dict d = py::dict(scene);
  py::dict domain;
  domain["mesh"] = kArrayMesh;
  d["domain"] = domain;
  return d;
}

// The Mesh of (vertices, faces) arrays: V (|V|, 3) floats, F (|F|, 3) integers, checked
// by the Mesh constructor as a mesh file is (mesh_validate.h: the same sentences, naming
// "vertices/faces").
Mesh mesh_of(const py::object& vertices, const py::object& faces) {
  if (vertices.is_none() || faces.is_none())
    throw py::value_error(std::string(kArrayMesh) + ": give both vertices (|V| x 3) and faces (|F| x 3)");
  auto np = py::module_::import("numpy");
  py::array v = np.attr("asarray")(vertices);
  py::array f = np.attr("asarray")(faces);
  auto shape_text = [](const py::array& a) { return py::str(py::tuple(a.attr("shape"))).cast<std::string>(); };
  if (v.ndim() != 2 || v.shape(1) != 3)
    throw py::value_error(std::string(kArrayMesh) + ": vertices must be a |V| x 3 array, not of shape " + shape_text(v));
  if (f.ndim() != 2 || f.shape(1) != 3)
    throw py::value_error(std::string(kArrayMesh) + ": faces must be a |F| x 3 array, not of shape " + shape_text(f));
  const char kind = v.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u')
    throw py::value_error(std::string(kArrayMesh) + ": vertices must be numbers (float64), not dtype " +
                          py::str(v.dtype()).cast<std::string>());
  if (f.dtype().kind() != 'i' && f.dtype().kind() != 'u')
    throw py::value_error(std::string(kArrayMesh) + ": faces must be integers (vertex indices), not dtype " +
                          py::str(f.dtype()).cast<std::string>());
  auto vd = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(v);
  auto fd = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(f);
  const auto nv = static_cast<size_t>(vd.shape(0));
  const auto nf = static_cast<size_t>(fd.shape(0));
  std::vector<Vec3> positions(nv);
  for (size_t i = 0; i < nv; ++i)
    for (int k = 0; k < 3; ++k) positions[i][k] = vd.at(static_cast<py::ssize_t>(i), k);
  std::vector<Face> tris(nf);
  for (size_t i = 0; i < nf; ++i)
    for (int k = 0; k < 3; ++k) {
      const std::int64_t x = fd.at(static_cast<py::ssize_t>(i), k);
      // Indices beyond int are out of range too: the validation's own sentence.
      if (x < 0 || x >= static_cast<std::int64_t>(nv))
        throw_input_error(kArrayMesh, "",
                          "face " + std::to_string(i) + " uses vertex " + std::to_string(x) +
                              ", but the vertices are numbered 0 to " + std::to_string(static_cast<long long>(nv) - 1));
      tris[i][static_cast<size_t>(k)] = static_cast<int>(x);
    }
  py::gil_scoped_release release;  // validation and connectivity of a large mesh take a while
  return Mesh(std::move(positions), std::move(tris), kArrayMesh);
}

// ---- pictures ----
// An RGB24 picture as an H x W x 3 uint8 array.
py::array_t<std::uint8_t> rgb_array(const Image& img) {
  py::array_t<std::uint8_t> a({static_cast<py::ssize_t>(img.height), static_cast<py::ssize_t>(img.width), py::ssize_t{3}});
  std::uint8_t* out = a.mutable_data();
  for (size_t q = 0; q < img.pixels.size(); ++q) {
    const std::uint32_t p = img.pixels[q];
    out[3 * q] = static_cast<std::uint8_t>((p >> 16) & 0xFF);
    out[3 * q + 1] = static_cast<std::uint8_t>((p >> 8) & 0xFF);
    out[3 * q + 2] = static_cast<std::uint8_t>(p & 0xFF);
  }
  return a;
}

py::dict report_dict(const GenerateReport& r) {
  py::dict d;
  d["method"] = r.method;
  d["seconds"] = r.seconds;
  d["residual"] = r.residual;
  d["iterations"] = r.iterations;
  d["frames"] = r.frames;
  d["vertices"] = r.vertices;
  d["warnings"] = r.warnings;
  d["edits"] = r.edits;
  // Topology between key frames (solver.keyframe_topology "matched"): the plan per
  // interval, as keyframe_topology.json has it; absent otherwise.
  if (!r.keyframe_intervals.empty()) d["keyframe_intervals"] = to_python(keyframe_intervals_json(r.keyframe_intervals));
  return d;
}

// A generated field with its domain: what tvf.generate returns (tvf.Field).
struct PyField {
  std::shared_ptr<const DesignSpace> space;
  std::shared_ptr<const Field> field;
  GenerateReport report;
  py::object vectors_cache;

  const TangentBundle& bundle() const { return space->bundle(); }
};

Vec3 vec3_of(const std::vector<double>& p, const char* what) {
  if (p.size() != 2 && p.size() != 3) throw py::value_error(std::string(what) + ": give [x, y] or [x, y, z]");
  return {p[0], p[1], p.size() == 3 ? p[2] : 0.0};
}

py::dict curve_dict(const std::vector<Vec3>& points, const std::vector<double>* times) {
  py::array_t<double> pts({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}});
  auto w = pts.mutable_unchecked<2>();
  for (size_t i = 0; i < points.size(); ++i)
    for (int k = 0; k < 3; ++k) w(static_cast<py::ssize_t>(i), k) = points[i][k];
  py::dict d;
  d["points"] = pts;
  if (times) d["times"] = py::array_t<double>(static_cast<py::ssize_t>(times->size()), times->data());
  return d;
}

// A streakline or timeline (integrate/streakline.h) as a dict of arrays: where each
// particle is at t1, its release time (or parameter), whether a particle before it left.
py::dict streak_dict(const Streakline& s, const char* release_key) {
  std::vector<Vec3> points;
  std::vector<double> release;
  py::array_t<bool> gap(static_cast<py::ssize_t>(s.points.size()));
  for (size_t i = 0; i < s.points.size(); ++i) {
    points.push_back(s.points[i].position);
    release.push_back(s.points[i].release);
    gap.mutable_at(static_cast<py::ssize_t>(i)) = s.points[i].gap_before;
  }
  py::dict d = curve_dict(points, nullptr);
  d[release_key] = py::array_t<double>(static_cast<py::ssize_t>(release.size()), release.data());
  d["gap_before"] = gap;
  d["t"] = s.t;
  d["released"] = s.released;
  d["left"] = s.left;
  d["resolution"] = s.resolution;
  d["largest_gap"] = s.largest_gap;
  d["unresolved"] = s.unresolved;
  const char* by = refinement_name(s.unresolved_by);
  d["unresolved_by"] = by ? py::object(py::str(by)) : py::object(py::none());
  return d;
}

std::vector<std::string> strings(const std::vector<std::filesystem::path>& paths) {
  std::vector<std::string> out;
  for (const auto& p : paths) out.push_back(p.string());
  return out;
}

// A Design with its Python-side helpers (tvf.Design).
struct PyDesign {
  Design design;
  explicit PyDesign(Design d) : design(std::move(d)) {}

  std::shared_ptr<PyField> field() const {
    auto f = std::make_shared<PyField>();
    f->space = design.field_space();
    f->field = design.field_ptr();
    f->report = design.report();
    return f;
  }
};

py::dict edit_report_dict(const EditReport& r) {
  py::dict d;
  d["summary"] = r.summary;
  d["key_frames"] = r.key_frames;
  d["window"] = py::make_tuple(r.window_first, r.window_last);
  d["region_faces"] = r.region_faces;
  d["iterations"] = r.iterations;
  d["residual"] = r.residual;
  return d;
}

}  // namespace

PYBIND11_MODULE(_tvf, m) {
  m.doc() = "tvf: design of time-varying vector fields on planar grids and surfaces (Chen et al., TVCG 2012).";

  static py::exception<GenerationCancelled> cancelled(m, "Cancelled", PyExc_RuntimeError);
  cancelled_type = cancelled.ptr();
  cancelled.doc() = "Raised when a `cancel` object stopped a solve; the design is unchanged.";
  // Bad input (tvf::Error) is a ValueError with the command line's sentence.
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const GenerationCancelled& e) {
      PyErr_SetString(cancelled_type, e.what());
    } catch (const Error& e) {
      // The place as attributes too: file, json_path (None when unknown), line, column
      // (0 when unknown), as the server's error answers carry them.
      const ErrorLocation w = location_of(e);
      py::object error = py::reinterpret_steal<py::object>(PyObject_CallFunction(PyExc_ValueError, "s", e.what()));
      if (!error) return;  // the call's own error is set
      auto text_or_none = [](const std::string& s) { return s.empty() ? py::object(py::none()) : py::object(py::str(s)); };
      error.attr("file") = text_or_none(w.file);
      error.attr("json_path") = text_or_none(w.json_path);
      error.attr("line") = py::int_(w.line);
      error.attr("column") = py::int_(w.column);
      PyErr_SetObject(PyExc_ValueError, error.ptr());
    }
  });

  py::class_<PyField, std::shared_ptr<PyField>>(m, "Field", R"(A generated time-varying field and the domain it lives on.

Arrays are read-only numpy views where the data allows (values, vertices, faces):
  vectors   (N, |V|, 3) float32  world vectors, the values of field.npy
  values    (N, |V|) complex128  the same vectors in each vertex's tangent basis
            (vectors[j, v] = values[j, v].real * e1[v] + values[j, v].imag * e2[v])
  e1, e2    (|V|, 3) float64     the tangent basis of every vertex
  vertices  (|V|, 3) float64, faces (|F|, 3) int32, times (N,) float64)")
      .def_property_readonly(
          "vectors",
          [](py::object self) {
            auto& f = self.cast<PyField&>();
            if (!f.vectors_cache) {
              std::vector<float> w = world_vectors_f32(f.bundle(), *f.field);
              py::array_t<float> a({static_cast<py::ssize_t>(f.field->frames()),
                                    static_cast<py::ssize_t>(f.field->num_vertices()), py::ssize_t{3}});
              std::copy(w.begin(), w.end(), a.mutable_data());
              a.attr("setflags")(py::arg("write") = false);
              f.vectors_cache = a;
            }
            return f.vectors_cache;
          },
          "(N, |V|, 3) float32 world vectors, frame-major: exactly the values `tvf generate` writes to field.npy.")
      .def_property_readonly(
          "values",
          [](py::object self) {
            auto& f = self.cast<PyField&>();
            return view(f.field->data().data(),
                        {static_cast<py::ssize_t>(f.field->frames()), static_cast<py::ssize_t>(f.field->num_vertices())},
                        self);
          },
          "(N, |V|) complex128: the field in each vertex's tangent basis (e1, e2), the library's own form (no copy).")
      .def_property_readonly(
          "vertices",
          [](py::object self) {
            const auto& pos = self.cast<PyField&>().space->mesh().positions();
            return view(pos.empty() ? nullptr : pos.front().data(), {static_cast<py::ssize_t>(pos.size()), 3}, self);
          },
          "(|V|, 3) float64 vertex positions (z = 0 on planar grids).")
      .def_property_readonly(
          "faces",
          [](py::object self) {
            const auto& faces = self.cast<PyField&>().space->mesh().faces();
            return view(faces.empty() ? nullptr : faces.front().data(), {static_cast<py::ssize_t>(faces.size()), 3},
                        self);
          },
          "(|F|, 3) int32 triangles (counter-clockwise).")
      .def_property_readonly(
          "times",
          [](const PyField& f) {
            py::array_t<double> t(f.field->frames());
            for (int j = 0; j < f.field->frames(); ++j) t.mutable_at(j) = f.field->time().time(j);
            return t;
          },
          "(N,) float64 design time of every frame.")
      .def_property_readonly(
          "e1",
          [](const PyField& f) {
            const int nv = f.field->num_vertices();
            py::array_t<double> a({static_cast<py::ssize_t>(nv), py::ssize_t{3}});
            for (int v = 0; v < nv; ++v)
              for (int k = 0; k < 3; ++k) a.mutable_at(v, k) = f.bundle().vertex_e1(v)[k];
            return a;
          },
          "(|V|, 3) float64 first tangent basis vector of every vertex.")
      .def_property_readonly(
          "e2",
          [](const PyField& f) {
            const int nv = f.field->num_vertices();
            py::array_t<double> a({static_cast<py::ssize_t>(nv), py::ssize_t{3}});
            for (int v = 0; v < nv; ++v)
              for (int k = 0; k < 3; ++k) a.mutable_at(v, k) = f.bundle().vertex_e2(v)[k];
            return a;
          },
          "(|V|, 3) float64 second tangent basis vector of every vertex.")
      .def_property_readonly("frames", [](const PyField& f) { return f.field->frames(); }, "Number of frames N.")
      .def_property_readonly("planar", [](const PyField& f) { return f.space->planar(); },
                             "True on planar domains (z = 0 everywhere).")
      .def_property_readonly("report", [](const PyField& f) { return report_dict(f.report); },
                             "What generation reported: method, seconds, residual, iterations, warnings, edits (and keyframe_intervals with solver.keyframe_topology matched).")
      .def(
          "streamline",
          [](const PyField& f, const std::vector<double>& seed, double t, double step, double max_length) {
            StreamlineOptions o;
            o.step = step;
            o.max_length = max_length;
            const std::vector<cplx> values = values_at(*f.field, t);
            const Streamline s = trace_streamline(f.bundle(), values, vec3_of(seed, "seed"), o);
            py::dict d = curve_dict(s.points, nullptr);
            d["seed"] = s.seed;
            d["stop_backward"] = to_string(s.stop_backward);
            d["stop_forward"] = to_string(s.stop_forward);
            return d;
          },
          py::arg("seed"), py::arg("t") = 0.0, py::kw_only(), py::arg("step") = 0.0, py::arg("max_length") = 0.0,
          R"(The streamline through `seed` ([x, y] or [x, y, z]) of the field at time t, both ways
(RK4, arc length; step 0: half the mean edge length; max_length 0: the domain's diagonal).
Returns {"points": (K, 3) array ordered along the flow, "seed": index of the seed,
"stop_backward", "stop_forward": why each end stopped}.)")
      .def(
          "pathline",
          [](const PyField& f, const std::vector<double>& seed, double t_start, std::optional<double> t_end,
             double dt) {
            PathlineOptions o;
            o.t_start = t_start;
            o.t_end = t_end ? *t_end : f.field->time().t1;
            o.dt = dt;
            const Pathline p = trace_pathline(f.bundle(), *f.field, vec3_of(seed, "seed"), o);
            py::dict d = curve_dict(p.points, &p.times);
            d["stop"] = to_string(p.stop);
            return d;
          },
          py::arg("seed"), py::arg("t_start") = 0.0, py::arg("t_end") = py::none(), py::kw_only(),
          py::arg("dt") = 0.0,
          R"(The pathline (dx/dt = V(x, t)) released at `seed` at t_start, to t_end (default: the
end of the time range; earlier integrates backwards). Returns {"points": (K, 3),
"times": (K,), "stop": why it ended}.)")
      .def(
          "ftle",
          [](const PyField& f, double horizon, const std::string& direction, const std::optional<std::vector<int>>& frames,
             const std::string& beyond_range, bool compose, double dt, const py::object& progress,
             const py::object& cancel) {
            if (direction != "both" && direction != "forward" && direction != "backward")
              throw py::value_error("ftle: direction must be \"both\", \"forward\" or \"backward\", got \"" +
                                    direction + "\"");
            if (beyond_range != "clamp" && beyond_range != "nan")
              throw py::value_error("ftle: beyond_range must be \"clamp\" or \"nan\", got \"" + beyond_range + "\"");
            FtleOptions o;
            o.horizon = horizon;
            o.forward = direction != "backward";
            o.backward = direction != "forward";
            o.beyond_range = beyond_range == "nan" ? HorizonPolicy::nan : HorizonPolicy::clamp;
            if (frames) o.frames = *frames;
            o.compose = compose;
            o.flow.dt = dt;
            FtleResult r;
            run_interruptible(progress, cancel, [&](GenerateOptions& g) {
              // After each frame and direction: its count, and a stop once cancelled.
              o.progress = [&](int done, int total) {
                g.progress(done, total);
                check_analysis_cancel(g.cancel);
              };
              r = compute_ftle(f.bundle(), *f.field, o);
            });
            const std::vector<py::ssize_t> shape{static_cast<py::ssize_t>(r.frames), static_cast<py::ssize_t>(r.vertices)};
            auto values = [&](const std::vector<float>& v) -> py::object {
              if (v.empty()) return py::none();
              py::array_t<float> a(shape);
              std::copy(v.begin(), v.end(), a.mutable_data());
              return a;
            };
            auto spans = [](const std::vector<double>& v) -> py::object {
              if (v.empty()) return py::none();
              return py::array_t<double>(static_cast<py::ssize_t>(v.size()), v.data());
            };
            py::dict d;
            d["horizon"] = r.horizon;
            d["forward"] = values(r.forward);
            d["backward"] = values(r.backward);
            d["forward_span"] = spans(r.forward_span);
            d["backward_span"] = spans(r.backward_span);
            d["forward_cut"] = r.forward_cut;
            d["backward_cut"] = r.backward_cut;
            d["forward_left"] = r.forward_left;
            d["backward_left"] = r.backward_left;
            return d;
          },
          py::arg("horizon"), py::kw_only(), py::arg("direction") = "both", py::arg("frames") = py::none(),
          py::arg("beyond_range") = "clamp", py::arg("compose") = false, py::arg("dt") = 0.0,
          py::arg("progress") = py::none(), py::arg("cancel") = py::none(),
          R"(Finite-time Lyapunov exponents, as `tvf ftle` (integrate/ftle.h): for every frame t
and vertex, ln(largest singular value of the flow map's gradient over [t, t ± horizon]) /
horizon. Returns {"forward", "backward": (N, |V|) float32 arrays (None for a direction not
asked; NaN where a particle left the domain, for frames not in `frames`, and with
beyond_range "nan" for windows past the time range), "forward_span", "backward_span": (N,)
the time integrated per frame (cut at the range's end by "clamp"), "forward_cut",
"backward_cut": frames whose window was cut, "forward_left", "backward_left": vertex-frames
whose particle left, "horizon"}. direction: "both", "forward" (repelling LCS) or
"backward" (attracting LCS); frames: the frames to compute (default all); compose: planar
grids, compose per-frame flow maps (faster, less accurate on ridges); dt: largest RK4 step
(0: half the frame spacing). A horizon too short to move a particle a millionth of an edge
raises ValueError naming the shortest one resolved. progress(done, total) and cancel as in
tvf.generate (after each frame and direction; Ctrl-C stops it too, tvf.Cancelled once
cancelled).)")
      .def(
          "streakline",
          [](const PyField& f, const std::vector<double>& seed, std::optional<double> t_start,
             std::optional<double> t_end, double release_spacing, double max_gap, double dt) {
            StreaklineOptions o;
            o.t0 = t_start ? *t_start : f.field->time().t0;
            o.t1 = t_end ? *t_end : f.field->time().t1;
            o.release_spacing = release_spacing;
            o.max_gap = max_gap;
            o.flow.dt = dt;
            return streak_dict(trace_streakline(f.bundle(), *f.field, vec3_of(seed, "seed"), o), "release");
          },
          py::arg("seed"), py::arg("t_start") = py::none(), py::arg("t_end") = py::none(), py::kw_only(),
          py::arg("release_spacing") = 0.0, py::arg("max_gap") = 0.0, py::arg("dt") = 0.0,
          R"(The streakline of dye released continuously at `seed` ([x, y] or [x, y, z]) over
[t_start, t_end] (default: the time range), as `tvf streaklines`: where each released
particle is at t_end. Returns {"points": (K, 3) oldest release first, "release": (K,) each
particle's release time, "gap_before": (K,) a particle between it and the one before left
the domain, "t", "released", "left", "resolution", "largest_gap", "unresolved",
"unresolved_by"}.
release_spacing: time between releases (0: a quarter of the frame spacing; over a million
releases is refused); max_gap: where neighbours end further apart, a particle released
halfway between them is added (0: a mean edge length; at most 20,000 added;
"unresolved" counts the neighbours still further apart, "largest_gap" the largest
distance between them, "unresolved_by" what stopped the refinement: None when resolved,
"particles" or "torn"); dt: largest RK4 step.)")
      .def(
          "timeline",
          [](const PyField& f, const std::vector<double>& a, const std::vector<double>& b, std::optional<double> t_start,
             std::optional<double> t_end, int count, double max_gap) {
            TimelineOptions o;
            o.t0 = t_start ? *t_start : f.field->time().t0;
            o.t1 = t_end ? *t_end : f.field->time().t1;
            o.count = count;
            o.max_gap = max_gap;
            return streak_dict(trace_timeline(f.bundle(), *f.field, vec3_of(a, "a"), vec3_of(b, "b"), o), "parameter");
          },
          py::arg("a"), py::arg("b"), py::arg("t_start") = py::none(), py::arg("t_end") = py::none(), py::kw_only(),
          py::arg("count") = 100, py::arg("max_gap") = 0.0,
          R"(The timeline: the segment from a to b drawn at t_start (default: the start of the time
range), carried by the flow to t_end (default: its end; earlier carries it backwards), as
`tvf timelines` (on a surface the line is the shortest path over it between a and b);
`count` particles on the line, refined where neighbours part by more
than max_gap (0: a mean edge length; 20,000 particles at most). Returns {"points": (K, 3)
along the line, "parameter": (K,) each particle's place on the initial segment in [0, 1],
"gap_before", "t", "released", "left", "resolution", "largest_gap", "unresolved",
"unresolved_by"}; both
ends at one point raise ValueError.)")
      .def(
          "export_vdb",
          [](const PyField& f, const std::string& dir) {
            return strings(write_vdb_sequence(dir, f.bundle(), *f.field, "field"));
          },
          py::arg("dir"),
          "Writes DIR/velocity_NNNN.vdb (one Vec3f grid `v` per frame; planar grids only), as `tvf export --vdb`.")
      .def(
          "export_ply",
          [](const PyField& f, const std::string& dir) { return strings(write_ply_sequence(dir, f.bundle(), *f.field)); },
          py::arg("dir"),
          "Writes DIR/velocity_NNNN.ply (vertices with vx, vy, vz, and faces) per frame, as `tvf export --ply`.")
      .def("__repr__", [](const PyField& f) {
        return "<tvf.Field " + std::to_string(f.field->frames()) + " frames x " +
               std::to_string(f.field->num_vertices()) + " vertices" + (f.space->planar() ? ", planar>" : ", surface>");
      });

  m.def(
      "generate",
      [](const py::object& scene, const py::object& vertices, const py::object& faces, const py::object& progress,
         const py::object& cancel, bool parallel, const py::object& stage) {
        if (!vertices.is_none() || !faces.is_none()) {
          // A mesh from arrays: a Design on it (the library's one path for a given mesh).
          DesignOptions dopt;
          dopt.parallel = parallel;
          Mesh mesh = mesh_of(vertices, faces);
          PyDesign d(Design(scene_of(with_array_domain(scene)), std::move(mesh), dopt));
          run_interruptible(progress, cancel, [&](GenerateOptions& o) { d.design.generate(o); }, stage);
          return d.field();
        }
        const Scene s = scene_of(scene);
        auto out = std::make_shared<PyField>();
        run_interruptible(progress, cancel, [&](GenerateOptions& o) {
          o.parallel = parallel;
          GeneratedField g = generate_scene(s, o);
          out->space = g.space;
          out->field = std::make_shared<const Field>(std::move(g.field));
          out->report = std::move(g.report);
        }, stage);
        return out;
      },
      py::arg("scene"), py::kw_only(), py::arg("vertices") = py::none(), py::arg("faces") = py::none(),
      py::arg("progress") = py::none(), py::arg("cancel") = py::none(), py::arg("parallel") = true,
      py::arg("stage") = py::none(),
      R"doc(Generates the field of a scene (a dict of the scene JSON, or a scene file's path).

vertices (|V|, 3) float64 and faces (|F|, 3) int: the domain as arrays instead of the
scene's own (which they replace; a dict may leave out "domain"; points are [x, y, z, t]
as on any mesh, a planar one too). They are checked
as a mesh file is, with the same sentences naming "vertices/faces" (out-of-range
indices, NaN coordinates, degenerate faces, non-manifold edges and vertices, unused
vertices, flipped orientation); nothing is repaired, so field.vertices are yours.

progress(done, total) is called as frames complete (returning False stops the solve,
as a set `cancel` does); `cancel` is any object with is_set() (threading.Event): once
set, the solve stops and tvf.Cancelled is raised. stage(text) is called with what the
solve does before its frames' count starts, as the command line's progress line says it
("building the domain", "planning the topology between key frames (interval 1 of 2)"),
when it changed (returning False stops the solve too).
Ctrl-C stops it too (KeyboardInterrupt). Bad input raises ValueError with the command
line's sentence ("scene: elements[0].type: ...").)doc");

  m.def(
      "analyze",
      [](const PyField& f) { return to_python(analysis_json_of(*f.space, *f.field)); },
      py::arg("field"),
      R"(The analysis of a field (DESIGN §9) as Python objects: {"frames", "times",
"singularities", "paths", "bifurcations", "coherence", ...}, the JSON `tvf analyze` writes.)");

  m.def(
      "load",
      [](const std::string& path) {
        const Design d = Design::open(path);
        auto f = std::make_shared<PyField>();
        f->space = d.field_space();
        f->field = d.field_ptr();
        f->report = d.report();
        return f;
      },
      py::arg("path"), "Reads a field written by `tvf generate` (its folder or field.tvff).");

  m.def(
      "export_vdb", [](const PyField& f, const std::string& dir) {
        return strings(write_vdb_sequence(dir, f.bundle(), *f.field, "field"));
      },
      py::arg("field"), py::arg("dir"), "Field.export_vdb as a function: DIR/velocity_NNNN.vdb per frame.");
  m.def(
      "export_ply", [](const PyField& f, const std::string& dir) {
        return strings(write_ply_sequence(dir, f.bundle(), *f.field));
      },
      py::arg("field"), py::arg("dir"), "Field.export_ply as a function: DIR/velocity_NNNN.ply per frame.");
  m.attr("vdb_available") = vdb_export_available();

  m.def(
      "render_texture",
      [](const PyField& f, int size, const py::object& frames, const std::optional<std::string>& frames_dir,
         const std::optional<std::string>& video, int pictures, double alpha, int lic, double noise_scale,
         const std::string& speed, double pixels_per_frame, double contrast, std::uint64_t seed,
         const std::vector<std::string>& overlay, const std::optional<std::vector<double>>& view,
         const std::optional<std::vector<double>>& up, double fps,
         const std::vector<std::vector<double>>& streaklines,
         const std::vector<std::vector<std::vector<double>>>& timelines, double time_scale,
         const py::object& progress) -> py::object {
        TextureAnimationOptions o;
        for (const auto& p : streaklines) o.streakline_seeds.push_back(vec3_of(p, "render_texture: a streaklines seed"));
        for (const auto& line : timelines) {
          if (line.size() != 2) throw Error("render_texture: a timeline is two points [a, b]");
          o.timelines.push_back({vec3_of(line[0], "render_texture: a timeline's first point"),
                                 vec3_of(line[1], "render_texture: a timeline's last point")});
        }
        o.dye_time_scale = time_scale;
        o.texture.size = size;
        o.texture.alpha = alpha;
        o.texture.lic = lic;
        o.texture.noise_scale = noise_scale;
        o.texture.pixels_per_frame = pixels_per_frame;
        o.texture.contrast = contrast;
        o.texture.seed = seed;
        if (speed == "physical")
          o.texture.speed = TextureSpeed::physical;
        else if (speed != "uniform")
          throw py::value_error("render_texture: speed is \"uniform\" or \"physical\", not \"" + speed + "\"");
        for (const auto& what : overlay) {
          if (what != "singularities" && what != "paths" && what != "streamlines" && what != "orbits")
            throw py::value_error("render_texture: overlay \"" + what +
                                  "\" is not one of singularities, paths, streamlines, orbits");
          o.overlay_singularities |= what == "singularities";
          o.overlay_paths |= what == "paths";
          o.overlay_streamlines |= what == "streamlines";
          o.overlay_orbits |= what == "orbits";
        }
        if (view) o.surface.direction = vec3_of(*view, "view");
        if (up) o.surface.up = vec3_of(*up, "up");
        o.frames = pictures;
        o.fps = fps;
        o.frames_dir = frames_dir.value_or("");
        o.video = video.value_or("");
        // Which pictures come back: one (an int), several (a sequence) or all (None). The
        // animation runs from the first asked for to the last (the texture is advected
        // frame by frame), files holding every picture of that range.
        const int total = pictures > 0 ? pictures : f.field->frames();
        std::vector<int> wanted;
        const bool single = py::isinstance<py::int_>(frames);
        if (frames.is_none()) {
          for (int k = 0; k < total; ++k) wanted.push_back(k);
        } else if (single) {
          wanted.push_back(frames.cast<int>());
        } else {
          wanted = frames.cast<std::vector<int>>();
          if (wanted.empty()) throw py::value_error("render_texture: frames is empty (give picture numbers, or None for all)");
        }
        o.first = INT_MAX;
        o.last = -1;
        for (int k : wanted) {
          if (k < 0 || k >= total)
            throw py::value_error("render_texture: frame " + std::to_string(k) + " is outside [0, " +
                                  std::to_string(total - 1) + "] (the animation has " + std::to_string(total) +
                                  " pictures)");
          o.first = std::min(o.first, k);
          o.last = std::max(o.last, k);
        }
        const std::set<int> keep(wanted.begin(), wanted.end());
        std::map<int, Image> made;  // filled in order by the one thread that hands pictures on
        o.on_picture = [&](int k, const Image& img) {
          if (keep.count(k)) made.emplace(k, img);
        };
        TextureAnimationReport report;
        run_interruptible(progress, py::none(), [&](GenerateOptions& g) {
          o.progress = g.progress;
          o.cancel = g.cancel;
          report = write_texture_animation(f.bundle(), *f.field, o);
        });
        // A timeline drawn unresolved at some pictures: a RuntimeWarning, as the CLI warns.
        for (size_t l = 0; l < report.timelines.size(); ++l) {
          const std::string note =
              unresolved_note(report.timelines[l], "timelines[" + std::to_string(l) + "]", TimelineOptions{}.max_points);
          if (!note.empty() && PyErr_WarnEx(PyExc_RuntimeWarning, note.c_str(), 1) < 0) throw py::error_already_set();
        }
        if (single) return rgb_array(made.at(wanted.front()));
        py::list out;
        for (int k : wanted) out.append(rgb_array(made.at(k)));
        return out;
      },
      py::arg("field"), py::arg("size") = 512, py::arg("frames") = py::none(), py::kw_only(),
      py::arg("frames_dir") = py::none(), py::arg("video") = py::none(), py::arg("pictures") = 0,
      py::arg("alpha") = 0.1, py::arg("lic") = -1, py::arg("noise_scale") = 0.0, py::arg("speed") = "uniform",
      py::arg("pixels_per_frame") = 0.0, py::arg("contrast") = 1.0, py::arg("seed") = 1,
      py::arg("overlay") = std::vector<std::string>{}, py::arg("view") = py::none(), py::arg("up") = py::none(),
      py::arg("fps") = 25.0, py::arg("streaklines") = std::vector<std::vector<double>>{},
      py::arg("timelines") = std::vector<std::vector<std::vector<double>>>{}, py::arg("time_scale") = 1.0,
      py::arg("progress") = py::none(),
      R"(The texture animation of a field (`tvf render texture`: LIC over advected noise on
planar grids, the image-space texture on surfaces) as pictures in memory.

frames: a picture number (returns one (H, W, 3) uint8 array), a sequence of them
(returns a list of such arrays, in that order) or None (every picture). Pictures are
numbered 0 .. pictures-1 over the field's time range (pictures 0: one per field frame);
the texture is warmed up at the first picture asked for and advected from there to the
last (as `tvf render texture --range A:B`): picture k is the same whichever later
pictures are asked for with it, and the same as frame_k.png of a run from that first.
frames_dir / video: also write every picture of that range as PNG frames
(frame_NNNNN.png, the folder appears complete or not at all) or as an MP4.
size: pixels on the long side (surfaces: the square picture's side). alpha, lic,
noise_scale, speed ("uniform" | "physical"), pixels_per_frame, contrast, seed: as
`tvf render texture`'s options; overlay: any of "singularities", "paths",
"streamlines", "orbits" (planar only); view, up: the camera on surfaces (from the
mesh's centre towards the eye; up in the picture). streaklines: dye seeds, [x, y] on
planar domains or [x, y, z] on or near a surface, whose dye, released from the first
picture on, is drawn in every picture (`--streakline`); timelines: segments [a, b]
drawn at the first picture and carried with the dye, in light blue (`--timeline`;
a RuntimeWarning says which were not resolved at some pictures, and why);
time_scale: how far the field carries that dye and those lines (`--time-scale`). progress(done, total) as pictures
are made; returning False from it stops the animation before its next picture and
raises tvf.Cancelled, as Ctrl-C stops it with KeyboardInterrupt: either way no file is
left (the PNG folder appears complete or not at all, a partial MP4 is removed). Bad
options raise ValueError naming the option.)");

  py::class_<PyDesign>(m, "Design", R"(A design you change step by step: the scene, its domain, the solver
set-up kept between solves (so re-solves after small changes start warm), the field
and its analysis, with undo and redo (tvf/api/design.h).

Design(scene): a dict, a scene file, or a folder written by `tvf generate` (its field is
read, not regenerated); Design(scene, vertices=V, faces=F): on a mesh given as arrays.)")
      .def(py::init([](const py::object& scene, const py::object& vertices, const py::object& faces, bool parallel) {
             DesignOptions o;
             o.parallel = parallel;
             if (!vertices.is_none() || !faces.is_none()) {
               Mesh mesh = mesh_of(vertices, faces);
               return PyDesign(Design(scene_of(with_array_domain(scene)), std::move(mesh), o));
             }
             if (py::isinstance<py::dict>(scene)) return PyDesign(Design(scene_of(scene), o));
             if (py::isinstance<py::str>(scene) || py::hasattr(scene, "__fspath__"))
               return PyDesign(Design::open(py::str(py::module_::import("os").attr("fspath")(scene)), o));
             throw py::type_error("a scene is a dict (the scene JSON) or a path");
           }),
           py::arg("scene"), py::kw_only(), py::arg("vertices") = py::none(), py::arg("faces") = py::none(),
           py::arg("parallel") = true,
           R"(Design(scene, *, vertices=None, faces=None, parallel=True). vertices/faces: the domain
as arrays, as in tvf.generate (the scene's domain becomes {"mesh": "vertices/faces"}, and
every later scene with that domain lives on these arrays).)")
      .def_property(
          "scene", [](const PyDesign& d) { return to_python(scene_to_json(d.design.scene())); },
          [](PyDesign& d, const py::dict& scene) { d.design.set_scene(to_json(scene), "scene"); },
          "The scene as a dict (canonical JSON: every key). Assign a dict to change it (validated; undoable).")
      .def(
          "generate",
          [](PyDesign& d, const py::object& progress, const py::object& cancel, const py::object& stage) {
            run_interruptible(progress, cancel, [&](GenerateOptions& o) { d.design.generate(o); }, stage);
            return d.field();
          },
          py::kw_only(), py::arg("progress") = py::none(), py::arg("cancel") = py::none(), py::arg("stage") = py::none(),
          "The field of the current scene (generated unless already there). progress/cancel/stage as tvf.generate.")
      .def_property_readonly("field", &PyDesign::field, "The field made last (ValueError when there is none).")
      .def_property_readonly("has_field", [](const PyDesign& d) { return d.design.has_field(); },
                             "Whether the current scene's field is there.")
      .def(
          "analyze",
          [](PyDesign& d, const py::object& progress, const py::object& cancel, const py::object& stage) {
            nlohmann::json j;
            run_interruptible(progress, cancel, [&](GenerateOptions& o) {
              d.design.generate(o);
              j = d.design.analysis_json();
            }, stage);
            return to_python(j);
          },
          py::kw_only(), py::arg("progress") = py::none(), py::arg("cancel") = py::none(), py::arg("stage") = py::none(),
          "The analysis JSON of DESIGN §9 of the current field (generated first if needed; progress/cancel/stage as tvf.generate).")
      .def(
          "check",
          [](PyDesign& d) -> py::object {
            std::optional<DesignCheck> c;
            run_interruptible(py::none(), py::none(), [&](GenerateOptions& o) {
              d.design.generate(o);
              c = d.design.check();
            });
            if (!c) return py::none();
            return to_python(design_check_to_json(*c));
          },
          "The design check (which designed features the field holds), as `tvf analyze` writes it.")
      .def(
          "edit",
          [](PyDesign& d, const py::object& entry, const py::kwargs& kwargs) {
            py::dict e;
            if (!entry.is_none()) {
              if (!py::isinstance<py::dict>(entry)) throw py::type_error("an edit is a dict such as {\"op\": \"smooth\", \"strength\": 0.5}");
              e = py::dict(entry);
            }
            for (auto item : kwargs) e[item.first] = item.second;
            const nlohmann::json j = to_json(e);
            EditReport r;
            run_interruptible(py::none(), py::none(), [&](GenerateOptions& o) {
              d.design.generate(o);
              r = d.design.edit(j);
            });
            return edit_report_dict(r);
          },
          py::arg("entry") = py::none(),
          R"(Applies a topological edit and appends it to the scene's edits (as `tvf edit`):
design.edit({"op": "cancel", "frame": 40, "pair": [[x1, y1], [x2, y2]]}) or
design.edit(op="smooth", strength=0.5). Ops: cancel, remove_bifurcation, move_bifurcation,
smooth (docs/scene_reference.md). A refused edit raises ValueError and changes nothing.
Returns {"summary", "key_frames", "window", "region_faces", "iterations", "residual"}.)")
      .def("undo", [](PyDesign& d) { d.design.undo(); }, "Back to the scene before the last change.")
      .def("redo", [](PyDesign& d) { d.design.redo(); }, "Forward again after undo().")
      .def_property_readonly("can_undo", [](const PyDesign& d) { return d.design.can_undo(); })
      .def_property_readonly("can_redo", [](const PyDesign& d) { return d.design.can_redo(); })
      .def(
          "save", [](const PyDesign& d, const std::optional<std::string>& path) { d.design.save(path.value_or("")); },
          py::arg("path") = py::none(), "Writes the scene file (atomically); default: the file it was read from. A mesh given as\narrays is written beside it (NAME.mesh.off) and the saved scene names that file.")
      .def(
          "write_outputs",
          [](PyDesign& d, const std::string& dir, bool vtk) {
            std::vector<std::filesystem::path> files;
            run_interruptible(py::none(), py::none(), [&](GenerateOptions& o) {
              d.design.generate(o);
              OutputOptions oo;
              oo.vtk = vtk;
              files = d.design.write_outputs(dir, oo);
            });
            return strings(files);
          },
          py::arg("dir"), py::kw_only(), py::arg("vtk") = true,
          "Writes what `tvf generate` writes (field.npy, vertices.npy, ..., field.tvff, VTK) into dir.")
      .def("__repr__", [](const PyDesign& d) {
        return std::string("<tvf.Design ") + (d.design.has_scene() ? d.design.scene().label() : "without scene") +
               (d.design.has_field() ? ", generated>" : ">");
      });
}
