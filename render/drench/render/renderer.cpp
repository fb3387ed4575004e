#include <drench/render/renderer.hpp>

#define GL_GLEXT_PROTOTYPES
#include <GL/glcorearb.h>

#include <algorithm>
#include <cassert>
#include <cstdio>
#include <string>
#include <vector>

#include <drench/render/render_error.hpp>

namespace drench::render {

namespace {

// Light in eye space: a key light from the upper left behind the viewer and a weak fill from the right, so
// that a sag in the cloth and the curvature of the water read as shape; ambient enough that a side facing
// away from the key (the cloth seen from below) still shows its colour.
constexpr const char* kLighting = R"(
const vec3 kKey = normalize(vec3(-0.4, 0.65, 0.65));
const vec3 kFill = normalize(vec3(0.7, -0.1, 0.7));
vec3 shade(vec3 base, vec3 n, vec3 to_eye, float specular, float shininess, float rim) {
  float key = max(dot(n, kKey), 0.0);
  float fill = max(dot(n, kFill), 0.0);
  float highlight = pow(max(dot(n, normalize(kKey + to_eye)), 0.0), shininess) * specular;
  float edge = pow(1.0 - max(dot(n, to_eye), 0.0), 3.0) * rim;
  return base * (0.38 + 0.55 * key + 0.18 * fill) + vec3(highlight + edge);
}
)";

constexpr const char* kMeshVertex = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
uniform mat4 u_view;
uniform mat4 u_projection;
out vec3 v_normal;
out vec3 v_eye_position;
void main() {
  vec4 eye = u_view * vec4(a_position, 1.0);
  v_eye_position = eye.xyz;
  v_normal = mat3(u_view) * a_normal;  // the view is a rigid motion
  gl_Position = u_projection * eye;
}
)";

constexpr const char* kMeshFragment = R"(
in vec3 v_normal;
in vec3 v_eye_position;
uniform vec3 u_front;
uniform vec3 u_back;
uniform float u_specular;
uniform float u_shininess;
uniform float u_rim;
out vec4 o_colour;
void main() {
  vec3 n = normalize(v_normal);
  vec3 to_eye = normalize(-v_eye_position);
  // Two-sided: the side facing the viewer is lit, whichever way the triangle winds.
  if (dot(n, to_eye) < 0.0) n = -n;
  vec3 base = gl_FrontFacing ? u_front : u_back;
  o_colour = vec4(shade(base, n, to_eye, u_specular, u_shininess, u_rim), 1.0);
}
)";

constexpr const char* kParticleVertex = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in float a_speed;
uniform mat4 u_view;
uniform mat4 u_projection;
uniform float u_radius;
uniform float u_viewport_height;
uniform float u_speed_scale;
uniform vec3 u_slow;
uniform vec3 u_fast;
out vec3 v_colour;
out vec3 v_eye_centre;
void main() {
  vec4 eye = u_view * vec4(a_position, 1.0);
  v_eye_centre = eye.xyz;
  gl_Position = u_projection * eye;
  // The sprite's diameter in pixels: the sphere's 2 r projected at its depth.
  gl_PointSize = max(u_viewport_height * u_projection[1][1] * u_radius / gl_Position.w, 1.0);
  v_colour = mix(u_slow, u_fast, clamp(a_speed / u_speed_scale, 0.0, 1.0));
}
)";

constexpr const char* kParticleFragment = R"(
in vec3 v_colour;
in vec3 v_eye_centre;
uniform mat4 u_projection;
uniform float u_radius;
out vec4 o_colour;
void main() {
  vec2 c = vec2(2.0 * gl_PointCoord.x - 1.0, 1.0 - 2.0 * gl_PointCoord.y);
  float r2 = dot(c, c);
  if (r2 > 1.0) discard;
  // A sphere, not a disc: its normal for the light and its depth for where particles overlap the cloth.
  vec3 n = vec3(c, sqrt(1.0 - r2));
  vec4 clip = u_projection * vec4(v_eye_centre + u_radius * n, 1.0);
  gl_FragDepth = 0.5 * clip.z / clip.w + 0.5;
  o_colour = vec4(shade(v_colour, n, normalize(-v_eye_centre), 0.25, 40.0, 0.0), 1.0);
}
)";

