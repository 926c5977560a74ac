#include "tvf/render/mesh_renderer.h"

#include "tvf/core/error.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GLES3/gl3.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <string>

namespace tvf {

// --- Camera -----------------------------------------------------------------------------

Camera Camera::framing(const Vec3& lo, const Vec3& hi, const Vec3& direction, const Vec3& up, double aspect,
                       double fov_y, double margin) {
  if (!(direction.norm() > 0) || !direction.allFinite())
    throw Error("camera: the viewing direction must be a non-zero vector");
  if (!(aspect > 0) || !(fov_y > 0 && fov_y < 180) || !(margin > 0))
    throw Error("camera: aspect, field of view (0–180°) and margin must be positive");
  Camera c;
  c.fov_y = fov_y;
  c.target = 0.5 * (lo + hi);
  const double radius = std::max(0.5 * (hi - lo).norm(), 1e-12);
  const Vec3 d = direction.normalized();
  // The smaller half-angle of the view (vertical, or horizontal when the picture is tall).
  const double half_y = 0.5 * fov_y * kPi / 180.0;
  const double half_x = std::atan(std::tan(half_y) * aspect);
  const double half = std::min(half_x, half_y);
  c.eye = c.target + d * (margin * radius / std::sin(half));
  Vec3 u = up - up.dot(d) * d;
  if (u.norm() < 1e-6 * std::max(1.0, up.norm())) {
    // up parallel to the viewing direction: take the axis least aligned with it
    Vec3 axis = Vec3::UnitZ();
    if (std::abs(d.z()) > 0.9) axis = Vec3::UnitY();
    u = axis - axis.dot(d) * d;
  }
  c.up = u.normalized();
  return c;
}

Camera Camera::framing(std::span<const Vec3> points, const Vec3& direction, const Vec3& up, double aspect,
                       double fov_y, double margin) {
  if (points.empty()) throw Error("camera: nothing to frame");
  Vec3 lo = points[0], hi = points[0];
  for (const Vec3& p : points) {
    if (!p.allFinite()) throw Error("camera: a point to frame is not finite");
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  Camera c = framing(lo, hi, direction, up, aspect, fov_y, margin);
  // Axes of the picture: s right, u up, d towards the eye.
  const Vec3 d = (c.eye - c.target).normalized();
  const Vec3 s = c.up.cross(d).normalized();
  const Vec3 u = d.cross(s);
  const double ty = std::tan(0.5 * fov_y * kPi / 180.0), tx = ty * aspect;
  double dist = 0;
  for (const Vec3& p : points) {
    const Vec3 q = p - c.target;
    // The point is inside when its lateral offsets, times margin, fit the view at its depth.
    dist = std::max({dist, q.dot(d) + margin * std::abs(q.dot(s)) / tx, q.dot(d) + margin * std::abs(q.dot(u)) / ty});
  }
  const double radius = 0.5 * (hi - lo).norm();
  dist = std::max(dist, (hi - lo).norm() * 1e-6 + 1e-12);
  // Keep the eye outside the points' bounding sphere.
  c.eye = c.target + d * std::max(dist, 1.05 * radius);
  return c;
}

Eigen::Matrix4d Camera::view() const {
  const Vec3 f = (target - eye).normalized();
  const Vec3 s = f.cross(up).normalized();
  const Vec3 u = s.cross(f);
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(eye);
  m(1, 3) = -u.dot(eye);
  m(2, 3) = f.dot(eye);
  return m;
}

Eigen::Matrix4d Camera::projection(double aspect, double near, double far) const {
  const double t = 1.0 / std::tan(0.5 * fov_y * kPi / 180.0);
  Eigen::Matrix4d p = Eigen::Matrix4d::Zero();
  p(0, 0) = t / aspect;
  p(1, 1) = t;
  p(2, 2) = (far + near) / (near - far);
  p(2, 3) = 2 * far * near / (near - far);
  p(3, 2) = -1;
  return p;
}

Vec3 Camera::project(const Vec3& x, int width, int height) const {
  const double aspect = static_cast<double>(width) / height;
  const Eigen::Vector4d e = view() * Eigen::Vector4d(x.x(), x.y(), x.z(), 1.0);
  const Eigen::Vector4d c = projection(aspect, 1.0, 2.0) * e;  // near/far do not move x, y
  return {(c.x() / c.w() + 1) * 0.5 * width, (1 - c.y() / c.w()) * 0.5 * height, -e.z()};
}

// --- OpenGL -----------------------------------------------------------------------------

namespace {

// One EGL display for the process, initialised by the first renderer and kept: terminating
// it would unload Mesa's driver, whose few process-lifetime allocations would then show up
// in leak checks as unnamed frames (tests/lsan.supp names the driver instead), and a later
// renderer would pay for loading it again.
std::mutex display_mutex;
EGLDisplay shared_display = EGL_NO_DISPLAY;

EGLDisplay acquire_display() {
  std::lock_guard lock(display_mutex);
  if (shared_display == EGL_NO_DISPLAY) {
    const char* ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (!ext || !std::strstr(ext, "EGL_MESA_platform_surfaceless"))
      throw Error("offscreen rendering: EGL has no surfaceless platform (install Mesa's EGL: Debian packages "
                  "libegl-mesa0 and libgl1-mesa-dri)");
    auto get_display =
        reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (!get_display) throw Error("offscreen rendering: EGL lacks eglGetPlatformDisplayEXT");
    EGLDisplay d = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    EGLint major = 0, minor = 0;
    if (d == EGL_NO_DISPLAY || !eglInitialize(d, &major, &minor))
      throw Error(fmt::format("offscreen rendering: cannot initialise EGL's surfaceless display (EGL error 0x{:x})",
                              eglGetError()));
    shared_display = d;
  }
  return shared_display;
}

const char* kMeshVertex = R"(#version 300 es
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec4 color;
uniform mat4 view;
uniform mat4 projection;
out vec3 eye_position;
out vec3 eye_normal;
out vec3 vertex_color;
void main() {
  vec4 e = view * vec4(position, 1.0);
  eye_position = e.xyz;
  eye_normal = mat3(view) * normal;
  vertex_color = color.rgb;
  gl_Position = projection * e;
}
)";

const char* kMeshFragment = R"(#version 300 es
precision highp float;
in vec3 eye_position;
in vec3 eye_normal;
in vec3 vertex_color;
uniform float ambient;
uniform int lighting;
uniform int two_sided;
out vec4 out_color;
void main() {
  vec3 c = vertex_color;
  if (lighting != 0) {
    float len = length(eye_normal);
    float d = len > 0.0 ? dot(eye_normal / len, normalize(-eye_position)) : 1.0;
    d = two_sided != 0 ? abs(d) : max(d, 0.0);
    c *= ambient + (1.0 - ambient) * d;
  }
  out_color = vec4(c, 1.0);
}
)";

// Lines and markers arrive in clip space (expanded into quads on the CPU); markers carry
// (u, v) in [-1, 1] and the width of their outline in those units.
const char* kOverlayVertex = R"(#version 300 es
layout(location = 0) in vec4 clip;
layout(location = 1) in vec4 color;
layout(location = 2) in vec3 disc;
out vec4 overlay_color;
out vec3 disc_uv;
void main() {
  overlay_color = color;
  disc_uv = disc;
  gl_Position = clip;
}
)";

