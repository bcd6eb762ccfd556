#pragma once
/// The renderer's GLSL sources (render/shaders.cpp), OpenGL 3.3 core.
///
///   surface: meshes and instanced contact spheres; attribute 0 position, 1 normal, 2 a
///            per-instance offset, 3 a tint (per instance: a contact's colour); Lambert key +
///            fill, Blinn-Phong on the key, hemisphere ambient.
///   translucent: the surface's vertex shader and shading, written to the two targets of
///            weighted blended order-independent transparency (the contact view's bodies).
///   composite: the translucent layers over the opaque image, one triangle over the viewport.
///   ground:  one quad on the first plane; a procedural grid and a fade to the background
///            towards the horizon. Drawn once per sequence.
///   shadow:  one body's blob shadow, a square on the plane multiplied into the ground per frame.

#include <string>

namespace softbake {

extern const char* const kSurfaceVertexShader;
extern const std::string kSurfaceFragmentShader;      ///< with the surface shading
extern const std::string kTranslucentFragmentShader;  ///< with the surface shading
extern const char* const kFullScreenVertexShader;
extern const char* const kCompositeFragmentShader;
extern const char* const kGroundVertexShader;
extern const char* const kGroundFragmentShader;
extern const char* const kShadowVertexShader;
extern const char* const kShadowFragmentShader;

}  // namespace softbake