constexpr const char* kBackdropVertex = R"(#version 330 core
out float v_height;
void main() {
  // One triangle that covers the screen, from gl_VertexID alone.
  vec2 p = vec2(float((gl_VertexID & 1) * 4 - 1), float((gl_VertexID & 2) * 2 - 1));
  v_height = 0.5 * p.y + 0.5;
  gl_Position = vec4(p, 0.0, 1.0);
}
)";

constexpr const char* kBackdropFragment = R"(#version 330 core
in float v_height;
uniform vec3 u_top;
uniform vec3 u_bottom;
out vec4 o_colour;
void main() {
  o_colour = vec4(mix(u_bottom, u_top, clamp(v_height, 0.0, 1.0)), 1.0);
}
)";

// The transparent water's shared pieces: the distance from the eye to what is opaque at a pixel, from the
// depth texture of the opaque pass (the view ray's length, not the depth along -z, since the thickness and
// the water's own distances are measured along the ray).
constexpr const char* kOpaqueDistance = R"(
uniform sampler2D u_background_depth;
uniform mat4 u_inverse_projection;
uniform vec2 u_viewport_origin;
uniform vec2 u_viewport_size;
vec2 pixel_uv() { return (gl_FragCoord.xy - u_viewport_origin) / u_viewport_size; }
float opaque_distance(vec2 uv) {
  float depth = texture(u_background_depth, uv).r;
  if (depth >= 1.0) return 1e30;  // the backdrop: nothing opaque along the ray
  vec4 eye = u_inverse_projection * vec4(2.0 * uv - 1.0, 2.0 * depth - 1.0, 1.0);
  return length(eye.xyz / eye.w);
}
)";

// Summed with additive blending over every face of the surface: a ray enters a closed surface through a face
// that faces it (counter-clockwise, front-facing) and leaves through one that does not, so the sum of the
// signed distances is the length of the ray inside the water. Each distance is cut at what is opaque, so
// water behind the cloth does not count and water that reaches the cloth counts up to it.
constexpr const char* kThicknessFragment = R"(
in vec3 v_normal;
in vec3 v_eye_position;
out vec4 o_thickness;
void main() {
  float d = min(length(v_eye_position), opaque_distance(pixel_uv()));
  o_thickness = vec4(gl_FrontFacing ? -d : d, 0.0, 0.0, 0.0);
}
)";

constexpr const char* kWaterFragment = R"(
in vec3 v_normal;
in vec3 v_eye_position;
uniform sampler2D u_background_colour;
uniform sampler2D u_thickness;
uniform mat4 u_projection;
uniform mat3 u_eye_to_world;
uniform float u_relative_index;  // air over water, 1 / n
uniform float u_f0;              // reflectance head on, ((n - 1) / (n + 1))^2
uniform vec3 u_absorption;       // 1/m per channel
out vec4 o_colour;

uniform vec3 u_zenith;
uniform vec3 u_horizon;
uniform vec3 u_ground;

// A plain sky over a darker ground, by the world direction's height: what the water reflects.
vec3 sky(vec3 d) {
  return d.y >= 0.0 ? mix(u_horizon, u_zenith, sqrt(d.y)) : mix(u_horizon, u_ground, sqrt(-d.y));
}

