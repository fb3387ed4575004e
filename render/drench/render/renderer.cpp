#include <drench/render/renderer.hpp>

#define GL_GLEXT_PROTOTYPES
#include <GL/glcorearb.h>

#include <algorithm>
#include <cassert>
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

}  // namespace

struct Renderer::State {
  GLuint mesh_program = 0, particle_program = 0, backdrop_program = 0;
  GLuint vertex_array = 0;
  GLuint vertex_buffer = 0, index_buffer = 0;
  std::vector<float> vertices;  // reused between frames
};

Renderer::Renderer() : m_state(std::make_unique<State>()) {
  State& s = *m_state;
  const std::string fragment_header = std::string("#version 330 core\n") + kLighting;
  s.mesh_program = link(kMeshVertex, fragment_header + kMeshFragment, "mesh");
  s.particle_program = link(kParticleVertex, fragment_header + kParticleFragment, "particle");
  s.backdrop_program = link(kBackdropVertex, kBackdropFragment, "backdrop");
  glGenVertexArrays(1, &s.vertex_array);
  glGenBuffers(1, &s.vertex_buffer);
  glGenBuffers(1, &s.index_buffer);
}

Renderer::~Renderer() {
  State& s = *m_state;
  glDeleteBuffers(1, &s.vertex_buffer);
  glDeleteBuffers(1, &s.index_buffer);
  glDeleteVertexArrays(1, &s.vertex_array);
  glDeleteProgram(s.mesh_program);
  glDeleteProgram(s.particle_program);
  glDeleteProgram(s.backdrop_program);
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

void Renderer::draw(const FrameGeometry& frame, const Camera& camera, const ParticleStyle& style, int width,
                    int height) {
  State& s = *m_state;
  const Scalar aspect = static_cast<Scalar>(width) / height;
  // The depth range just holds the scene's bounding sphere, for the most depth precision where it matters.
  const Scalar radius = std::max(0.5 * frame.bounds.diagonal().norm(), 1e-3);
  const Scalar distance = (camera.position - frame.bounds.center()).norm();
  const Scalar far = 2.0 * (distance + radius);
  const Scalar near = std::max(0.5 * (distance - radius), 1e-4 * far);
  const Eigen::Matrix4d view = view_matrix(camera);
  const Eigen::Matrix4d projection = projection_matrix(camera, aspect, near, far);

  glDisable(GL_DEPTH_TEST);
  glDepthMask(GL_FALSE);
  glBindVertexArray(s.vertex_array);
  glUseProgram(s.backdrop_program);
  set_colour(s.backdrop_program, "u_top", Palette::kBackdropTop);
  set_colour(s.backdrop_program, "u_bottom", Palette::kBackdropBottom);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glDepthMask(GL_TRUE);
  glClear(GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_CULL_FACE);

  glBindBuffer(GL_ARRAY_BUFFER, s.vertex_buffer);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, s.index_buffer);
  const auto draw_mesh = [&](const TriangleMesh* mesh, const float(&front)[3], const float(&back)[3],
                             float specular, float shininess, float rim) {
    if (mesh == nullptr || mesh->triangles.empty()) return;
    mesh_vertices(*mesh, s.vertices);
    glBufferData(GL_ARRAY_BUFFER, s.vertices.size() * sizeof(float), s.vertices.data(), GL_STREAM_DRAW);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, mesh->triangles.size() * sizeof(Triangle), mesh->triangles.data(),
                 GL_STREAM_DRAW);
    glEnableVertexAttribArray(0);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                          reinterpret_cast<const void*>(3 * sizeof(float)));
    glUseProgram(s.mesh_program);
    set_matrix(s.mesh_program, "u_view", view);
    set_matrix(s.mesh_program, "u_projection", projection);
    set_colour(s.mesh_program, "u_front", front);
    set_colour(s.mesh_program, "u_back", back);
    glUniform1f(glGetUniformLocation(s.mesh_program, "u_specular"), specular);
    glUniform1f(glGetUniformLocation(s.mesh_program, "u_shininess"), shininess);
    glUniform1f(glGetUniformLocation(s.mesh_program, "u_rim"), rim);
    static_assert(sizeof(Triangle) == 3 * sizeof(GLuint), "triangles upload as GL_UNSIGNED_INT triples");
    glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(3 * mesh->triangles.size()), GL_UNSIGNED_INT, nullptr);
  };
  draw_mesh(frame.obstacles, Palette::kObstacle, Palette::kObstacle, 0.05f, 20.0f, 0.0f);
  if (frame.cloth_wireframe) glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
  draw_mesh(frame.cloth, Palette::kClothFront, Palette::kClothBack, 0.04f, 12.0f, 0.0f);
  glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
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
    glBufferData(GL_ARRAY_BUFFER, s.vertices.size() * sizeof(float), s.vertices.data(), GL_STREAM_DRAW);
    glEnableVertexAttribArray(0);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 4 * sizeof(float), nullptr);
    glVertexAttribPointer(1, 1, GL_FLOAT, GL_FALSE, 4 * sizeof(float),
                          reinterpret_cast<const void*>(3 * sizeof(float)));
    glUseProgram(s.particle_program);
    set_matrix(s.particle_program, "u_view", view);
    set_matrix(s.particle_program, "u_projection", projection);
    glUniform1f(glGetUniformLocation(s.particle_program, "u_radius"), static_cast<float>(style.radius));
    glUniform1f(glGetUniformLocation(s.particle_program, "u_viewport_height"), static_cast<float>(height));
    glUniform1f(glGetUniformLocation(s.particle_program, "u_speed_scale"),
                static_cast<float>(style.speed_scale));
    set_colour(s.particle_program, "u_slow", Palette::kSlowWater);
    set_colour(s.particle_program, "u_fast", Palette::kFastWater);
    glEnable(GL_PROGRAM_POINT_SIZE);
    glDrawArrays(GL_POINTS, 0, static_cast<GLsizei>(x.size()));
  }
  glBindVertexArray(0);
}

}  // namespace drench::render
