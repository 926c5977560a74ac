#include "render_command.h"

#include "progress.h"

#include "tvf/core/error.h"
#include "tvf/design/design_space.h"
#include "tvf/design/generate.h"
#include "tvf/design/scene_json.h"
#include "tvf/field/field_io.h"
#include "tvf/render/texture_animation.h"

#include <fmt/format.h>

#include <charconv>
#include <cstdio>
#include <filesystem>

namespace fs = std::filesystem;

namespace tvf::cli {

RenderCommand::RenderCommand(CLI::App& app) {
  render_ = app.add_subcommand("render", "Pictures and videos of a field (texture animation)");
  render_->require_subcommand(1);
  texture_ = render_->add_subcommand(
      "texture", "Dense texture animation (IBFV texture advection) of a field on a planar domain: PNG frames and/or MP4");
  texture_->add_option("input", input_, "Folder written by `tvf generate` (or its field.tvff), or a scene file")
      ->required();
  texture_->add_option("-o,--output", outputs_,
                       "Output: a folder of PNG frames, or a file ending in .mp4 (give -o twice for both)")
      ->required();
  texture_->add_option("-s,--size", size_, "Pixels on the long side of the domain")->capture_default_str();
  texture_->add_option("--fps", fps_, "Frames per second of the video")->capture_default_str();
  texture_->add_option("--frames", frames_, "Pictures over the field's time range (default: the field's frames)");
  texture_->add_option("--range", range_, "Only pictures A to B of them (A:B, inclusive, from 0)");
  texture_->add_option("--overlay", overlay_,
                       "Draw over the texture: singularities (the frame's, as dots), paths (the singularity paths "
                       "so far, as trails), streamlines (evenly spaced, placed anew each frame: for stills); "
                       "several at once as --overlay singularities paths")
      ->check(CLI::IsMember({"singularities", "paths", "streamlines"}));
  texture_->add_option("--alpha", alpha_, "Weight of the fresh noise per frame (shorter streaks when larger)")
      ->capture_default_str();
  texture_->add_option("--noise-scale", noise_scale_, "Noise cell size in pixels (default: size/256)");
  texture_->add_option("--speed", speed_, "Pixels the texture moves per frame of the field (default: size/128)");
  texture_->add_flag("--physical-speed", physical_,
                     "Move the texture in proportion to the field's speed (the 90th-percentile speed moves --speed "
                     "pixels); by default it moves at one speed along the field everywhere");
  texture_->add_option("--lic", lic_,
                       "Pixels each way of the line integral convolution that smooths the advected texture "
                       "(default: size/64; 0: show the advected texture itself)");
  texture_->add_option("--contrast", contrast_, "Contrast of the pictures")->capture_default_str();
  texture_->add_option("--seed", seed_, "Noise seed")->capture_default_str();
  texture_->add_flag("-q,--quiet", quiet_, "Print nothing but errors and warnings");
}

namespace {

// "A:B" → (A, B).
void parse_range(const std::string& text, int& first, int& last) {
  const auto colon = text.find(':');
  auto number = [&](std::string_view s, int& out) {
    const auto r = std::from_chars(s.data(), s.data() + s.size(), out);
    return r.ec == std::errc() && r.ptr == s.data() + s.size();
  };
  if (colon == std::string::npos || !number(std::string_view(text).substr(0, colon), first) ||
      !number(std::string_view(text).substr(colon + 1), last))
    throw Error(fmt::format("--range {}: expected FIRST:LAST frame numbers, e.g. 0:49", text));
}

}  // namespace

int RenderCommand::run() {
  if (!texture_->parsed()) return 1;
  const bool show = !quiet_ && progress_wanted();
  Progress progress("tvf render texture", show);

  TextureAnimationOptions options;
  for (const auto& out : outputs_) {
    const bool mp4 = fs::path(out).extension() == ".mp4" || fs::path(out).extension() == ".MP4";
    std::string& slot = mp4 ? options.video : options.frames_dir;
    if (!slot.empty())
      throw Error(fmt::format("{}: give at most one {} output", out, mp4 ? "MP4" : "frames folder"));
    slot = out;
  }
  if (!range_.empty()) parse_range(range_, options.first, options.last);
  options.frames = frames_;
  options.fps = fps_;
  for (const auto& what : overlay_) {
    options.overlay_singularities |= what == "singularities";
    options.overlay_paths |= what == "paths";
    options.overlay_streamlines |= what == "streamlines";
  }
  options.texture.size = size_;
  options.texture.alpha = alpha_;
  options.texture.lic = lic_;
  options.texture.noise_scale = noise_scale_;
  options.texture.pixels_per_frame = speed_;
  options.texture.speed = physical_ ? TextureSpeed::physical : TextureSpeed::uniform;
  options.texture.contrast = contrast_;
  options.texture.seed = seed_;
  if (frames_ < 0) throw Error(fmt::format("--frames {}: must be at least 1", frames_));

  const fs::path input(input_);
  std::error_code ec;
  if (!fs::exists(input, ec))
    throw Error(fmt::format("{}: no such file or folder (give a folder written by `tvf generate`, "
                            "its field.tvff, or a scene file)", input_));
  const std::string surface_note =
      "surface texture rendering is not available yet: `tvf render texture` draws planar domains only "
      "(surfaces will be rendered with offscreen OpenGL in a later version)";
  std::vector<std::string> warnings;
  Mesh mesh;
  Field field;
  if (fs::is_directory(input, ec) || input.extension() == ".tvff") {
    const fs::path file = fs::is_directory(input, ec) ? input / "field.tvff" : input;
    if (!fs::exists(file, ec))
      throw Error(fmt::format("{}: no field.tvff in this folder (write one with `tvf generate SCENE -o {}`)", input_,
                              input_));
    progress.note("reading the field");
    FieldFile ff = load_field_file(file.string());
    mesh = std::move(ff.mesh);
    field = std::move(ff.field);
  } else {
    const Scene scene = load_scene(input_);
    progress.note("building the domain");
    const auto space = make_design_space(scene);
    if (!space->planar()) throw Error(fmt::format("{}: {}", input_, surface_note));
    GenerateOptions gen;
    gen.progress = [&](int done, int total) { progress.update(done, total); };
    GenerateReport report;
    field = generate(*space, scene, gen, &report);
    warnings = report.warnings;
    mesh = space->mesh();
  }
  const TangentBundle bundle(mesh);
  if (!bundle.is_flat()) throw Error(fmt::format("{}: {}", input_, surface_note));

  progress.note("rendering");
  options.progress = [&](int done, int total) { progress.update(done, total); };
  const TextureAnimationReport report = write_texture_animation(bundle, field, options);
  progress.finish();
  for (const auto& w : warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  if (!quiet_) {
    std::printf("rendered %d frames of %d×%d pixels in %.2f s", report.frames, report.width, report.height,
                report.seconds);
    if (report.frames > 1 && report.texture_seconds > 0)
      std::printf(" (texture %.1f frames/s)", (report.frames - 1) / report.texture_seconds);
    std::printf("; wrote");
    for (const auto& f : report.files) std::printf(" %s", fs::absolute(f).lexically_normal().c_str());
    std::printf("\n");
  }
  return 0;
}

}  // namespace tvf::cli
