#pragma once
/// Small pieces of OpenGL the renderer is built from: shader programs, uniforms, error checks and
/// mesh buffers. Every call needs a current context (render/egl_context.hpp).

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>

#include <vector>

#include <Eigen/Core>

#include "core/types.hpp"

namespace softbake {

/// A linked program of the two sources. Throws softbake::Error with the driver's log.
GLuint linkProgram(const char* vertex, const char* fragment);

/// Throws softbake::Error naming `what` when OpenGL has recorded an error.
void checkGl(const char* what);

void uniform(GLuint program, const char* name, const Vec3f& v);
void uniform(GLuint program, const char* name, float v);
void uniform(GLuint program, const char* name, int v);
void uniform(GLuint program, const char* name, const Eigen::Matrix4f& m);

/// A vertex array of interleaved position + normal floats and triangle indices.
struct MeshBuffers {
  GLuint vao = 0, vertices = 0, indices = 0;
  GLsizei indexCount = 0;

  void create(const std::vector<float>& interleaved, const std::vector<Index>& triangleIndices,
              GLenum usage);
  void destroy();
};

}  // namespace softbake
