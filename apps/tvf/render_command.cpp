#include "render_command.h"

#include "progress.h"
#include "render_input.h"

#include "tvf/core/error.h"
#include "tvf/scene/design_space.h"
#include "tvf/design/generate.h"
#include "tvf/scene/scene_json.h"
#include "tvf/field/field_io.h"
#include "tvf/render/crowd.h"
#include "tvf/render/grass.h"
#include "tvf/render/painterly.h"
#include "tvf/render/particles.h"
#include "tvf/render/surface_crowd.h"
#include "tvf/render/texture_animation.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>

namespace fs = std::filesystem;

namespace tvf::cli {

RenderCommand::RenderCommand(CLI::App& app) {
  render_ = app.add_subcommand(
      "render", "Pictures and videos of a field (texture animation, painterly strokes, crowds, particles, grass)");
  render_->require_subcommand(1);
  texture_ = render_->add_subcommand(
      "texture", "Dense texture animation (IBFV texture advection) of a field on a planar domain, or on a surface seen "
      "from a camera (offscreen OpenGL): PNG frames and/or MP4");
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
                       "so far, as trails), streamlines (evenly spaced, placed anew each frame: for stills), orbits "
                       "(periodic orbits and Hopf events, planar domains); "
                       "several at once as --overlay singularities paths")
      ->check(CLI::IsMember({"singularities", "paths", "streamlines", "orbits"}));
  texture_->add_option("--streakline", streaklines_,
                       "Inject dye at X,Y (planar domains) or X,Y,Z (surfaces: a point on or near the surface) from "
                       "the start of the animation and draw its streakline in every picture (give it again for more "
                       "seeds)");
  texture_->add_option("--timeline", timelines_,
                       "Draw the segment X0,Y0,X1,Y1 (planar) or X0,Y0,Z0,X1,Y1,Z1 (surfaces) at the start of the "
                       "animation and carry it with the dye: a material line in light blue in every picture (give it "
                       "again for more)");
  texture_->add_option("--time-scale", time_scale_,
                       "How far the field carries the --streakline dye: it travels as the field would carry it over "
                       "this many times its time range while the field itself changes at its own pace")
      ->capture_default_str();
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
  // Surfaces: the camera and the texture's samples (render/surface_texture.h).
  texture_->add_option("--view", view_, "Surfaces: direction from the mesh's centre to the camera, X,Y,Z (default 1,-0.6,0.5)")
      ->delimiter(',')
      ->expected(3);
  texture_->add_option("--up", up_, "Surfaces: the direction that points up in the picture, X,Y,Z (default 0,0,1)")
      ->delimiter(',')
      ->expected(3);
  texture_->add_option("--fov", fov_, "Surfaces: vertical field of view of the camera in degrees")->capture_default_str();
  texture_->add_option("--spacing", spacing_, "Surfaces: pixels between the texture's samples on the screen")
      ->capture_default_str();

  auto common = [&](CLI::App* sub, const char* outputs, bool seeded) {
    sub->add_option("input", input_, "Folder written by `tvf generate` (or its field.tvff), or a scene file")
        ->required();
    sub->add_option("-o,--output", outputs_, outputs)->required();
    sub->add_option("--fps", fps_, "Frames per second of the video")->capture_default_str();
    sub->add_option("--frames", frames_, "Pictures over the field's time range (default: the field's frames)");
    if (seeded) sub->add_option("--seed", seed_, "Random seed")->capture_default_str();
    sub->add_flag("-q,--quiet", quiet_, "Print nothing but errors and warnings");
  };
  const char* frames_or_video = "Output: a folder of PNG frames, or a file ending in .mp4 (give -o twice for both)";
  auto time_scale = [&](CLI::App* sub, const char* what) {
    sub->add_option("--time-scale", time_scale_,
                    fmt::format("How far the field carries the {}: they travel as the field would carry them over "
                                "this many times its time range while the field itself changes at its own pace",
                                what))
        ->capture_default_str();
  };
  painterly_ = render_->add_subcommand(
      "painterly", "Painterly animation: brush strokes over a picture, oriented and carried by the field (planar domains)");
  common(painterly_, frames_or_video, true);
  painterly_->add_option("--image", image_, "The picture to paint (PNG); the domain is stretched onto it")->required();
  painterly_->add_option("--mask", mask_,
                         "Where the field applies (PNG, white: moving strokes; black: strokes stay put); "
                         "default: everywhere");
  painterly_->add_option("--stroke-width", stroke_width_, "Stroke width in pixels")->capture_default_str();
  painterly_->add_option("--stroke-length", stroke_length_, "Stroke length in pixels")->capture_default_str();
  painterly_->add_option("--density", density_, "Strokes covering a pixel on average")->capture_default_str();
  time_scale(painterly_, "strokes");