const char* kOverlayFragment = R"(#version 300 es
precision highp float;
in vec4 overlay_color;
in vec3 disc_uv;
out vec4 out_color;
void main() {
  vec3 c = overlay_color.rgb;
  if (disc_uv.z > 0.0) {
    float r = length(disc_uv.xy);
    if (r > 1.0) discard;
    if (r > 1.0 - disc_uv.z) c = vec3(0.0);
  }
  out_color = vec4(c, 1.0);
}
)";

GLuint compile(GLenum kind, const char* source) {
  const GLuint s = glCreateShader(kind);
  glShaderSource(s, 1, &source, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048] = {};
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    glDeleteShader(s);
    throw Error(fmt::format("offscreen rendering: a shader does not compile: {}", log));
  }
  return s;
}

GLuint link(const char* vertex, const char* fragment) {
  const GLuint vs = compile(GL_VERTEX_SHADER, vertex);
  const GLuint fs = compile(GL_FRAGMENT_SHADER, fragment);
  const GLuint p = glCreateProgram();
  glAttachShader(p, vs);
  glAttachShader(p, fs);
  glLinkProgram(p);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[2048] = {};
    glGetProgramInfoLog(p, sizeof log, nullptr, log);
    glDeleteProgram(p);
    throw Error(fmt::format("offscreen rendering: shaders do not link: {}", log));
  }
  return p;
}

