#include "synth_command.h"

#include "progress.h"
#include "render_input.h"

#include "tvf/core/error.h"
#include "tvf/scene/design_space.h"
#include "tvf/design/generate.h"
#include "tvf/scene/scene_json.h"
#include "tvf/field/field_io.h"
#include "tvf/render/mesh_renderer.h"
#include "tvf/synth/planar_synthesis.h"
#include "tvf/synth/surface_synthesis.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <filesystem>

namespace fs = std::filesystem;

namespace tvf::cli {

SynthCommand::SynthCommand(CLI::App& render) {
  auto common = [&](CLI::App* sub, const char* exemplar_help) {
    sub->add_option("input", input_, "Folder written by `tvf generate` (or its field.tvff), or a scene file")
        ->required();
    sub->add_option("-o,--output", outputs_,
                    "Pictures: a folder of PNG frames, or a file ending in .mp4 (give -o twice for both); "
                    "surfaces are drawn from a camera (--view, --up)");
    sub->add_option("--meshes", meshes_, "Folder for one mesh per frame (frame_00000.ply …)");
    sub->add_option("--exemplar", exemplar_, exemplar_help)->required();
    sub->add_option("--exemplar-size", exemplar_size_, "Pixels of a procedural exemplar")->capture_default_str();
    sub->add_option("-s,--size", size_, "Pixels on the long side of the domain (surfaces: of the square picture)")
        ->capture_default_str();
    sub->add_option("--view", view_, "Surfaces: direction from the mesh's centre to the camera, X,Y,Z (default 1,-0.6,0.5)")
        ->delimiter(',')
        ->expected(3);
    sub->add_option("--up", up_, "Surfaces: the direction that points up in the picture, X,Y,Z (default 0,0,1)")
        ->delimiter(',')
        ->expected(3);
    sub->add_option("--frames", frames_, "Pictures over the field's time range (default: the field's frames)");
    sub->add_option("--fps", fps_, "Frames per second of the video")->capture_default_str();
    sub->add_option("--levels", levels_, "Resolution levels of the first frame")->capture_default_str();
    sub->add_option("--frame-levels", frame_levels_, "Levels run on each later frame")->capture_default_str();
    sub->add_option("--neighbourhood", neighbourhood_, "Neighbourhood size in samples (odd)")->capture_default_str();
    sub->add_option("--iterations", iterations_, "Optimization iterations per level and frame")->capture_default_str();
    sub->add_option("--first-iterations", iterations_first_, "Iterations per level on the first frame")
        ->capture_default_str();
    sub->add_option("--stride", stride_, "Planar: pixels between neighbourhood centres")->capture_default_str();
    sub->add_option("--temporal-weight", temporal_weight_,
                    "Weight of the previous frame carried by the field (higher: steadier, slower to adapt)")
        ->capture_default_str();
    sub->add_option("--max-distortion", max_distortion_,
                    "Planar: renew texture that the flow stretched or squeezed along some axis by more than this "
                    "factor (0: never)")
        ->capture_default_str();
    sub->add_option("--renew-frames", renew_frames_, "Planar: frames of the cross-fade to fresh texture")
        ->capture_default_str();
    sub->add_option("--speed", speed_,
                    "Pixels (surfaces: texels) the texture moves per frame of the field at the field's typical speed "
                    "(default: size/256 planar; on surfaces one mean edge length of the mesh)");
    sub->add_option("--texel", texel_, "Surfaces: world length of one exemplar pixel (default: the samples' spacing)");
    sub->add_option("--density", density_,
                    "Surfaces: samples per mesh edge, each face split into density² triangles (1: a sample per vertex; "
                    "default 0: automatic, about 60,000 samples or more)")
        ->capture_default_str();
    sub->add_option("--seed", seed_, "Random seed of the first frame")->capture_default_str();
    sub->add_flag("-q,--quiet", quiet_, "Print nothing but errors and warnings");
  };
  synth_ = render.add_subcommand(
      "synth", "Exemplar-based texture synthesis oriented and carried by the field (Kwatra et al. 2005/2007): "
               "PNG frames / MP4 on planar domains, per-vertex coloured PLY meshes on surfaces");
  common(synth_, "Exemplar picture (PNG or JPEG), or a procedural one: stripes, pebbles");
  terrain_ = render.add_subcommand(
      "terrain", "Evolving terrain: a height map synthesized from a height exemplar displaces the domain "
                 "(hillshaded PNG frames / MP4 on planar domains; OBJ/PLY meshes per frame)");
  common(terrain_, "Height-map exemplar (PNG or JPEG, gray = height), or a procedural one: ridges, dunes");
  terrain_->add_option("--mesh-format", mesh_format_, "Mesh files: obj or ply (PLY with colours by height)")
      ->check(CLI::IsMember({"obj", "ply"}));
  terrain_->add_option("--mesh-resolution", mesh_resolution_, "Planar: vertices on the long side of each mesh")
      ->capture_default_str();
  height_scale_option_ = terrain_->add_option("--height-scale", height_scale_,
                       "Height 1 as a fraction of the domain (planar: long side, default 0.1; surfaces: "
                       "bounding-box diagonal, default 0.03)");
  terrain_->add_option("--relief", relief_, "Planar pictures: hillshade exaggeration (default: size/8)");
}

namespace {

Exemplar exemplar_for(const std::string& name, int channels, int size, std::uint64_t seed) {
  std::error_code ec;
  if (!fs::exists(name, ec) && fs::path(name).extension().empty()) {
    if (name != "stripes" && name != "pebbles" && name != "ridges" && name != "dunes")
      throw Error(fmt::format("--exemplar {}: no such picture, and not a procedural exemplar "
                              "(stripes, pebbles, ridges or dunes)", name));
    const ProceduralExemplar kind = parse_procedural_exemplar(name);
    Exemplar e = make_procedural_exemplar(kind, size, seed);
    if (e.channels != channels)
      throw Error(fmt::format("--exemplar {}: a {} exemplar; this command needs a {}", name,
                              e.channels == 1 ? "height-map" : "colour", channels == 1 ? "height map (ridges, dunes)"
                                                                                        : "colour one (stripes, pebbles)"));
    return e;
  }
  return load_exemplar(name, channels);
}

// The library names its options as in SynthesisOptions ("synthesis option frame_levels:
// …"); on the command line the sentence names the flag the user typed.
[[noreturn]] void rethrow_with_flag_names(const Error& e) {
  static const std::pair<const char*, const char*> flags[] = {
      {"size", "--size"}, {"levels", "--levels"}, {"frame_levels", "--frame-levels"},
      {"neighbourhood", "--neighbourhood"}, {"stride", "--stride"}, {"iterations_first", "--first-iterations"},
      {"iterations", "--iterations"}, {"temporal_weight", "--temporal-weight"}, {"pixels_per_frame", "--speed"},
      {"texel", "--texel"}, {"density", "--density"}, {"max_distortion", "--max-distortion"}, {"renew_frames", "--renew-frames"}, {"relief", "--relief"}, {"height_scale", "--height-scale"},
      {"mesh_resolution", "--mesh-resolution"}};
  const std::string message = e.what();
  const std::string prefix = "synthesis option ";
  if (message.rfind(prefix, 0) == 0)
    for (const auto& [name, flag] : flags) {
      const std::string key = prefix + name + ":";
      if (message.rfind(key, 0) == 0) throw Error(flag + message.substr(key.size() - 1));
    }
  throw e;
}

}  // namespace

int SynthCommand::run() {
  try {
    return run_checked();
  } catch (const Error& e) {
    rethrow_with_flag_names(e);
  }
}

int SynthCommand::run_checked() {
  const bool terrain = terrain_->parsed();
  const char* label = terrain ? "tvf render terrain" : "tvf render synth";
  Progress progress(label, !quiet_ && progress_wanted());
  std::string frames_dir, video;
  for (const auto& out : outputs_) {
    const bool mp4 = fs::path(out).extension() == ".mp4" || fs::path(out).extension() == ".MP4";
    std::error_code ec;
    if (!mp4 && fs::path(out).has_extension() && !fs::is_directory(out, ec))
      throw Error(fmt::format("-o {}: cannot write {} output; an output is a folder of PNG frames (a name without an "
                              "extension) or a file ending in .mp4",
                              out, fs::path(out).extension().string()));
    std::string& slot = mp4 ? video : frames_dir;
    if (!slot.empty()) throw Error(fmt::format("{}: give at most one {} output", out, mp4 ? "MP4" : "frames folder"));
    slot = out;
  }
  if (frames_dir.empty() && video.empty() && meshes_.empty())
    throw Error(fmt::format("{}: give -o (PNG frames folder or .mp4) and/or --meshes FOLDER", label));
  if (frames_ != kFramesNotGiven && frames_ < 1)
    throw Error(fmt::format("--frames {}: must be at least 1 (leave it out for the field's frames)", frames_));
  const int frames = frames_ == kFramesNotGiven ? 0 : frames_;
  const Exemplar exemplar = exemplar_for(exemplar_, terrain ? 1 : 3, exemplar_size_, seed_);

  SynthesisOptions so;
  so.size = size_;
  so.levels = levels_;
  so.frame_levels = frame_levels_;
  so.neighbourhood = neighbourhood_;
  so.iterations = iterations_;
  so.iterations_first = iterations_first_;
  so.stride = stride_;
  so.temporal_weight = temporal_weight_;
  so.pixels_per_frame = speed_;
  so.texel = texel_;
  so.density = density_;
  so.max_distortion = max_distortion_;
  so.renew_frames = renew_frames_;
  so.seed = seed_;

  RenderInput in = load_render_input(input_, progress, "synth", true);
  const TangentBundle& bundle = in.space->bundle();
  progress.note("synthesizing");
  SynthesisAnimationReport report;
  if (in.mesh.is_planar_xy()) {
    SynthesisAnimationOptions options;
    options.synthesis = so;
    options.frames = frames;
    options.terrain = terrain;
    options.relief = relief_;
    options.frames_dir = frames_dir;
    options.video = video;
    options.meshes_dir = meshes_;
    if (!mesh_format_.empty()) options.mesh_format = mesh_format_;
    options.mesh_resolution = mesh_resolution_;
    if (height_scale_option_->count() > 0) options.height_scale = height_scale_;
    options.fps = fps_;
    options.progress = [&](int done, int total) { progress.update(done, total); };
    if (!terrain && !meshes_.empty())
      throw Error("--meshes: planar texture synthesis writes pictures (-o); meshes per frame are for terrain and surfaces");
    report = write_planar_synthesis(bundle, in.field, exemplar, options);
  } else {
    SurfaceSynthesisAnimationOptions options;
    if (!frames_dir.empty() || !video.empty()) {
      // Pictures through the offscreen mesh renderer, from a camera framed once on the
      // undisplaced mesh (so terrain does not make the view jump between frames).
      const Vec3 direction = view_.empty() ? Vec3(1, -0.6, 0.5) : Vec3(view_[0], view_[1], view_[2]);
      const Vec3 up = up_.empty() ? Vec3(0, 0, 1) : Vec3(up_[0], up_[1], up_[2]);
      const Camera camera = Camera::framing(in.mesh.positions(), direction, up);
      auto renderer = std::make_shared<MeshRenderer>();
      RenderOptions ro;
      ro.width = ro.height = size_;
      options.renderer = [renderer, camera, ro](const Mesh& mesh, const std::vector<Vec3>& colours) {
        std::vector<std::uint32_t> packed(colours.size());
        for (size_t v = 0; v < colours.size(); ++v) {
          auto channel = [&](double x) { return static_cast<std::uint32_t>(std::clamp(x, 0.0, 1.0) * 255.0 + 0.5); };
          packed[v] = (channel(colours[v].x()) << 16) | (channel(colours[v].y()) << 8) | channel(colours[v].z());
        }
        renderer->set_mesh(mesh);
        renderer->set_colors(packed);
        return renderer->render(camera, ro);
      };
    }
    options.synthesis = so;
    options.frames = frames;
    options.terrain = terrain;
    options.meshes_dir = meshes_;
    options.frames_dir = frames_dir;
    options.video = video;
    if (!mesh_format_.empty()) options.mesh_format = mesh_format_;
    if (height_scale_option_->count() > 0) options.height_scale = height_scale_;
    options.fps = fps_;
    options.progress = [&](int done, int total) { progress.update(done, total); };
    report = write_surface_synthesis(bundle, in.field, exemplar, options);
  }
  progress.finish();
  for (const auto& w : in.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  if (!quiet_) {
    std::printf("synthesized %d frames in %.2f s (first %.2f s, then %.2f s per frame; patch distance %.3f); wrote",
                report.frames, report.seconds, report.first_frame_seconds, report.mean_frame_seconds,
                report.mean_patch_distance);
    for (const auto& f : report.files) std::printf(" %s", fs::absolute(f).lexically_normal().c_str());
    std::printf("\n");
  }
  return 0;
}

}  // namespace tvf::cli