  crowd_ = render_->add_subcommand(
      "crowd", "Crowd steering: agents moving by w_goal*G + w_field*F around obstacles to goals (planar domains, or "
               "on a surface by geodesic distance)");
  common(crowd_, "Output: a folder of PNG frames, a file ending in .mp4, and/or a file ending in .csv (trajectories)",
         false);
  crowd_->add_option("--crowd", crowd_file_, "The crowd file (JSON: agents, start, goals, obstacles, weights)")
      ->required();
  crowd_->add_option("--w-goal", weight_goal_, "Weight of the goal direction G (overrides the crowd file)");
  crowd_->add_option("--w-field", weight_field_, "Weight of the designed field F (overrides the crowd file)");
  crowd_->add_option("-s,--size", app_size_, "Pixels on the long side of the domain")->capture_default_str();
  crowd_->add_option("--view", view_, "Surfaces: direction from the mesh's centre to the camera, X,Y,Z (default 1,-0.6,0.5)")
      ->delimiter(',')
      ->expected(3);
  crowd_->add_option("--up", up_, "Surfaces: the direction that points up in the picture, X,Y,Z (default 0,0,1)")
      ->delimiter(',')
      ->expected(3);
  crowd_->add_option("--fov", fov_, "Surfaces: vertical field of view of the camera in degrees")->capture_default_str();

  particles_ = render_->add_subcommand(
      "particles", "Particles with self-spin: leaves carried by the field, at a constant angle to it (planar domains, "
                   "or on a surface seen from a camera)");
  common(particles_, frames_or_video, true);
  particles_->add_option("--count", count_, "Number of particles")->capture_default_str();
  particles_->add_option("--particle-size", particle_size_, "Leaf length in pixels")->capture_default_str();
  particles_->add_option("--spin", spin_,
                         "Angle in degrees from the advection direction to each leaf's up direction "
                         "(default: random per leaf)");
  particles_->add_option("-s,--size", app_size_, "Pixels on the long side of the domain")->capture_default_str();
  time_scale(particles_, "leaves");
  particles_->add_option("--streakline", streaklines_,
                         "Inject dye at X,Y (planar domains) or X,Y,Z (surfaces: a point on or near the surface) from "
                         "the start of the animation, carried with the leaves and drawn as fading smoke in every "
                         "picture (give it again for more seeds)");
  particles_->add_option("--timeline", timelines_,
                         "Draw the segment X0,Y0,X1,Y1 (planar) or X0,Y0,Z0,X1,Y1,Z1 (surfaces) at the start of the "
                         "animation and carry it with the leaves: a material line in light blue in every picture "
                         "(give it again for more)");
  particles_->add_option("--view", view_, "Surfaces: direction from the mesh's centre to the camera, X,Y,Z (default 1,-0.6,0.5)")
      ->delimiter(',')
      ->expected(3);
  particles_->add_option("--up", up_, "Surfaces: the direction that points up in the picture, X,Y,Z (default 0,0,1)")
      ->delimiter(',')
      ->expected(3);
  particles_->add_option("--fov", fov_, "Surfaces: vertical field of view of the camera in degrees")->capture_default_str();