struct OverlayVertex {
  float clip[4];
  float color[4];
  float disc[3];
};

void unpack(std::uint32_t c, float out[4]) {
  out[0] = static_cast<float>((c >> 16) & 0xFFu) / 255.0f;
  out[1] = static_cast<float>((c >> 8) & 0xFFu) / 255.0f;
  out[2] = static_cast<float>(c & 0xFFu) / 255.0f;
  out[3] = 1.0f;
}

}  // namespace

struct MeshRenderer::Impl {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  std::mutex mutex;
  GLuint mesh_program = 0, overlay_program = 0;
  GLuint mesh_vao = 0, overlay_vao = 0;
  GLuint position_buffer = 0, normal_buffer = 0, color_buffer = 0, index_buffer = 0, overlay_buffer = 0;
  GLsizei index_count = 0;
  int vertices = 0;
  Vec3 center{0, 0, 0};  // bounding sphere of the mesh
  double radius = 0;
  std::string name;
  GLint max_samples = 0, max_size = 0;
  // Framebuffers of the last size used.
  int fb_width = 0, fb_height = 0, fb_samples = -1;
  GLuint ms_fbo = 0, ms_color = 0, ms_depth = 0, resolve_fbo = 0, resolve_color = 0;

  // Makes the context current for the scope.
  struct Current {
    Impl& impl;
    explicit Current(Impl& i) : impl(i) {
      if (!eglMakeCurrent(impl.display, EGL_NO_SURFACE, EGL_NO_SURFACE, impl.context))
        throw Error(fmt::format("offscreen rendering: cannot make the OpenGL context current (EGL error 0x{:x})",
                                eglGetError()));
    }
    // Also drops EGL's state for this thread: renders run on whichever TBB worker the
    // frame pipeline picks, and a worker that still held Mesa's per-thread state when the
    // process exited freed it twice (its thread-exit destructor raced Mesa's teardown).
    ~Current() {
      eglMakeCurrent(impl.display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
      eglReleaseThread();
    }
  };

  void free_framebuffers() {
    glDeleteFramebuffers(1, &ms_fbo);
    glDeleteFramebuffers(1, &resolve_fbo);
    glDeleteRenderbuffers(1, &ms_color);
    glDeleteRenderbuffers(1, &ms_depth);
    glDeleteRenderbuffers(1, &resolve_color);
    ms_fbo = resolve_fbo = ms_color = ms_depth = resolve_color = 0;
    fb_width = fb_height = 0;
    fb_samples = -1;
  }

  void framebuffers(int w, int h, int samples) {
    if (w == fb_width && h == fb_height && samples == fb_samples) return;
    free_framebuffers();
    glGenFramebuffers(1, &ms_fbo);
    glGenRenderbuffers(1, &ms_color);
    glGenRenderbuffers(1, &ms_depth);
    glBindRenderbuffer(GL_RENDERBUFFER, ms_color);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA8, w, h);
    glBindRenderbuffer(GL_RENDERBUFFER, ms_depth);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH_COMPONENT24, w, h);
    glBindFramebuffer(GL_FRAMEBUFFER, ms_fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, ms_color);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, ms_depth);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw Error(fmt::format("offscreen rendering: cannot make a {}×{} framebuffer", w, h));
    glGenFramebuffers(1, &resolve_fbo);
    glGenRenderbuffers(1, &resolve_color);
    glBindRenderbuffer(GL_RENDERBUFFER, resolve_color);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, w, h);
    glBindFramebuffer(GL_FRAMEBUFFER, resolve_fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, resolve_color);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw Error(fmt::format("offscreen rendering: cannot make a {}×{} framebuffer", w, h));
    fb_width = w;
    fb_height = h;
    fb_samples = samples;
  }
};

