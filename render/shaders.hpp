#pragma once
/// The renderer's GLSL sources (render/shaders.cpp), OpenGL 3.3 core.
///
///   surface: meshes and instanced contact spheres; attribute 0 position, 1 normal, 2 a
///            per-instance offset; Lambert key + fill, Blinn-Phong on the key, hemisphere ambient.
///   ground:  one quad on the first plane; a procedural grid and a fade to the background
///            towards the horizon. Drawn once per sequence.
///   shadow:  one body's blob shadow, a square on the plane multiplied into the ground per frame.

namespace softbake {

extern const char* const kSurfaceVertexShader;
extern const char* const kSurfaceFragmentShader;
extern const char* const kGroundVertexShader;
extern const char* const kGroundFragmentShader;
extern const char* const kShadowVertexShader;
extern const char* const kShadowFragmentShader;

}  // namespace softbake