void main() {
  vec2 uv = pixel_uv();
  vec3 incident = normalize(v_eye_position);
  vec3 n = normalize(v_normal);
  if (dot(n, incident) > 0.0) n = -n;  // the side the eye sees
  float cos_i = clamp(-dot(n, incident), 0.0, 1.0);
  float fresnel = u_f0 + (1.0 - u_f0) * pow(1.0 - cos_i, 5.0);  // Schlick 1994
  // abs: a surface wound clockwise from outside sums to minus its thickness.
  float thickness = abs(texture(u_thickness, uv).r);
  // What shows through is what lies where the refracted ray leaves the water, unless something opaque
  // stands between the eye and the water there (then the straight view, which has no such artefact).
  vec2 seen = uv;
  vec3 refracted = refract(incident, n, u_relative_index);
  vec4 clip = u_projection * vec4(v_eye_position + thickness * refracted, 1.0);
  vec2 shifted = 0.5 * clip.xy / clip.w + 0.5;
  if (clip.w > 0.0 && all(greaterThanEqual(shifted, vec2(0.0))) && all(lessThanEqual(shifted, vec2(1.0))) &&
      opaque_distance(shifted) > length(v_eye_position))
    seen = shifted;
  vec3 behind = texture(u_background_colour, seen).rgb * exp(-u_absorption * thickness);
  vec3 reflected = sky(u_eye_to_world * reflect(incident, n));
  // The key light's glint, as sharp as a calm surface gives it.
  float glint = 0.8 * pow(max(dot(n, normalize(kKey - incident)), 0.0), 400.0);
  o_colour = vec4(mix(behind, reflected, fresnel) + vec3(glint), 1.0);
}
)";

GLuint compile(GLenum kind, const std::string& source, const char* name) {
  const GLuint shader = glCreateShader(kind);
  const char* text = source.c_str();
  glShaderSource(shader, 1, &text, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048] = {};
    glGetShaderInfoLog(shader, sizeof log, nullptr, log);
    glDeleteShader(shader);
    throw RenderError(std::string("the ") + name + " shader does not compile: " + log);
  }
  return shader;
}

GLuint link(const std::string& vertex, const std::string& fragment, const char* name) {
  const GLuint v = compile(GL_VERTEX_SHADER, vertex, name);
  const GLuint f = compile(GL_FRAGMENT_SHADER, fragment, name);
  const GLuint program = glCreateProgram();
  glAttachShader(program, v);
  glAttachShader(program, f);
  glLinkProgram(program);
  glDeleteShader(v);
  glDeleteShader(f);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[2048] = {};
    glGetProgramInfoLog(program, sizeof log, nullptr, log);
    glDeleteProgram(program);
    throw RenderError(std::string("the ") + name + " shaders do not link: " + log);
  }
  return program;
}

/// Column-major floats, as glUniformMatrix4fv takes them.
void set_matrix(GLuint program, const char* name, const Eigen::Matrix4d& m) {
  const Eigen::Matrix4f f = m.cast<float>();
  glUniformMatrix4fv(glGetUniformLocation(program, name), 1, GL_FALSE, f.data());
}

void set_colour(GLuint program, const char* name, const float (&rgb)[3]) {
  glUniform3fv(glGetUniformLocation(program, name), 1, rgb);
}

void set_float(GLuint program, const char* name, float value) {
  glUniform1f(glGetUniformLocation(program, name), value);
}

/// (Re)allocates a 2D texture of `width` x `height` with nearest sampling, clamped at the edges.
void allocate_texture(GLuint texture, GLint internal_format, GLenum format, GLenum type, int width,
                      int height, GLint filter) {
  glBindTexture(GL_TEXTURE_2D, texture);
  glTexImage2D(GL_TEXTURE_2D, 0, internal_format, width, height, 0, format, type, nullptr);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, filter);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, filter);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
}

}  // namespace

struct Renderer::State {
  GLuint mesh_program = 0, particle_program = 0, backdrop_program = 0;
  GLuint thickness_program = 0, water_program = 0;
  GLuint vertex_array = 0;
  GLuint vertex_buffer = 0, index_buffer = 0;
  std::vector<float> vertices;  // reused between frames
  // The transparent water's targets, of the viewport's size: the opaque scene (colour, depth) and the
  // water's thickness. Made on the first transparent frame, remade when the size or sampling changes. The
  // opaque scene is drawn multisampled as the caller's framebuffer is, then resolved into the textures, so
  // that edges seen through the water are as smooth as edges seen directly.
  int target_width = 0, target_height = 0, target_samples = 0;
  GLuint background_framebuffer = 0, thickness_framebuffer = 0, multisampled_framebuffer = 0;
  GLuint background_colour = 0, background_depth = 0, thickness = 0;  // textures
  GLuint multisampled_renderbuffers[2] = {0, 0};                      // colour, depth

