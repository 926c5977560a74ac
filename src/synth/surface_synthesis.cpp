#include "tvf/synth/surface_synthesis.h"

#include "tvf/core/error.h"
#include "tvf/field/field_sampler.h"
#include "tvf/integrate/surface_walk.h"
#include "tvf/mesh/face_subdivision.h"
#include "tvf/render/frame_output.h"
#include "tvf/synth/terrain.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace tvf {

namespace {

void check_option(bool ok, const char* name, const std::string& why) {
  if (!ok) throw Error(fmt::format("synthesis option {}: {}", name, why));
}

inline void point_tap(const Mesh& mesh, const SurfacePoint& p, Tap& tap) {
  const Face& f = mesh.face(p.face);
  for (size_t c = 0; c < 3; ++c) {
    tap.sample[c] = f[c];
    tap.weight[c] = static_cast<float>(p.bary[static_cast<Eigen::Index>(c)]);
  }
  tap.sample[3] = f[0];
  tap.weight[3] = 0.f;
}

}  // namespace

Field resample_field(const TangentBundle& bundle, const Field& field, const TangentBundle& samples,
                     const FaceSubdivision& subdivision) {
  const int ns = samples.mesh().num_vertices();
  TVF_CHECK(static_cast<size_t>(ns) == subdivision.face.size(), "{} samples, {} subdivision vertices", ns,
            subdivision.face.size());
  Field out(field.time(), ns);
  const FieldSampler sampler(bundle, field);
  const TimeSampling& ts = field.time();
  tbb::parallel_for(tbb::blocked_range<int>(0, ns, 1024), [&](const tbb::blocked_range<int>& range) {
    for (int v = range.begin(); v < range.end(); ++v) {
      const SurfacePoint p{subdivision.face[static_cast<size_t>(v)], subdivision.bary[static_cast<size_t>(v)]};
      for (int j = 0; j < ts.frames; ++j) {
        const Vec3 w = sampler.world(p, ts.time(j));
        cplx z = samples.world_to_vertex(v, w);
        const double m = std::abs(z);
        if (m > 0) z *= w.norm() / m;
        out.at(j, v) = z;
      }
    }
  });
  return out;
}

namespace {

// The samples: the mesh's vertices (density 1) or those of its faces subdivided. The field
// is read there frame by frame (Impl::vertex_values), not resampled for all its frames at
// once: memory does not grow with the field's frames.
struct SampleSurface {
  int density = 1;
  std::unique_ptr<FaceSubdivision> subdivision;
  std::unique_ptr<TangentBundle> bundle;
};

int automatic_density(const Mesh& mesh) {
  // The smallest subdivision with at least 60,000 samples, at most 8 per edge.
  int n = 1;
  while (n < 8 && subdivision_vertex_count(mesh, n) < 60'000) ++n;
  return n;
}

SampleSurface make_samples(const TangentBundle& bundle, int density) {
  SampleSurface s;
  s.density = density > 0 ? density : automatic_density(bundle.mesh());
  if (s.density == 1) return s;
  s.subdivision = std::make_unique<FaceSubdivision>(subdivide_faces(bundle.mesh(), s.density));
  s.bundle = std::make_unique<TangentBundle>(s.subdivision->mesh);
  return s;
}

}  // namespace

struct SurfaceSynthesizer::Impl {
  SampleSurface samples;
  const TangentBundle& bundle;  // of the samples
  const TangentBundle& input;   // of the field's mesh
  const Field& field;           // on the input mesh
  SynthesisOptions o;
  int C = 3;
  double texel_ = 0;
  std::vector<Exemplar> exemplars;
  std::vector<std::unique_ptr<ExemplarIndex>> indices;
  std::vector<Neighbourhoods> nbs;
  std::vector<std::vector<int>> matches;   // per level: the last match of each vertex (search hints)
  std::vector<std::vector<cplx>> built;    // per level: the direction each vertex's grid was walked for
  std::vector<SurfacePoint> vertex_point;  // each vertex as a point of its first face
  std::vector<int> vertex_halfedge;        // the halfedge leaving it in that face
  std::vector<float> x, target;
  double p90 = 0, time_scale = 0;  // world length per (unit speed × unit time)
  double t = 0;
  bool started = false;
  SynthesisFrameReport report;

