#include "render/gl_resources.hpp"

#include "core/error.hpp"
#include "core/text.hpp"

namespace softbake {

namespace {

GLuint compileShader(GLenum type, const char* source) {
  const GLuint shader = glCreateShader(type);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048] = {};
    glGetShaderInfoLog(shader, sizeof log, nullptr, log);
    glDeleteShader(shader);
    throw Error(cat("renderer: the OpenGL driver rejected a shader: ", log));
  }
  return shader;
}

}  // namespace

GLuint linkProgram(const char* vertex, const char* fragment) {
  const GLuint vs = compileShader(GL_VERTEX_SHADER, vertex);
  const GLuint fs = compileShader(GL_FRAGMENT_SHADER, fragment);
  const GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[2048] = {};
    glGetProgramInfoLog(program, sizeof log, nullptr, log);
    glDeleteProgram(program);
    throw Error(cat("renderer: the OpenGL driver could not link a shader program: ", log));
  }
  return program;
}

void checkGl(const char* what) {
  const GLenum error = glGetError();
  if (error != GL_NO_ERROR)
    throw Error(cat("renderer: OpenGL error 0x", std::hex, error, " ", what));
}

void uniform(GLuint program, const char* name, const Vec3f& v) {
  glUniform3f(glGetUniformLocation(program, name), v.x(), v.y(), v.z());
}
void uniform(GLuint program, const char* name, float v) {
  glUniform1f(glGetUniformLocation(program, name), v);
}
void uniform(GLuint program, const char* name, int v) {
  glUniform1i(glGetUniformLocation(program, name), v);
}
void uniform(GLuint program, const char* name, const Eigen::Matrix4f& m) {
  glUniformMatrix4fv(glGetUniformLocation(program, name), 1, GL_FALSE, m.data());  // column-major
}

void MeshBuffers::create(const std::vector<float>& interleaved,
                         const std::vector<Index>& triangleIndices, GLenum usage) {
  glGenVertexArrays(1, &vao);
  glGenBuffers(1, &vertices);
  glGenBuffers(1, &indices);
  glBindVertexArray(vao);
  glBindBuffer(GL_ARRAY_BUFFER, vertices);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(interleaved.size() * sizeof(float)), interleaved.data(),
               usage);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                        reinterpret_cast<const void*>(3 * sizeof(float)));
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, indices);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(triangleIndices.size() * sizeof(Index)),
               triangleIndices.data(), GL_STATIC_DRAW);
  indexCount = GLsizei(triangleIndices.size());
  glBindVertexArray(0);
}

void MeshBuffers::destroy() {
  glDeleteBuffers(1, &vertices);
  glDeleteBuffers(1, &indices);
  glDeleteVertexArrays(1, &vao);
}

}  // namespace softbake
