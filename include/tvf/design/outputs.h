#pragma once
// Everything `tvf generate` writes (DESIGN §11), staged and committed as a whole so a
// failed run leaves no partial output:
//   field.npy (N×|V|×3 float32, world vectors, frame-major), vertices.npy (|V|×3 float64),
//   faces.npy (|F|×3 int32), times.npy (N float64), field.tvff (native, exact reload),
//   field.pvd + field_NNNN.vtu (VTK series), coherence.csv, scene.json (canonical scene),
//   divergence.json when the scene is "incompressible" (OutputOptions::incompressible),
//   keyframe_topology.json when its key-frame topology is "matched"
//   (OutputOptions::keyframe_intervals; keyframe_intervals_json's form).
#include "tvf/design/keyframe_topology.h"
#include "tvf/scene/design_space.h"
#include "tvf/scene/scene.h"
#include "tvf/field/field.h"
#include "tvf/solve/hodge_projection.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <vector>

namespace tvf {

struct OutputOptions {
  bool vtk = true;  // the VTK series can be large; `--no-vtk` skips it
  // Under mpirun with K > 1 ranks: each rank writes its own piece of every VTK frame
  // (field_NNNN_pR.vtu joined by field_NNNN.pvtu; `--vtk-pieces`) instead of rank 0 writing
  // the one-process series (field_NNNN.vtu), which stays the default so that K ranks write
  // the same outputs as one process (DESIGN.md §12). Ignored with one rank.
  bool vtk_pieces = false;
  std::function<void(const std::string&)> on_step;  // progress: name of the part written
  // The projection's report (GenerateReport::incompressible): written as divergence.json.
  const IncompressibleReport* incompressible = nullptr;
  // GenerateReport::keyframe_intervals: written as keyframe_topology.json when not empty.
  const std::vector<KeyframeIntervalReport>* keyframe_intervals = nullptr;
};

// divergence.json: {"boundary", "method", "seconds", "max_before", "max_after",
// "worst_residual", "times": [...], "before": [...], "after": [...]} (docs/file_formats.md).
nlohmann::json incompressible_report_json(const IncompressibleReport& report, const TimeSampling& time);

// Returns the paths written (final names inside `dir`).
std::vector<std::filesystem::path> write_field_outputs(const std::filesystem::path& dir,
                                                       const DesignSpace& space,
                                                       const Field& field, const Scene& scene,
                                                       const OutputOptions& options = {});

}  // namespace tvf