  Impl(const TangentBundle& b, const Field& f, const Exemplar& e, const SynthesisOptions& options)
      : samples(make_samples(b, checked_density(options.density))),
        bundle(samples.bundle ? *samples.bundle : b),
        input(b),
        field(f),
        o(options),
        C(e.channels) {
    const Mesh& mesh = bundle.mesh();
    check_option(o.levels >= 1 && o.levels <= 8, "levels", fmt::format("{} is outside [1, 8]", o.levels));
    check_option(o.frame_levels >= 1 && o.frame_levels <= o.levels, "frame_levels",
                 fmt::format("{} is outside [1, levels = {}]", o.frame_levels, o.levels));
    check_option(o.neighbourhood >= 3 && o.neighbourhood <= 21 && o.neighbourhood % 2 == 1, "neighbourhood",
                 fmt::format("{} must be odd, in [3, 21]", o.neighbourhood));
    check_option(o.iterations_first >= 1 && o.iterations_first <= 100, "iterations_first",
                 fmt::format("{} is outside [1, 100]", o.iterations_first));
    check_option(o.iterations >= 1 && o.iterations <= 100, "iterations", fmt::format("{} is outside [1, 100]", o.iterations));
    check_option(std::isfinite(o.temporal_weight) && o.temporal_weight >= 0 && o.temporal_weight <= 100, "temporal_weight",
                 fmt::format("{} is outside [0, 100]", o.temporal_weight));
    check_option(std::isfinite(o.pixels_per_frame) && o.pixels_per_frame >= 0 && o.pixels_per_frame <= 1000,
                 "pixels_per_frame", fmt::format("{} is outside [0, 1000]", o.pixels_per_frame));
    check_option(std::isfinite(o.texel) && o.texel >= 0, "texel", fmt::format("{} must be at least 0", o.texel));
    check_option(o.pca_dimensions >= 1 && o.pca_dimensions <= 256, "pca_dimensions",
                 fmt::format("{} is outside [1, 256]", o.pca_dimensions));
    check_option(o.candidates >= 1 && o.candidates <= 16, "candidates", fmt::format("{} is outside [1, 16]", o.candidates));
    for (const cplx& z : field.data())
      if (!std::isfinite(z.real()) || !std::isfinite(z.imag()))
        throw_input_error(b.mesh().source(), "", "the field has a value that is not a finite number");
    TVF_CHECK(field.num_vertices() == b.mesh().num_vertices(), "field of {} vertices on a mesh of {}",
              field.num_vertices(), b.mesh().num_vertices());
    texel_ = o.texel > 0 ? o.texel : mesh.mean_edge_length();

    build_exemplar_pyramid(e, o, exemplars, indices);
    nbs.resize(static_cast<size_t>(o.levels));
    matches.resize(static_cast<size_t>(o.levels));
    built.resize(static_cast<size_t>(o.levels));

    const int nv = mesh.num_vertices();
    vertex_point.resize(static_cast<size_t>(nv));
    vertex_halfedge.resize(static_cast<size_t>(nv));
    for (int v = 0; v < nv; ++v) {
      const int h = mesh.outgoing(v)[0];
      const int face = Mesh::face_of(h);
      SurfacePoint p;
      p.face = face;
      // A hair inside the face, not on its corner: a walk that starts exactly at a vertex
      // and runs exactly along an edge (common on a regularly subdivided mesh under a
      // symmetric field) leaves through the vertex again and again without moving
      // (walk_surface cannot choose the face round the vertex that holds the direction).
      constexpr double kInside = 1e-9;
      p.bary = Vec3::Constant(kInside);
      p.bary[h % 3] = 1.0 - 2 * kInside;
      vertex_point[static_cast<size_t>(v)] = p;
      vertex_halfedge[static_cast<size_t>(v)] = h;
    }

    std::vector<double> speeds;
    const size_t total = field.data().size();
    const size_t step = std::max<size_t>(1, total / 1'000'000);
    for (size_t k = 0; k < total; k += step) speeds.push_back(std::abs(field.data()[k]));
    if (!speeds.empty()) {
      auto mid = speeds.begin() + static_cast<long>(0.9 * static_cast<double>(speeds.size() - 1));
      std::nth_element(speeds.begin(), mid, speeds.end());
      p90 = *mid;
    }
    const TimeSampling& ts = field.time();
    const double frame_dt = ts.frames > 1 ? std::abs(ts.t1 - ts.t0) / (ts.frames - 1) : 1.0;
    // Default motion: one edge of the input mesh per frame, whatever the sample density.
    const double per_frame = o.pixels_per_frame > 0 ? o.pixels_per_frame * texel_ : b.mesh().mean_edge_length();
    time_scale = p90 > 0 && frame_dt > 0 ? per_frame / (p90 * frame_dt) : 0.0;
  }