  grass_ = render_->add_subcommand(
      "grass", "Grass: strands rooted on the ground whose tips an IK solve pulls toward the field (planar domains)");
  common(grass_, frames_or_video, true);
  grass_->add_option("--count", grass_count_, "Number of strands")->capture_default_str();
  grass_->add_option("--segments", grass_segments_, "Rigid segments per strand")->capture_default_str();
  grass_->add_option("--length", grass_length_, "Strand length as a fraction of the domain's longer side")
      ->capture_default_str();
  grass_->add_option("--bend", grass_bend_, "Degrees the tip leans from the vertical in full wind")
      ->capture_default_str();
  grass_->add_option("--wind-speed", grass_wind_,
                     "Field speed |V| that bends a strand fully (default: the field's 99th percentile)");
  grass_->add_option("--response", grass_response_,
                     "Exponent of the bend's response to the wind (above 1: stiff grass that stands in a breeze)")
      ->capture_default_str();
  grass_->add_option("--elevation", grass_elevation_, "Camera degrees above the ground (90: top-down)")
      ->capture_default_str();
  grass_->add_option("-s,--size", grass_size_, "Pixels on the long side of the picture")->capture_default_str();
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

namespace {

bool has_extension(const std::string& out, const char* lower) {
  std::string e = fs::path(out).extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e == lower;
}

// Splits the -o outputs into a frames folder and an MP4. A name with any other extension
// (out.avi, c.txt) is refused rather than made a folder of PNGs under that name; an
// existing folder may have any name.
void split_outputs(const std::vector<std::string>& outputs, std::string& frames_dir, std::string& video,
                   const char* kinds = "a folder of PNG frames (a name without an extension) or a file ending in "
                                       ".mp4") {
  for (const auto& out : outputs) {
    const bool mp4 = has_extension(out, ".mp4");
    std::error_code ec;
    if (!mp4 && fs::path(out).has_extension() && !fs::is_directory(out, ec))
      throw Error(fmt::format("-o {}: cannot write {} output; an output is {}", out,
                              fs::path(out).extension().string(), kinds));
    std::string& slot = mp4 ? video : frames_dir;
    if (!slot.empty())
      throw Error(fmt::format("{}: give at most one {} output", out, mp4 ? "MP4" : "frames folder"));
    slot = out;
  }
}

void print_report(const char* what, int frames, int width, int height, double seconds,
                  const std::vector<std::string>& files) {
  std::printf("rendered %d %s frames of %d×%d pixels in %.2f s; wrote", frames, what, width, height, seconds);
  for (const auto& f : files) std::printf(" %s", fs::absolute(f).lexically_normal().c_str());
  std::printf("\n");
}

}  // namespace

namespace {

// The --streakline seeds: X,Y on a planar domain (X,Y,0 too: it lies at z = 0), X,Y,Z on a
// surface.
std::vector<Vec3> parse_dye_seeds(const std::vector<std::string>& texts, const Mesh& mesh) {
  const bool planar = mesh.is_planar_xy();
  std::vector<Vec3> seeds;
  for (const auto& text : texts) {
    double x = 0, y = 0, z = 0;
    char c1 = 0, c2 = 0, extra = 0;
    const int n = std::sscanf(text.c_str(), "%lf %c %lf %c %lf %c", &x, &c1, &y, &c2, &z, &extra);
    const bool two = n == 3 && c1 == ',', three = n == 5 && c1 == ',' && c2 == ',';
    if (planar && !two && !three)
      throw Error(fmt::format("--streakline {}: expected X,Y (a point of the planar domain)", text));
    if (!planar && !three)
      throw Error(fmt::format("--streakline {}: expected X,Y,Z (a point on or near the surface)", text));
    if (planar && three && z != 0)
      throw Error(fmt::format("--streakline {}: Z = {} is off the planar domain, which lies at z = 0: give X,Y", text, z));
    seeds.push_back(Vec3(x, y, three ? z : 0.0));
  }
  return seeds;
}

// The --timeline segments: X0,Y0,X1,Y1 on a planar domain, X0,Y0,Z0,X1,Y1,Z1 on a surface.
std::vector<std::array<Vec3, 2>> parse_timelines(const std::vector<std::string>& texts, const Mesh& mesh) {
  const bool planar = mesh.is_planar_xy();
  const size_t want = planar ? 4 : 6;
  std::vector<std::array<Vec3, 2>> lines;
  for (const auto& text : texts) {
    std::vector<double> v;
    bool ok = true;
    for (size_t at = 0; ok && at <= text.size();) {
      const size_t comma = std::min(text.find(',', at), text.size());
      const std::string word = text.substr(at, comma - at);
      double x = 0;
      const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), x);
      ok = !word.empty() && ec == std::errc() && end == word.data() + word.size() && std::isfinite(x);
      v.push_back(x);
      at = comma + 1;
    }
    if (!ok || v.size() != want)
      throw Error(fmt::format("--timeline {}: expected {}", text,
                              planar ? "X0,Y0,X1,Y1 (two points of the planar domain)"
                                     : "X0,Y0,Z0,X1,Y1,Z1 (two points on or near the surface)"));
    const size_t d = want / 2;
    lines.push_back({Vec3(v[0], v[1], planar ? 0.0 : v[2]), Vec3(v[d], v[d + 1], planar ? 0.0 : v[d + 2])});
  }
  return lines;
}