  /// @param samples  the caller's framebuffer's (GL_SAMPLES); <= 1 draws the opaque scene straight into the
  ///        textures
  void ensure_targets(int width, int height, int samples);
  /// Uploads `mesh` with smooth normals into the vertex and index buffers, attributes 0 and 1 set.
  void upload_mesh(const TriangleMesh& mesh);
};

void Renderer::State::ensure_targets(int width, int height, int samples) {
  samples = std::max(samples, 1);
  if (background_framebuffer != 0 && width == target_width && height == target_height &&
      samples == target_samples)
    return;
  if (background_framebuffer == 0) {
    glGenFramebuffers(1, &background_framebuffer);
    glGenFramebuffers(1, &thickness_framebuffer);
    glGenFramebuffers(1, &multisampled_framebuffer);
    glGenRenderbuffers(2, multisampled_renderbuffers);
    GLuint textures[3];
    glGenTextures(3, textures);
    background_colour = textures[0];
    background_depth = textures[1];
    thickness = textures[2];
  }
  target_width = width;
  target_height = height;
  target_samples = samples;
  GLenum multisampled_status = GL_FRAMEBUFFER_COMPLETE;
  if (samples > 1) {
    glBindRenderbuffer(GL_RENDERBUFFER, multisampled_renderbuffers[0]);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA8, width, height);
    glBindRenderbuffer(GL_RENDERBUFFER, multisampled_renderbuffers[1]);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH_COMPONENT24, width, height);
    glBindRenderbuffer(GL_RENDERBUFFER, 0);
    glBindFramebuffer(GL_FRAMEBUFFER, multisampled_framebuffer);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                              multisampled_renderbuffers[0]);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER,
                              multisampled_renderbuffers[1]);
    multisampled_status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  }
  // Linear colour, since the refracted ray lands between pixels; depth and thickness are read per pixel.
  allocate_texture(background_colour, GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, width, height, GL_LINEAR);
  allocate_texture(background_depth, GL_DEPTH_COMPONENT24, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, width, height,
                   GL_NEAREST);
  // 32-bit float: a sum of distances of about a metre whose differences are millimetres.
  allocate_texture(thickness, GL_R32F, GL_RED, GL_FLOAT, width, height, GL_NEAREST);
  glBindTexture(GL_TEXTURE_2D, 0);
  glBindFramebuffer(GL_FRAMEBUFFER, background_framebuffer);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, background_colour, 0);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, background_depth, 0);
  const GLenum background_status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  glBindFramebuffer(GL_FRAMEBUFFER, thickness_framebuffer);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, thickness, 0);
  const GLenum thickness_status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  if (background_status != GL_FRAMEBUFFER_COMPLETE || thickness_status != GL_FRAMEBUFFER_COMPLETE ||
      multisampled_status != GL_FRAMEBUFFER_COMPLETE) {
    char text[128];
    std::snprintf(text, sizeof text,
                  "the transparent water's framebuffers are incomplete (status 0x%04x, 0x%04x, 0x%04x)",
                  background_status, thickness_status, multisampled_status);
    throw RenderError(text);
  }
}

Renderer::Renderer() : m_state(std::make_unique<State>()) {
  State& s = *m_state;
  const std::string fragment_header = std::string("#version 330 core\n") + kLighting;
  s.mesh_program = link(kMeshVertex, fragment_header + kMeshFragment, "mesh");
  s.particle_program = link(kParticleVertex, fragment_header + kParticleFragment, "particle");
  s.backdrop_program = link(kBackdropVertex, kBackdropFragment, "backdrop");
  s.thickness_program =
      link(kMeshVertex, fragment_header + kOpaqueDistance + kThicknessFragment, "thickness");
  s.water_program = link(kMeshVertex, fragment_header + kOpaqueDistance + kWaterFragment, "water");
  glGenVertexArrays(1, &s.vertex_array);
  glGenBuffers(1, &s.vertex_buffer);
  glGenBuffers(1, &s.index_buffer);
}