  static int checked_density(int density) {
    check_option(density >= 0 && density <= 8, "density", fmt::format("{} is outside [0, 8] (0: automatic)", density));
    return density;
  }

  // The field at time tt at the samples: at the input's vertices, or (subdivided) as
  // resample_field does for one time: FieldSampler in the original face, projected onto
  // the sample's tangent plane, its length kept.
  std::vector<cplx> vertex_values(double tt) const {
    const FieldSampler sampler(input, field);
    std::vector<cplx> values(static_cast<size_t>(bundle.mesh().num_vertices()));
    if (!samples.subdivision) {
      for (size_t v = 0; v < values.size(); ++v) values[v] = sampler.at_vertex(static_cast<int>(v), tt);
      return values;
    }
    const FaceSubdivision& sub = *samples.subdivision;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, values.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t v = r.begin(); v < r.end(); ++v) {
        const Vec3 w = sampler.world(SurfacePoint{sub.face[v], sub.bary[v]}, tt);
        cplx z = bundle.world_to_vertex(static_cast<int>(v), w);
        const double m = std::abs(z);
        if (m > 0) z *= w.norm() / m;
        values[v] = z;
      }
    });
    return values;
  }

  // Neighbourhoods of one level: a walked grid around every vertex. A grid is walked again
  // only where the field's direction turned by more than kRewalk radians since it was last
  // walked (its corner taps then move by less than R·√2·kRewalk ≈ 0.1 spacing at R = 3):
  // walking is most of a surface frame's cost, and most directions change slowly.
  static constexpr double kRewalk = 0.025;
  void build_neighbourhoods(int level, const std::vector<cplx>& values) {
    const Mesh& mesh = bundle.mesh();
    const int w = o.neighbourhood, R = w / 2;
    const double spacing = texel_ * std::ldexp(1.0, level);
    const double floor = 1e-12 * std::max(p90, 1e-300);
    Neighbourhoods& nb = nbs[static_cast<size_t>(level)];
    const int nv = mesh.num_vertices();
    std::vector<cplx>& dirs = built[static_cast<size_t>(level)];
    if (nb.size != w || dirs.size() != static_cast<size_t>(nv)) {
      nb.size = w;
      nb.taps.assign(static_cast<size_t>(nv) * static_cast<size_t>(w * w), Tap{});
      dirs.assign(static_cast<size_t>(nv), cplx(0, 0));  // not a unit vector: walked on first use
    }
    tbb::parallel_for(tbb::blocked_range<int>(0, nv, 64), [&](const tbb::blocked_range<int>& range) {
      std::vector<SurfacePoint> column_point(static_cast<size_t>(w));
      std::vector<cplx> column_frame(static_cast<size_t>(w));  // start-frame vectors → that point's face frame
      for (int v = range.begin(); v < range.end(); ++v) {
        const SurfacePoint& start = vertex_point[static_cast<size_t>(v)];
        const cplx z = values[static_cast<size_t>(v)] * bundle.corner_to_face(vertex_halfedge[static_cast<size_t>(v)]);
        const cplx u = std::abs(z) > floor ? z / std::abs(z) : cplx(1, 0);
        if (std::abs(u - dirs[static_cast<size_t>(v)]) < kRewalk) continue;
        dirs[static_cast<size_t>(v)] = u;
        const cplx du = u * spacing;
        const cplx dv = cplx(0, -1) * u * spacing;  // clockwise: the exemplar's y
        // Along the row through the centre, both ways.
        column_point[static_cast<size_t>(R)] = start;
        column_frame[static_cast<size_t>(R)] = 1.0;
        for (int sgn : {1, -1})
          for (int c = 1; c <= R; ++c) {
            const size_t prev = static_cast<size_t>(R + sgn * (c - 1)), cur = static_cast<size_t>(R + sgn * c);
            const SurfaceWalk walk = walk_surface(bundle, column_point[prev], double(sgn) * du * column_frame[prev]);
            column_point[cur] = walk.end;
            column_frame[cur] = column_frame[prev] * walk.transport;
          }
        Tap* taps = nb.taps.data() + static_cast<size_t>(v) * static_cast<size_t>(w * w);
        for (int c = 0; c < w; ++c) {
          point_tap(mesh, column_point[static_cast<size_t>(c)], taps[R * w + c]);
          for (int sgn : {1, -1}) {
            SurfacePoint p = column_point[static_cast<size_t>(c)];
            cplx frame = column_frame[static_cast<size_t>(c)];
            for (int r = 1; r <= R; ++r) {
              const SurfaceWalk walk = walk_surface(bundle, p, double(sgn) * dv * frame);
              p = walk.end;
              frame *= walk.transport;
              point_tap(mesh, p, taps[(R + sgn * r) * w + c]);
            }
          }
        }
      }
    });
  }

  // The values carried along the field over dt (backward walk, midpoint rule).
  std::vector<float> advect(const std::vector<float>& g, const std::vector<cplx>& values, double dt) const {
    const Mesh& mesh = bundle.mesh();
    std::vector<float> out(g.size());
    const double s = time_scale * dt;
    tbb::parallel_for(tbb::blocked_range<int>(0, mesh.num_vertices(), 256), [&](const tbb::blocked_range<int>& range) {
      for (int v = range.begin(); v < range.end(); ++v) {
        const SurfacePoint& start = vertex_point[static_cast<size_t>(v)];
        const cplx z = values[static_cast<size_t>(v)] * bundle.corner_to_face(vertex_halfedge[static_cast<size_t>(v)]);
        const SurfaceWalk half = walk_surface(bundle, start, -0.5 * s * z);
        const cplx zm = interpolate_in_face(bundle, values, half.end) * std::conj(half.transport);
        const SurfaceWalk walk = walk_surface(bundle, start, -s * zm);
        const Face& f = mesh.face(walk.end.face);
        for (int c = 0; c < C; ++c) {
          double a = 0;
          for (size_t k = 0; k < 3; ++k)
            a += walk.end.bary[static_cast<Eigen::Index>(k)] * g[static_cast<size_t>(f[k]) * static_cast<size_t>(C) + static_cast<size_t>(c)];
          out[static_cast<size_t>(v) * static_cast<size_t>(C) + static_cast<size_t>(c)] = static_cast<float>(a);
        }
      }
    });
    return out;
  }

  const SynthesisFrameReport& advance(double tt) {
    const auto start = std::chrono::steady_clock::now();
    const std::vector<cplx> values = vertex_values(tt);
    OptimizeOptions opt;
    OptimizeReport last;
    if (!started) {
      random_exemplar_pixels(exemplars.back(), bundle.mesh().num_vertices(), o.seed, x);
      opt.iterations = o.iterations_first;
      for (int l = o.levels - 1; l >= 0; --l) {
        build_neighbourhoods(l, values);
        last = optimize_texture(nbs[static_cast<size_t>(l)], *indices[static_cast<size_t>(l)], x, {}, opt, &matches[static_cast<size_t>(l)]);
      }
      report.levels = o.levels;
      started = true;
    } else {
      target = advect(x, values, tt - t);
      x = target;
      opt.iterations = o.iterations;
      opt.temporal_weight = o.temporal_weight;
      for (int l = o.frame_levels - 1; l >= 0; --l) {
        build_neighbourhoods(l, values);
        last = optimize_texture(nbs[static_cast<size_t>(l)], *indices[static_cast<size_t>(l)], x, target, opt, &matches[static_cast<size_t>(l)]);
      }
      report.levels = o.frame_levels;
    }
    t = tt;
    report.patch_distance = last.patch_distance;
    report.uncovered = last.uncovered;
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return report;
  }
};