// A --timeline drawn unresolved at some pictures: the picture alone does not say so. Warnings
// go to stderr even with --quiet, as the input's warnings do.
void warn_unresolved_timelines(const std::vector<TimelineRecord>& records, const std::vector<std::string>& texts) {
  for (size_t l = 0; l < records.size() && l < texts.size(); ++l) {
    const std::string note = unresolved_note(records[l], "--timeline " + texts[l], TimelineOptions{}.max_points);
    if (!note.empty()) std::fprintf(stderr, "warning: %s\n", note.c_str());
  }
}

}  // namespace

// --frames as given (refused below 1), or 0 for the field's own frames.
int RenderCommand::frames_or_default() const {
  if (!frames_) return 0;
  if (*frames_ < 1) throw Error(fmt::format("--frames {}: must be at least 1 (leave it out for the field's frames)", *frames_));
  return *frames_;
}

int RenderCommand::run() {
  if (!(std::isfinite(fps_) && fps_ > 0)) throw Error(fmt::format("--fps {}: must be a positive number", fps_));
  if (!(std::isfinite(time_scale_) && time_scale_ > 0))
    throw Error(fmt::format("--time-scale {}: must be a positive number", time_scale_));
  if (texture_->parsed()) return run_texture();
  if (painterly_->parsed()) return run_painterly();
  if (crowd_->parsed()) return run_crowd();
  if (particles_->parsed()) return run_particles();
  if (grass_->parsed()) return run_grass();
  return 1;
}

namespace {

// What a crowd run wrote; `trajectories_only`: no pictures were drawn, only the CSV.
void print_crowd_report(const AnimationReport& report, bool trajectories_only) {
  if (!trajectories_only)
    return print_report("crowd", report.frames, report.width, report.height, report.seconds, report.files);
  std::printf("simulated %d crowd frames in %.2f s; wrote", report.frames, report.seconds);
  for (const auto& f : report.files) std::printf(" %s", fs::absolute(f).lexically_normal().c_str());
  std::printf("\n");
}

}  // namespace

