#include "tvf/design/outputs.h"

#include "tvf/analysis/coherence.h"
#include "tvf/core/atomic_output.h"
#include "tvf/core/error.h"
#include "tvf/scene/scene_json.h"
#include "tvf/field/field_io.h"
#include "tvf/field/npy.h"
#include "tvf/field/vtk_io.h"
#include "tvf/field/world_vectors.h"
#include "tvf/solve/distributed.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <optional>
#include <string>
#include <string_view>

namespace tvf {

namespace {

bool all_digits(std::string_view s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// The distributed VTK series (mpirun -n K, K > 1): field_NNNN.pvtu and its pieces
// field_NNNN_pR.vtu.
bool is_vtk_parallel_name(const std::string& name) {
  constexpr std::string_view prefix = "field_";
  if (!name.starts_with(prefix)) return false;
  const std::string_view rest = std::string_view(name).substr(prefix.size());
  if (rest.ends_with(".pvtu")) return all_digits(rest.substr(0, rest.size() - 5));
  if (!rest.ends_with(".vtu")) return false;
  const std::string_view body = rest.substr(0, rest.size() - 4);
  const size_t p = body.find("_p");
  return p != std::string_view::npos && all_digits(body.substr(0, p)) && all_digits(body.substr(p + 2));
}

}  // namespace

nlohmann::json incompressible_report_json(const IncompressibleReport& r, const TimeSampling& time) {
  return {{"boundary", to_string(r.boundary)},
          {"method", r.method},
          {"seconds", r.seconds},
          {"max_before", r.max_before},
          {"max_after", r.max_after},
          {"worst_residual", r.worst_residual},
          {"times", time.times()},
          {"before", r.before},
          {"after", r.after}};
}

std::vector<std::filesystem::path> write_field_outputs(const std::filesystem::path& dir,
                                                       const DesignSpace& space,
                                                       const Field& field, const Scene& scene,
                                                       const OutputOptions& options) {
  // Written into the scene's own folder, the outputs keep the input scene as the user wrote
  // it: the scene.json of the outputs would replace it (in canonical form, its mesh path
  // made absolute).
  std::error_code same_ec;
  const bool input_scene_here =
      !scene.source_path.empty() && std::filesystem::equivalent(dir / "scene.json", scene.source_path, same_ec);
  // Under mpirun with K > 1 ranks (solve/distributed.h) every rank comes here: rank 0 stages
  // and writes the assembled outputs (by default the same as one process); with
  // options.vtk_pieces every rank writes its pieces of the VTK frames into rank 0's staging
  // folder (a folder all ranks see), and rank 0 commits once all did. After the spacetime
  // generator rank 0 alone holds the whole field and each rank its share.
  const int ranks = distributed_ranks();
  const int rank = distributed_rank();
  const bool root = rank == 0;
  const bool pieces = ranks > 1 && options.vtk && options.vtk_pieces;
  // Nothing non-finite is written (the formats have no NaN): such a field means the
  // design's numbers were too extreme to compute with. (The ranks agree, so that all stop.)
  size_t bad = field.data().size();
  for (size_t k = 0; k < field.data().size() && bad == field.data().size(); ++k) {
    const cplx z = field.data()[k];
    if (!std::isfinite(z.real()) || !std::isfinite(z.imag())) bad = k;
  }
  const bool finite = bad == field.data().size();
  if (!(ranks > 1 ? distributed_all(finite) : finite)) {
    if (finite) throw Error(fmt::format("{}: the computed field is not finite on rank 0; nothing was written", scene.label()));
    throw_input_error(scene.label(), "",
                      fmt::format("the computed field is not finite at frame {}, vertex {} (the design's numbers "
                                  "are too extreme to compute with); nothing was written",
                                  bad / static_cast<size_t>(field.num_vertices()),
                                  bad % static_cast<size_t>(field.num_vertices())));
  }
  std::optional<OutputStage> staged;
  std::exception_ptr failure;
  std::string stage_path;
  if (root) {
    try {
      staged.emplace(dir);
      stage_path = staged->stage().string();
    } catch (...) {
      if (ranks == 1) throw;
      failure = std::current_exception();
    }
  }
  const Mesh& mesh = space.mesh();
  const std::vector<int> owners = pieces ? distributed_vertex_owners(mesh.num_vertices()) : std::vector<int>();
  std::vector<cplx> piece_values;  // this rank's piece, from the ranks' shares (not rank 0's)
  bool from_shares = false;
  if (ranks > 1) {
    stage_path = distributed_broadcast(stage_path);
    if (failure) std::rethrow_exception(failure);
    if (stage_path.empty()) return {};  // rank 0 reports why
    // Where the field is rank 0's alone, the other ranks write their pieces from their
    // shares: first made current where rank 0 changed the field after the solve (edits, the
    // projection), then each rank's halo vertices received from their ranks.
    // (Agreed by all ranks: some rank holds no whole field.)
    from_shares = pieces && !distributed_all(field.num_vertices() == mesh.num_vertices());
    if (from_shares) {
      TVF_CHECK(distributed_has_share(), "a rank holds neither the field nor its share");
      if (!scene.edits.empty() || scene.incompressible) distributed_refresh_share(field);
      piece_values = distributed_share_values(root ? std::vector<int>() : vtk_piece_points(mesh, owners, rank));
    }
    if (!root) {
      // This rank's pieces of the VTK series; rank 0 commits them when every rank wrote its own.
      try {
        if (from_shares)
          write_vtk_series_piece(stage_path, "field", space.bundle(), field.time(), owners, rank, piece_values);
        else if (pieces)
          write_vtk_series_piece(stage_path, "field", space.bundle(), field, owners, rank);
      } catch (...) {
        failure = std::current_exception();
      }
      distributed_all(!failure);
      if (failure) std::rethrow_exception(failure);
      return {};
    }
  }
  OutputStage& stage = *staged;
  const auto nv = static_cast<size_t>(mesh.num_vertices());
  const auto nf = static_cast<size_t>(mesh.num_faces());
  const auto n = static_cast<size_t>(field.frames());
  auto step = [&](const char* what) {
    if (options.on_step) options.on_step(what);
  };
  try {
    step("field.npy");
    // Frame by frame: the 32-bit world vectors of one frame at a time (not 12 more bytes
    // per vertex-frame beside the field).
    write_npy_parts(stage.file("field.npy").string(), {n, nv, 3}, n, [&](size_t j) {
      std::vector<float> world = world_vectors_f32(space.bundle(), field, static_cast<int>(j));
      if (!std::all_of(world.begin(), world.end(), [](float x) { return std::isfinite(x); }))
        throw_input_error(scene.label(), "",
                          "the computed field's vectors exceed the range of field.npy's 32-bit floats (the design's "
                          "numbers are too extreme); nothing was written");
      return world;
    });

    step("vertices.npy, faces.npy, times.npy");
    std::vector<double> verts(nv * 3);
    for (size_t v = 0; v < nv; ++v)
      for (size_t k = 0; k < 3; ++k)
        verts[3 * v + k] = mesh.position(static_cast<int>(v))[static_cast<Eigen::Index>(k)];
    write_npy(stage.file("vertices.npy").string(), {nv, 3}, verts.data());
    std::vector<std::int32_t> faces(nf * 3);
    for (size_t f = 0; f < nf; ++f)
      for (size_t k = 0; k < 3; ++k) faces[3 * f + k] = mesh.face(static_cast<int>(f))[k];
    write_npy(stage.file("faces.npy").string(), {nf, 3}, faces.data());
    const std::vector<double> times = field.time().times();
    write_npy(stage.file("times.npy").string(), {n}, times.data());

    step("field.tvff");
    // The copy of the scene must stay valid next to the outputs: its mesh path is made
    // absolute (relative paths were relative to the original scene file).
    Scene copy = scene;
    auto absolute = [&](const std::string& p) {
      return std::filesystem::absolute(scene.resolve_path(p)).lexically_normal().string();
    };
    if (!copy.domain.mesh.empty()) copy.domain.mesh = absolute(copy.domain.mesh);
    for (Keyframe& k : copy.keyframes)
      if (!k.field.empty()) k.field = absolute(k.field);
    const nlohmann::json scene_json = scene_to_json(copy);
    save_field_file(stage.file("field.tvff").string(), mesh, field, scene_json);

    step("coherence.csv, scene.json");
    write_file_atomically(stage.file("coherence.csv"), coherence_csv(field, coherence(field)));
    if (!input_scene_here) write_file_atomically(stage.file("scene.json"), scene_to_text(copy));

    if (options.incompressible) {
      step("divergence.json");
      write_file_atomically(stage.file("divergence.json"),
                            incompressible_report_json(*options.incompressible, field.time()).dump(2) + "\n");
    }

    if (options.keyframe_intervals && !options.keyframe_intervals->empty()) {
      step("keyframe_topology.json");
      const nlohmann::json intervals{{"intervals", keyframe_intervals_json(*options.keyframe_intervals)}};
      write_file_atomically(stage.file("keyframe_topology.json"), intervals.dump(2) + "\n");
    }

    if (options.vtk) {
      if (!pieces) {
        step("field.pvd + field_NNNN.vtu");
        write_vtk_series(stage.stage().string(), "field", space.bundle(), field);
      } else {
        step("field.pvd + field_NNNN.pvtu + field_NNNN_pR.vtu");
        write_vtk_series_piece(stage.stage().string(), "field", space.bundle(), field, owners, rank);
      }
    }
  } catch (...) {
    if (ranks == 1) throw;
    failure = std::current_exception();
  }
  if (ranks > 1) {
    const bool all_wrote = distributed_all(!failure);
    if (failure) std::rethrow_exception(failure);
    if (!all_wrote)
      throw Error(fmt::format("{}: another rank could not write its pieces of the VTK series; nothing was "
                            "written",
                            dir.string()));
    if (pieces) write_vtk_parallel_series(stage.stage().string(), "field", field.time().times(), ranks);
  }
  // The outputs of an earlier run into the same folder that this run does not write
  // (divergence.json without "incompressible", the VTK series with --no-vtk or fewer
  // frames) go in the same commit.
  return stage.commit([input_scene_here](const std::string& name) {
    if (name == "scene.json") return !input_scene_here;
    return name == "field.npy" || name == "vertices.npy" || name == "faces.npy" || name == "times.npy" ||
           name == "field.tvff" || name == "coherence.csv" || name == "divergence.json" ||
           name == "keyframe_topology.json" || name == "field.pvd" || is_numbered_name(name, "field_", ".vtu") ||
           is_vtk_parallel_name(name);
  });
}

}  // namespace tvf