SurfaceSynthesizer::SurfaceSynthesizer(const TangentBundle& bundle, const Field& field, const Exemplar& exemplar,
                                       const SynthesisOptions& options)
    : impl_(std::make_unique<Impl>(bundle, field, exemplar, options)) {}
SurfaceSynthesizer::~SurfaceSynthesizer() = default;
int SurfaceSynthesizer::channels() const { return impl_->C; }
double SurfaceSynthesizer::texel() const { return impl_->texel_; }
int SurfaceSynthesizer::density() const { return impl_->samples.density; }
const TangentBundle& SurfaceSynthesizer::sample_bundle() const { return impl_->bundle; }
const Mesh& SurfaceSynthesizer::sample_mesh() const { return impl_->bundle.mesh(); }
const SynthesisFrameReport& SurfaceSynthesizer::advance(double t) { return impl_->advance(t); }
double SurfaceSynthesizer::time() const { return impl_->t; }
const std::vector<float>& SurfaceSynthesizer::values() const { return impl_->x; }
const Neighbourhoods& SurfaceSynthesizer::neighbourhoods() const { return impl_->nbs[0]; }

std::vector<Vec3> SurfaceSynthesizer::colours() const {
  const int C = impl_->C;
  const auto& x = impl_->x;
  std::vector<Vec3> out(x.size() / static_cast<size_t>(C));
  for (size_t v = 0; v < out.size(); ++v) {
    if (C == 1)
      out[v] = Vec3::Constant(x[v]);
    else
      out[v] = Vec3(x[3 * v], x[3 * v + 1], x[3 * v + 2]);
    out[v] = out[v].cwiseMax(0.0).cwiseMin(1.0);
  }
  return out;
}