Renderer::~Renderer() {
  State& s = *m_state;
  glDeleteBuffers(1, &s.vertex_buffer);
  glDeleteBuffers(1, &s.index_buffer);
  glDeleteVertexArrays(1, &s.vertex_array);
  if (s.background_framebuffer != 0) {
    glDeleteFramebuffers(1, &s.background_framebuffer);
    glDeleteFramebuffers(1, &s.thickness_framebuffer);
    glDeleteFramebuffers(1, &s.multisampled_framebuffer);
    glDeleteRenderbuffers(2, s.multisampled_renderbuffers);
    const GLuint textures[3] = {s.background_colour, s.background_depth, s.thickness};
    glDeleteTextures(3, textures);
  }
  glDeleteProgram(s.mesh_program);
  glDeleteProgram(s.particle_program);
  glDeleteProgram(s.backdrop_program);
  glDeleteProgram(s.thickness_program);
  glDeleteProgram(s.water_program);
}

namespace {

/// Positions and area-weighted vertex normals, interleaved (x y z nx ny nz), for smooth shading.
void mesh_vertices(const TriangleMesh& mesh, std::vector<float>& out) {
  Vec3Array normals(mesh.positions.size(), Vec3::Zero());
  for (const Triangle& t : mesh.triangles) {
    assert(t[0] < mesh.positions.size() && t[1] < mesh.positions.size() && t[2] < mesh.positions.size());
    // The cross product's length is twice the area: larger triangles weigh more.
    const Vec3 n =
        (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
    for (Index v : t)
      normals[v] += n;
  }
  out.resize(6 * mesh.positions.size());
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    const Scalar length = normals[i].norm();
    const Vec3 n = length > 0 ? Vec3(normals[i] / length) : Vec3(0, 1, 0);
    for (int a = 0; a < 3; ++a) {
      out[6 * i + a] = static_cast<float>(mesh.positions[i][a]);
      out[6 * i + 3 + a] = static_cast<float>(n[a]);
    }
  }
}

}  // namespace

void Renderer::State::upload_mesh(const TriangleMesh& mesh) {
  mesh_vertices(mesh, vertices);
  glBindBuffer(GL_ARRAY_BUFFER, vertex_buffer);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, index_buffer);
  glBufferData(GL_ARRAY_BUFFER, vertices.size() * sizeof(float), vertices.data(), GL_STREAM_DRAW);
  static_assert(sizeof(Triangle) == 3 * sizeof(GLuint), "triangles upload as GL_UNSIGNED_INT triples");
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, mesh.triangles.size() * sizeof(Triangle), mesh.triangles.data(),
               GL_STREAM_DRAW);
  glEnableVertexAttribArray(0);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                        reinterpret_cast<const void*>(3 * sizeof(float)));
}