MeshRenderer::MeshRenderer() : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.display = acquire_display();
  try {
    if (!eglBindAPI(EGL_OPENGL_ES_API)) throw Error("offscreen rendering: EGL cannot bind OpenGL ES");
    const EGLint config_attributes[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_ES3_BIT, EGL_NONE};
    EGLConfig config = nullptr;
    EGLint configs = 0;
    eglChooseConfig(m.display, config_attributes, &config, 1, &configs);
    const EGLint context_attributes[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 0, EGL_NONE};
    m.context = eglCreateContext(m.display, configs > 0 ? config : EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT,
                                 context_attributes);
    if (m.context == EGL_NO_CONTEXT)
      throw Error(fmt::format("offscreen rendering: cannot create an OpenGL ES 3 context (EGL error 0x{:x})",
                              eglGetError()));
    Impl::Current current(m);
    m.name = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    glGetIntegerv(GL_MAX_SAMPLES, &m.max_samples);
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &m.max_size);
    m.mesh_program = link(kMeshVertex, kMeshFragment);
    m.overlay_program = link(kOverlayVertex, kOverlayFragment);
    glGenVertexArrays(1, &m.mesh_vao);
    glGenVertexArrays(1, &m.overlay_vao);
    GLuint buffers[5];
    glGenBuffers(5, buffers);
    m.position_buffer = buffers[0];
    m.normal_buffer = buffers[1];
    m.color_buffer = buffers[2];
    m.index_buffer = buffers[3];
    m.overlay_buffer = buffers[4];
    glBindVertexArray(m.mesh_vao);
    glBindBuffer(GL_ARRAY_BUFFER, m.position_buffer);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    glEnableVertexAttribArray(0);
    glBindBuffer(GL_ARRAY_BUFFER, m.normal_buffer);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    glEnableVertexAttribArray(1);
    glBindBuffer(GL_ARRAY_BUFFER, m.color_buffer);
    glVertexAttribPointer(2, 4, GL_UNSIGNED_BYTE, GL_TRUE, 0, nullptr);
    glEnableVertexAttribArray(2);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, m.index_buffer);
    glBindVertexArray(m.overlay_vao);
    glBindBuffer(GL_ARRAY_BUFFER, m.overlay_buffer);
    glVertexAttribPointer(0, 4, GL_FLOAT, GL_FALSE, sizeof(OverlayVertex), nullptr);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, sizeof(OverlayVertex),
                          reinterpret_cast<const void*>(offsetof(OverlayVertex, color)));
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(2, 3, GL_FLOAT, GL_FALSE, sizeof(OverlayVertex),
                          reinterpret_cast<const void*>(offsetof(OverlayVertex, disc)));
    glEnableVertexAttribArray(2);
    glBindVertexArray(0);
  } catch (...) {
    if (m.context != EGL_NO_CONTEXT) eglDestroyContext(m.display, m.context);
    throw;
  }
}