SynthesisAnimationReport write_surface_synthesis(const TangentBundle& bundle, const Field& field,
                                                 const Exemplar& exemplar,
                                                 const SurfaceSynthesisAnimationOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const bool pictures = !options.frames_dir.empty() || !options.video.empty();
  if (!pictures && options.meshes_dir.empty())
    throw Error("surface texture synthesis: give a meshes folder (and, with a renderer, frames or a video) to write");
  if (pictures && !options.renderer)
    throw Error("surface texture synthesis: pictures of a surface need a mesh renderer; write per-frame meshes "
                "(PLY with vertex colours) instead");
  if (options.frames < 0 || options.frames > 100000)
    throw Error(fmt::format("frames {}: must be in [1, 100000] (or 0: the field's frames)", options.frames));
  if (options.terrain && exemplar.channels != 1) throw Error("terrain needs a 1-channel (height) exemplar");
  if (!options.terrain && options.mesh_format != "ply")
    throw Error(fmt::format("mesh format '{}': coloured surfaces are written as PLY only", options.mesh_format));
  if (!std::isfinite(options.height_scale) || options.height_scale < 0 || options.height_scale > 1)
    throw Error(fmt::format("synthesis option height_scale: {} is outside [0, 1]", options.height_scale));
  SurfaceSynthesizer synth(bundle, field, exemplar, options.synthesis);
  const TangentBundle& samples = synth.sample_bundle();
  const Mesh& mesh = samples.mesh();
  const int frames = options.frames > 0 ? options.frames : field.frames();
  const TimeSampling& ts = field.time();

  std::unique_ptr<TerrainMeshWriter> terrain_meshes;
  std::unique_ptr<OutputStage> colour_meshes;
  if (!options.meshes_dir.empty()) {
    if (options.terrain) {
      TerrainMeshOptions mo;
      mo.format = options.mesh_format;
      mo.height_scale = options.height_scale;
      terrain_meshes = std::make_unique<TerrainMeshWriter>(options.meshes_dir, mesh, mo);
    } else {
      colour_meshes = std::make_unique<OutputStage>(options.meshes_dir);
    }
  }
  std::unique_ptr<FrameOutput> out;
  SynthesisAnimationReport report;
  double later = 0, distance = 0;
  const double amount = options.height_scale * mesh.diameter();
  for (int k = 0; k < frames; ++k) {
    const double t = frames > 1 ? ts.t0 + (ts.t1 - ts.t0) * k / (frames - 1) : ts.t0;
    const SynthesisFrameReport& fr = synth.advance(t);
    if (k == 0) report.first_frame_seconds = fr.seconds; else later += fr.seconds;
    distance += fr.patch_distance;
    std::vector<Vec3> colours = synth.colours();
    if (options.terrain)
      for (auto& c : colours) c = terrain_colour(c.x());
    if (terrain_meshes) terrain_meshes->add_surface(samples, synth.values());
    if (colour_meshes) write_colored_ply(colour_meshes->file(fmt::format("frame_{:05d}.ply", k)).string(), mesh, colours);
    if (pictures) {
      const Image image = options.terrain ? options.renderer(displace_along_normals(samples, synth.values(), amount), colours)
                                          : options.renderer(mesh, colours);
      if (!out) {
        out = std::make_unique<FrameOutput>(options.frames_dir, options.video, image.width, image.height, options.fps);
        report.width = image.width;
        report.height = image.height;
      }
      out->add(image);
    }
    if (options.progress) options.progress(k + 1, frames);
  }
  if (out) report.files = out->finish();
  if (terrain_meshes) terrain_meshes->finish();
  if (colour_meshes) colour_meshes->commit();
  if (!options.meshes_dir.empty()) report.files.push_back(options.meshes_dir);
  report.frames = frames;
  report.mean_frame_seconds = frames > 1 ? later / (frames - 1) : report.first_frame_seconds;
  report.mean_patch_distance = distance / frames;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace tvf