void Renderer::draw(const FrameGeometry& frame, const Camera& camera, const ParticleStyle& style, int width,
                    int height, const WaterStyle& water) {
  State& s = *m_state;
  const Scalar aspect = static_cast<Scalar>(width) / height;
  // The depth range just holds the scene's bounding sphere, for the most depth precision where it matters.
  const Scalar radius = std::max(0.5 * frame.bounds.diagonal().norm(), 1e-3);
  const Scalar distance = (camera.position - frame.bounds.center()).norm();
  const Scalar far = 2.0 * (distance + radius);
  const Scalar near = std::max(0.5 * (distance - radius), 1e-4 * far);
  const Eigen::Matrix4d view = view_matrix(camera);
  const Eigen::Matrix4d projection = projection_matrix(camera, aspect, near, far);
  const bool transparent_water = water.shading == WaterShading::TRANSPARENT && frame.surface != nullptr &&
                                 !frame.surface->triangles.empty();

  glBindVertexArray(s.vertex_array);
  const auto draw_mesh = [&](const TriangleMesh* mesh, const float(&front)[3], const float(&back)[3],
                             float specular, float shininess, float rim) {
    if (mesh == nullptr || mesh->triangles.empty()) return;
    s.upload_mesh(*mesh);
    glUseProgram(s.mesh_program);
    set_matrix(s.mesh_program, "u_view", view);
    set_matrix(s.mesh_program, "u_projection", projection);
    set_colour(s.mesh_program, "u_front", front);
    set_colour(s.mesh_program, "u_back", back);
    set_float(s.mesh_program, "u_specular", specular);
    set_float(s.mesh_program, "u_shininess", shininess);
    set_float(s.mesh_program, "u_rim", rim);
    glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(3 * mesh->triangles.size()), GL_UNSIGNED_INT, nullptr);
  };
  // The backdrop, the obstacles and the cloth: all that the water may hide or show.
  const auto draw_opaque = [&]() {
    glDisable(GL_DEPTH_TEST);
    glDepthMask(GL_FALSE);
    glDisable(GL_BLEND);
    glUseProgram(s.backdrop_program);
    set_colour(s.backdrop_program, "u_top", Palette::kBackdropTop);
    set_colour(s.backdrop_program, "u_bottom", Palette::kBackdropBottom);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glDepthMask(GL_TRUE);
    glClear(GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_CULL_FACE);
    draw_mesh(frame.obstacles, Palette::kObstacle, Palette::kObstacle, 0.05f, 20.0f, 0.0f);
    if (frame.cloth_wireframe) glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
    draw_mesh(frame.cloth, Palette::kClothFront, Palette::kClothBack, 0.04f, 12.0f, 0.0f);
    glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
  };

  if (transparent_water) {
    // The caller's framebuffer and viewport, to come back to after the passes into the textures.
    GLint caller_framebuffer = 0, viewport[4] = {0, 0, width, height};
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &caller_framebuffer);
    glGetIntegerv(GL_VIEWPORT, viewport);
    GLint samples = 0;
    glGetIntegerv(GL_SAMPLES, &samples);
    s.ensure_targets(width, height, samples);
    glViewport(0, 0, width, height);
    if (s.target_samples > 1) {
      glBindFramebuffer(GL_FRAMEBUFFER, s.multisampled_framebuffer);
      draw_opaque();
      glBindFramebuffer(GL_READ_FRAMEBUFFER, s.multisampled_framebuffer);
      glBindFramebuffer(GL_DRAW_FRAMEBUFFER, s.background_framebuffer);
      glBlitFramebuffer(0, 0, width, height, 0, 0, width, height, GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT,
                        GL_NEAREST);
    } else {
      glBindFramebuffer(GL_FRAMEBUFFER, s.background_framebuffer);
      draw_opaque();
    }
    // The opaque scene again in the caller's (multisampled) framebuffer, whose depth the water's last pass
    // tests against; drawn now so that the surface is uploaded once, for both of its passes.
    glBindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(caller_framebuffer));
    glViewport(viewport[0], viewport[1], viewport[2], viewport[3]);
    draw_opaque();

    // The thickness: every face of the water, none hidden, summed.
    const auto set_pass_uniforms = [&](GLuint program, GLint origin_x, GLint origin_y) {
      glUseProgram(program);
      set_matrix(program, "u_view", view);
      set_matrix(program, "u_projection", projection);
      set_matrix(program, "u_inverse_projection", projection.inverse());
      glUniform2f(glGetUniformLocation(program, "u_viewport_origin"), static_cast<float>(origin_x),
                  static_cast<float>(origin_y));
      glUniform2f(glGetUniformLocation(program, "u_viewport_size"), static_cast<float>(width),
                  static_cast<float>(height));
      glActiveTexture(GL_TEXTURE0);
      glBindTexture(GL_TEXTURE_2D, s.background_depth);
      glUniform1i(glGetUniformLocation(program, "u_background_depth"), 0);
    };
    s.upload_mesh(*frame.surface);
    glBindFramebuffer(GL_FRAMEBUFFER, s.thickness_framebuffer);
    glViewport(0, 0, width, height);
    glClearColor(0.0f, 0.0f, 0.0f, 0.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    glDisable(GL_DEPTH_TEST);
    glDepthMask(GL_FALSE);
    glEnable(GL_BLEND);
    glBlendEquation(GL_FUNC_ADD);
    glBlendFunc(GL_ONE, GL_ONE);
    set_pass_uniforms(s.thickness_program, 0, 0);
    const auto surface_elements = static_cast<GLsizei>(3 * frame.surface->triangles.size());
    glDrawElements(GL_TRIANGLES, surface_elements, GL_UNSIGNED_INT, nullptr);
    glDisable(GL_BLEND);

    // The water's nearest face over the opaque scene, shaded from the textures.
    glBindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(caller_framebuffer));
    glViewport(viewport[0], viewport[1], viewport[2], viewport[3]);
    set_pass_uniforms(s.water_program, viewport[0], viewport[1]);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, s.background_colour);
    glUniform1i(glGetUniformLocation(s.water_program, "u_background_colour"), 1);
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_2D, s.thickness);
    glUniform1i(glGetUniformLocation(s.water_program, "u_thickness"), 2);
    const Eigen::Matrix3f eye_to_world = view.topLeftCorner<3, 3>().transpose().cast<float>();
    glUniformMatrix3fv(glGetUniformLocation(s.water_program, "u_eye_to_world"), 1, GL_FALSE,
                       eye_to_world.data());
    const Scalar n = water.refractive_index;
    set_float(s.water_program, "u_relative_index", static_cast<float>(1.0 / n));
    set_float(s.water_program, "u_f0", static_cast<float>(((n - 1) / (n + 1)) * ((n - 1) / (n + 1))));
    set_colour(s.water_program, "u_zenith", Palette::kSkyZenith);
    set_colour(s.water_program, "u_horizon", Palette::kSkyHorizon);
    set_colour(s.water_program, "u_ground", Palette::kGround);
    const Eigen::Vector3f absorption = water.absorption.cast<float>();
    glUniform3fv(glGetUniformLocation(s.water_program, "u_absorption"), 1, absorption.data());
    glEnable(GL_DEPTH_TEST);
    glDepthMask(GL_TRUE);
    glDrawElements(GL_TRIANGLES, surface_elements, GL_UNSIGNED_INT, nullptr);
    for (GLenum unit : {GL_TEXTURE2, GL_TEXTURE1, GL_TEXTURE0}) {
      glActiveTexture(unit);
      glBindTexture(GL_TEXTURE_2D, 0);
    }
    glBindVertexArray(0);
    return;
  }

  draw_opaque();
  if (frame.surface != nullptr) {
    draw_mesh(frame.surface, Palette::kWater, Palette::kWater, 0.35f, 60.0f, 0.25f);
  } else if (frame.particles != nullptr && !frame.particles->empty()) {
    const Vec3Array& x = *frame.particles;
    assert(frame.velocities == nullptr || frame.velocities->size() == x.size());
    s.vertices.resize(4 * x.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
      for (int a = 0; a < 3; ++a)
        s.vertices[4 * i + a] = static_cast<float>(x[i][a]);
      s.vertices[4 * i + 3] = frame.velocities ? static_cast<float>((*frame.velocities)[i].norm()) : 0.0f;
    }
    glBindBuffer(GL_ARRAY_BUFFER, s.vertex_buffer);
    glBufferData(GL_ARRAY_BUFFER, s.vertices.size() * sizeof(float), s.vertices.data(), GL_STREAM_DRAW);
    glEnableVertexAttribArray(0);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 4 * sizeof(float), nullptr);
    glVertexAttribPointer(1, 1, GL_FLOAT, GL_FALSE, 4 * sizeof(float),
                          reinterpret_cast<const void*>(3 * sizeof(float)));
    glUseProgram(s.particle_program);
    set_matrix(s.particle_program, "u_view", view);
    set_matrix(s.particle_program, "u_projection", projection);
    set_float(s.particle_program, "u_radius", static_cast<float>(style.radius));
    set_float(s.particle_program, "u_viewport_height", static_cast<float>(height));
    set_float(s.particle_program, "u_speed_scale", static_cast<float>(style.speed_scale));
    set_colour(s.particle_program, "u_slow", Palette::kSlowWater);
    set_colour(s.particle_program, "u_fast", Palette::kFastWater);
    glEnable(GL_PROGRAM_POINT_SIZE);
    glDrawArrays(GL_POINTS, 0, static_cast<GLsizei>(x.size()));
  }
  glBindVertexArray(0);
}

}  // namespace drench::render