MeshRenderer::~MeshRenderer() {
  Impl& m = *impl_;
  if (eglMakeCurrent(m.display, EGL_NO_SURFACE, EGL_NO_SURFACE, m.context)) {
    m.free_framebuffers();
    const GLuint buffers[5] = {m.position_buffer, m.normal_buffer, m.color_buffer, m.index_buffer, m.overlay_buffer};
    glDeleteBuffers(5, buffers);
    glDeleteVertexArrays(1, &m.mesh_vao);
    glDeleteVertexArrays(1, &m.overlay_vao);
    glDeleteProgram(m.mesh_program);
    glDeleteProgram(m.overlay_program);
    eglMakeCurrent(m.display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  }
  eglDestroyContext(m.display, m.context);
  eglReleaseThread();
}

std::string MeshRenderer::renderer_name() const { return impl_->name; }
int MeshRenderer::num_vertices() const { return impl_->vertices; }

void MeshRenderer::set_mesh(std::span<const Vec3> positions, std::span<const Face> faces) {
  const size_t nv = positions.size();
  if (nv > 0x7FFFFFFF) throw Error("mesh renderer: too many vertices");
  std::vector<float> pos(3 * nv), nrm(3 * nv, 0.0f);
  std::vector<Vec3> normals(nv, Vec3::Zero());
  for (size_t v = 0; v < nv; ++v) {
    if (!positions[v].allFinite()) throw Error(fmt::format("mesh renderer: vertex {} is not a finite point", v));
    for (int c = 0; c < 3; ++c) pos[3 * v + static_cast<size_t>(c)] = static_cast<float>(positions[v][c]);
  }
  std::vector<std::uint32_t> index(3 * faces.size());
  for (size_t f = 0; f < faces.size(); ++f) {
    for (size_t c = 0; c < 3; ++c) {
      const int v = faces[f][c];
      if (v < 0 || static_cast<size_t>(v) >= nv)
        throw Error(fmt::format("mesh renderer: face {} names vertex {} of {}", f, v, nv));
      index[3 * f + c] = static_cast<std::uint32_t>(v);
    }
    const Vec3& a = positions[static_cast<size_t>(faces[f][0])];
    const Vec3 n = (positions[static_cast<size_t>(faces[f][1])] - a).cross(positions[static_cast<size_t>(faces[f][2])] - a);
    for (size_t c = 0; c < 3; ++c) normals[static_cast<size_t>(faces[f][c])] += n;  // area weighted
  }
  for (size_t v = 0; v < nv; ++v) {
    const double len = normals[v].norm();
    if (len > 0)
      for (int c = 0; c < 3; ++c) nrm[3 * v + static_cast<size_t>(c)] = static_cast<float>(normals[v][c] / len);
  }
  Impl& m = *impl_;
  std::lock_guard lock(m.mutex);
  Impl::Current current(m);
  glBindBuffer(GL_ARRAY_BUFFER, m.position_buffer);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(pos.size() * sizeof(float)), pos.data(), GL_STATIC_DRAW);
  glBindBuffer(GL_ARRAY_BUFFER, m.normal_buffer);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(nrm.size() * sizeof(float)), nrm.data(), GL_STATIC_DRAW);
  const std::vector<std::uint32_t> gray_colors(nv, 0xFF808080u);
  glBindBuffer(GL_ARRAY_BUFFER, m.color_buffer);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(nv * 4), gray_colors.data(), GL_DYNAMIC_DRAW);
  glBindVertexArray(m.mesh_vao);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, m.index_buffer);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(index.size() * sizeof(std::uint32_t)), index.data(),
               GL_STATIC_DRAW);
  glBindVertexArray(0);
  m.index_count = static_cast<GLsizei>(index.size());
  m.vertices = static_cast<int>(nv);
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::max()), hi = -lo;
  for (const Vec3& p : positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  m.center = nv > 0 ? Vec3(0.5 * (lo + hi)) : Vec3::Zero();
  m.radius = nv > 0 ? 0.5 * (hi - lo).norm() : 0.0;
}