int RenderCommand::run_crowd() {
  const bool show = !quiet_ && progress_wanted();
  Progress progress("tvf render crowd", show);
  CrowdAnimationOptions options;
  std::vector<std::string> pictures;
  for (const auto& out : outputs_) {
    if (has_extension(out, ".csv")) {
      if (!options.csv.empty()) throw Error(fmt::format("{}: give at most one CSV output", out));
      options.csv = out;
    } else {
      pictures.push_back(out);
    }
  }
  split_outputs(pictures, options.frames_dir, options.video,
                "a folder of PNG frames (a name without an extension), a file ending in .mp4 or a file ending in "
                ".csv");
  options.frames = frames_or_default();
  options.fps = fps_;
  options.size = app_size_;
  RenderInput in = load_render_input(input_, progress, "crowd", true);
  const TangentBundle bundle(in.mesh);
  if (!bundle.is_flat()) {
    // A surface: agents walk on the mesh to goals by geodesic distance (render/surface_crowd.h).
    SurfaceCrowdSpec sspec = load_surface_crowd_spec(crowd_file_);
    if (weight_goal_) sspec.weight_goal = *weight_goal_;
    if (weight_field_) sspec.weight_field = *weight_field_;
    SurfaceCrowdAnimationOptions so;
    so.frames = options.frames;
    so.size = options.size;
    so.frames_dir = options.frames_dir;
    so.video = options.video;
    so.csv = options.csv;
    so.fps = options.fps;
    if (!view_.empty()) so.view.direction = Vec3(view_[0], view_[1], view_[2]);
    if (!up_.empty()) so.view.up = Vec3(up_[0], up_[1], up_[2]);
    so.view.fov = fov_;
    progress.note("simulating");
    so.progress = [&](int done, int total) { progress.update(done, total); };
    SurfaceCrowdResult sres;
    const AnimationReport sreport = write_surface_crowd_animation(bundle, in.field, sspec, so, &sres);
    progress.finish();
    for (const auto& w : in.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    if (!quiet_) {
      const long arrived = std::count_if(sres.arrived.begin(), sres.arrived.end(), [](int k) { return k >= 0; });
      std::printf("%ld of %zu agents reached a goal\n", arrived, sres.arrived.size());
      print_crowd_report(sreport, so.frames_dir.empty() && so.video.empty());
    }
    return 0;
  }
  CrowdSpec spec = load_crowd_spec(crowd_file_);
  if (weight_goal_) spec.weight_goal = *weight_goal_;
  if (weight_field_) spec.weight_field = *weight_field_;
  progress.note("simulating");
  options.progress = [&](int done, int total) { progress.update(done, total); };
  CrowdResult result;
  const AnimationReport report = write_crowd_animation(bundle, in.field, spec, options, &result);
  progress.finish();
  for (const auto& w : in.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  if (!quiet_) {
    const long arrived = std::count_if(result.arrived.begin(), result.arrived.end(), [](int k) { return k >= 0; });
    std::printf("%ld of %zu agents reached a goal\n", arrived, result.arrived.size());
    print_crowd_report(report, options.frames_dir.empty() && options.video.empty());
  }
  return 0;
}

int RenderCommand::run_particles() {
  const bool show = !quiet_ && progress_wanted();
  Progress progress("tvf render particles", show);
  ParticleAnimationOptions options;
  split_outputs(outputs_, options.frames_dir, options.video);
  options.frames = frames_or_default();
  options.fps = fps_;
  options.particles.count = count_;
  options.particles.size = particle_size_;
  options.particles.spin = std::isnan(spin_) ? spin_ : spin_ * kPi / 180.0;
  options.particles.image_size = app_size_;
  options.particles.seed = seed_;
  options.time_scale = time_scale_;
  if (!view_.empty()) options.surface.direction = Vec3(view_[0], view_[1], view_[2]);
  if (!up_.empty()) options.surface.up = Vec3(up_[0], up_[1], up_[2]);
  options.surface.fov = fov_;
  RenderInput in = load_render_input(input_, progress, "particles", true);
  options.dye_seeds = parse_dye_seeds(streaklines_, in.mesh);
  options.timelines = parse_timelines(timelines_, in.mesh);
  const TangentBundle bundle(in.mesh);
  progress.note("rendering");
  options.progress = [&](int done, int total) { progress.update(done, total); };
  const AnimationReport report = write_particle_animation(bundle, in.field, options);
  progress.finish();
  for (const auto& w : in.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  warn_unresolved_timelines(report.timelines, timelines_);
  if (!quiet_) print_report("particle", report.frames, report.width, report.height, report.seconds, report.files);
  return 0;
}

int RenderCommand::run_grass() {
  const bool show = !quiet_ && progress_wanted();
  Progress progress("tvf render grass", show);
  GrassAnimationOptions options;
  split_outputs(outputs_, options.frames_dir, options.video);
  options.frames = frames_or_default();
  options.fps = fps_;
  options.grass.count = grass_count_;
  options.grass.segments = grass_segments_;
  options.grass.length = grass_length_;
  options.grass.bend = grass_bend_;
  options.grass.wind_speed = grass_wind_;
  options.grass.response = grass_response_;
  options.grass.seed = seed_;
  options.render.elevation = grass_elevation_;
  options.render.image_size = grass_size_;
  RenderInput in = load_render_input(input_, progress, "grass", false);
  const TangentBundle bundle(in.mesh);
  progress.note("growing");
  options.progress = [&](int done, int total) { progress.update(done, total); };
  const AnimationReport report = write_grass_animation(bundle, in.field, options);
  progress.finish();
  for (const auto& w : in.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  if (!quiet_) print_report("grass", report.frames, report.width, report.height, report.seconds, report.files);
  return 0;
}

int RenderCommand::run_painterly() {
  const bool show = !quiet_ && progress_wanted();
  Progress progress("tvf render painterly", show);
  PainterlyAnimationOptions options;
  split_outputs(outputs_, options.frames_dir, options.video);
  options.frames = frames_or_default();
  options.fps = fps_;
  options.painterly.stroke_width = stroke_width_;
  options.painterly.stroke_length = stroke_length_;
  options.painterly.density = density_;
  options.painterly.seed = seed_;
  options.time_scale = time_scale_;
  const Image image = read_png(image_);
  const Image mask = mask_.empty() ? Image() : read_png(mask_);
  RenderInput in = load_render_input(input_, progress, "painterly", false);
  const TangentBundle bundle(in.mesh);
  progress.note("painting");
  options.progress = [&](int done, int total) { progress.update(done, total); };
  const AnimationReport report = write_painterly_animation(bundle, in.field, image, mask, options);
  progress.finish();
  for (const auto& w : in.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  if (!quiet_) print_report("painterly", report.frames, report.width, report.height, report.seconds, report.files);
  return 0;
}

int RenderCommand::run_texture() {
  const bool show = !quiet_ && progress_wanted();
  Progress progress("tvf render texture", show);

  TextureAnimationOptions options;
  split_outputs(outputs_, options.frames_dir, options.video);
  if (!range_.empty()) parse_range(range_, options.first, options.last);
  options.frames = frames_or_default();
  options.fps = fps_;
  for (const auto& what : overlay_) {
    options.overlay_singularities |= what == "singularities";
    options.overlay_paths |= what == "paths";
    options.overlay_streamlines |= what == "streamlines";
    options.overlay_orbits |= what == "orbits";
  }
  options.texture.size = size_;
  options.texture.alpha = alpha_;
  options.texture.lic = lic_;
  options.texture.noise_scale = noise_scale_;
  options.texture.pixels_per_frame = speed_;
  options.texture.speed = physical_ ? TextureSpeed::physical : TextureSpeed::uniform;
  options.texture.contrast = contrast_;
  options.texture.seed = seed_;
  if (!view_.empty()) options.surface.direction = Vec3(view_[0], view_[1], view_[2]);
  if (!up_.empty()) options.surface.up = Vec3(up_[0], up_[1], up_[2]);
  options.surface.fov = fov_;
  options.surface.spacing = spacing_;

  RenderInput in = load_render_input(input_, progress, "texture", true);
  options.streakline_seeds = parse_dye_seeds(streaklines_, in.mesh);
  options.timelines = parse_timelines(timelines_, in.mesh);
  options.dye_time_scale = time_scale_;
  const std::vector<std::string>& warnings = in.warnings;
  const Field& field = in.field;
  const TangentBundle bundle(in.mesh);

  progress.note("rendering");
  options.progress = [&](int done, int total) { progress.update(done, total); };
  const TextureAnimationReport report = write_texture_animation(bundle, field, options);
  progress.finish();
  for (const auto& w : warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  warn_unresolved_timelines(report.timelines, timelines_);
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