void MeshRenderer::set_colors(std::span<const std::uint32_t> colors) {
  Impl& m = *impl_;
  if (colors.size() != static_cast<size_t>(m.vertices))
    throw Error(fmt::format("mesh renderer: {} colours for {} vertices", colors.size(), m.vertices));
  // 0x00RRGGBB → bytes R, G, B, A in memory.
  std::vector<std::uint8_t> bytes(4 * colors.size());
  for (size_t v = 0; v < colors.size(); ++v) {
    bytes[4 * v] = static_cast<std::uint8_t>(colors[v] >> 16);
    bytes[4 * v + 1] = static_cast<std::uint8_t>(colors[v] >> 8);
    bytes[4 * v + 2] = static_cast<std::uint8_t>(colors[v]);
    bytes[4 * v + 3] = 255;
  }
  std::lock_guard lock(m.mutex);
  Impl::Current current(m);
  glBindBuffer(GL_ARRAY_BUFFER, m.color_buffer);
  glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(bytes.size()), bytes.data());
}

Image MeshRenderer::render(const Camera& camera, const RenderOptions& o, std::span<const RenderLine> lines,
                           std::span<const RenderMarker> markers) {
  Impl& m = *impl_;
  if (o.width < 1 || o.height < 1 || o.width > m.max_size || o.height > m.max_size)
    throw Error(fmt::format("mesh renderer: a picture of {}×{} pixels is outside 1–{} on each side", o.width,
                            o.height, m.max_size));
  if (!(o.ambient >= 0 && o.ambient <= 1)) throw Error("mesh renderer: ambient must be in [0, 1]");
  if (!camera.eye.allFinite() || !camera.target.allFinite() || (camera.eye - camera.target).norm() == 0 ||
      !(camera.fov_y > 0 && camera.fov_y < 180))
    throw Error("mesh renderer: the camera needs a finite eye apart from its target and a field of view in (0, 180)°");
  const int samples = o.samples <= 1 ? 0 : std::min(o.samples, static_cast<int>(m.max_samples));
  const double aspect = static_cast<double>(o.width) / o.height;

  // Near and far planes around what is drawn.
  const Eigen::Matrix4d view = camera.view();
  const double dist = (camera.eye - camera.target).norm();
  double zmin = dist, zmax = dist;
  {
    // The overlays and the mesh's vertices bound the depth range when known.
    auto extend = [&](const Vec3& x) {
      const double z = -(view * Eigen::Vector4d(x.x(), x.y(), x.z(), 1.0)).z();
      zmin = std::min(zmin, z);
      zmax = std::max(zmax, z);
    };
    for (const auto& line : lines)
      for (const auto& p : line.points) extend(p);
    for (const auto& mk : markers) extend(mk.position);
    if (m.vertices > 0) {  // the mesh's bounding sphere
      const double zc = -(view * Eigen::Vector4d(m.center.x(), m.center.y(), m.center.z(), 1.0)).z();
      zmin = std::min(zmin, zc - m.radius);
      zmax = std::max(zmax, zc + m.radius);
    }
  }
  const double near = std::max(zmin * 0.9, 1e-3 * dist);
  const double far = std::max(zmax * 1.1, near * 1.01);
  const Eigen::Matrix4d proj = camera.projection(aspect, near, far);

  // Overlay quads in clip space.
  std::vector<OverlayVertex> quads;
  const double bias = 2e-3;  // NDC depth towards the camera
  // Overlays come `pixels` (at their depth) towards the camera, so that a surface tilted
  // away under a marker or a wide line does not cut it, plus a small depth bias.
  const double pixel_at_unit_depth = 2 * std::tan(0.5 * camera.fov_y * kPi / 180.0) / o.height;
  auto clip_of = [&](const Vec3& x, double lift = 1.0, double pixels = 0.0) {
    Eigen::Vector4d e = view * Eigen::Vector4d(x.x(), x.y(), x.z(), 1.0);
    // Along the ray to the eye (the eye space's origin): the point stays where it is seen.
    const double dist_e = e.head<3>().norm();
    if (dist_e > 0) e.head<3>() *= std::max(0.1, 1.0 - pixels * pixel_at_unit_depth * std::max(-e.z(), 0.0) / dist_e);
    Eigen::Vector4d c = proj * e;
    c.z() -= lift * bias * c.w();
    return c;
  };
  auto push_quad = [&](const Eigen::Vector4d (&c)[4], const float color[4], const float (&disc)[4][3]) {
    const int order[6] = {0, 1, 2, 2, 1, 3};
    for (int k : order) {
      OverlayVertex v{};
      for (int i = 0; i < 4; ++i) v.clip[i] = static_cast<float>(c[k][i]);
      std::memcpy(v.color, color, sizeof v.color);
      std::memcpy(v.disc, disc[k], sizeof v.disc);
      quads.push_back(v);
    }
  };
  const float no_disc[4][3] = {};
  // A disc (no outline: its fraction of the radius just above 0, the shader's mark of a disc).
  const float round[4][3] = {{-1, -1, 1e-6f}, {-1, 1, 1e-6f}, {1, -1, 1e-6f}, {1, 1, 1e-6f}};
  // A line: a quad per segment and a disc of its width at every point, so that its joints and
  // ends are round (square caps stuck out of a bent line's outer corners: the casing's, 2.2
  // times as wide, as black spikes beside a sketch's corners).
  auto add_line = [&](const RenderLine& line, double width, std::uint32_t color, double lift) {
    float col[4];
    unpack(color, col);
    const double shift = 2.2 * line.width;  // the same for the casing and the line
    const double hw = 0.5 * width;
    auto offset = [&](const Eigen::Vector4d& c, const Vec2& off) {
      Eigen::Vector4d r = c;
      r.x() += off.x() / (0.5 * o.width) * c.w();
      r.y() += off.y() / (0.5 * o.height) * c.w();
      return r;
    };
    std::vector<Eigen::Vector4d> clip(line.points.size());
    for (size_t i = 0; i < line.points.size(); ++i) clip[i] = clip_of(line.points[i], lift, shift);
    for (size_t i = 0; i + 1 < line.points.size(); ++i) {
      const Eigen::Vector4d &a = clip[i], &b = clip[i + 1];
      if (a.w() <= 0 || b.w() <= 0) continue;  // behind the camera
      const Vec2 sa(a.x() / a.w() * 0.5 * o.width, a.y() / a.w() * 0.5 * o.height);
      const Vec2 sb(b.x() / b.w() * 0.5 * o.width, b.y() / b.w() * 0.5 * o.height);
      Vec2 d = sb - sa;
      const double len = d.norm();
      d = len > 1e-9 ? Vec2(d / len) : Vec2(1, 0);
      const Vec2 n(-d.y(), d.x());
      const Eigen::Vector4d q[4] = {offset(a, -hw * n), offset(a, hw * n), offset(b, -hw * n), offset(b, hw * n)};
      push_quad(q, col, no_disc);
    }
    for (const Eigen::Vector4d& c : clip) {
      if (c.w() <= 0) continue;
      const Eigen::Vector4d q[4] = {offset(c, Vec2(-hw, -hw)), offset(c, Vec2(-hw, hw)), offset(c, Vec2(hw, -hw)),
                                    offset(c, Vec2(hw, hw))};
      push_quad(q, col, round);
    }
  };
  for (const auto& line : lines)
    if (line.casing) add_line(line, 2.2 * line.width, 0x000000, 1.0);
  // Casings and underlays are drawn without writing depth, so that the coloured lines over
  // them are not hidden by them (their caps and depths differ a little; an underlay three
  // times as wide is lifted three times as far and hid the line traced over it).
  for (const auto& line : lines)
    if (line.underlay) add_line(line, line.width, line.color, 1.5);
  const size_t casing_vertices = quads.size();
  for (const auto& line : lines)
    if (!line.underlay) add_line(line, line.width, line.color, 1.5);
  for (const auto& mk : markers) {
    Eigen::Vector4d c = clip_of(mk.position, 1.0, 2 * mk.radius);
    if (c.w() <= 0) continue;
    c.z() -= 3 * bias * c.w();  // markers above lines
    float col[4];
    unpack(mk.color, col);
    const double rx = mk.radius / (0.5 * o.width) * c.w(), ry = mk.radius / (0.5 * o.height) * c.w();
    // Its fraction of the radius; above 0 (the shader's mark of a disc) where there is none.
    const float outline = static_cast<float>(std::clamp(mk.outline / std::max(mk.radius, 1e-3), 1e-6, 1.0));
    const Eigen::Vector4d q[4] = {c + Eigen::Vector4d(-rx, -ry, 0, 0), c + Eigen::Vector4d(-rx, ry, 0, 0),
                                  c + Eigen::Vector4d(rx, -ry, 0, 0), c + Eigen::Vector4d(rx, ry, 0, 0)};
    const float disc[4][3] = {{-1, -1, outline}, {-1, 1, outline}, {1, -1, outline}, {1, 1, outline}};
    push_quad(q, col, disc);
  }

  std::lock_guard lock(m.mutex);
  Impl::Current current(m);
  m.framebuffers(o.width, o.height, samples);
  glBindFramebuffer(GL_FRAMEBUFFER, m.ms_fbo);
  glViewport(0, 0, o.width, o.height);
  float bg[4];
  unpack(o.background, bg);
  glClearColor(bg[0], bg[1], bg[2], 1.0f);
  glClearDepthf(1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  glDisable(GL_CULL_FACE);
  if (m.index_count > 0) {
    glUseProgram(m.mesh_program);
    float vm[16], pm[16];
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) {
        vm[4 * c + r] = static_cast<float>(view(r, c));
        pm[4 * c + r] = static_cast<float>(proj(r, c));
      }
    glUniformMatrix4fv(glGetUniformLocation(m.mesh_program, "view"), 1, GL_FALSE, vm);
    glUniformMatrix4fv(glGetUniformLocation(m.mesh_program, "projection"), 1, GL_FALSE, pm);
    glUniform1f(glGetUniformLocation(m.mesh_program, "ambient"), static_cast<float>(o.ambient));
    glUniform1i(glGetUniformLocation(m.mesh_program, "lighting"), o.lighting ? 1 : 0);
    glUniform1i(glGetUniformLocation(m.mesh_program, "two_sided"), o.two_sided ? 1 : 0);
    glBindVertexArray(m.mesh_vao);
    glDrawElements(GL_TRIANGLES, m.index_count, GL_UNSIGNED_INT, nullptr);
  }
  if (!quads.empty()) {
    glUseProgram(m.overlay_program);
    glBindVertexArray(m.overlay_vao);
    glBindBuffer(GL_ARRAY_BUFFER, m.overlay_buffer);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(quads.size() * sizeof(OverlayVertex)), quads.data(),
                 GL_STREAM_DRAW);
    if (casing_vertices > 0) {
      glDepthMask(GL_FALSE);
      glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(casing_vertices));
      glDepthMask(GL_TRUE);
    }
    glDrawArrays(GL_TRIANGLES, static_cast<GLint>(casing_vertices), static_cast<GLsizei>(quads.size() - casing_vertices));
  }
  glBindVertexArray(0);
  // Resolve the samples and read the picture back (bottom row first).
  glBindFramebuffer(GL_READ_FRAMEBUFFER, m.ms_fbo);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, m.resolve_fbo);
  glBlitFramebuffer(0, 0, o.width, o.height, 0, 0, o.width, o.height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, m.resolve_fbo);
  std::vector<std::uint8_t> rgba(static_cast<size_t>(o.width) * static_cast<size_t>(o.height) * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, o.width, o.height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  const GLenum err = glGetError();
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (err != GL_NO_ERROR) throw Error(fmt::format("offscreen rendering: OpenGL error 0x{:x}", err));
  Image img(o.width, o.height);
  for (int y = 0; y < o.height; ++y) {
    const std::uint8_t* row = rgba.data() + static_cast<size_t>(o.height - 1 - y) * static_cast<size_t>(o.width) * 4;
    for (int x = 0; x < o.width; ++x) img.at(x, y) = rgb(row[4 * x], row[4 * x + 1], row[4 * x + 2]);
  }
  return img;
}

}  // namespace tvf
