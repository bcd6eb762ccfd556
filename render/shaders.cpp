// The GLSL of the renderer (OpenGL 3.3 core, so the same code runs on llvmpipe and on GPUs).
#include "render/shaders.hpp"

namespace softbake {

const char* const kSurfaceVertexShader = R"(#version 330 core
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec3 aNormal;
layout(location = 2) in vec3 aOffset;
layout(location = 3) in vec3 aTint;
uniform mat4 uViewProjection;
uniform float uScale;
out vec3 vPosition;
out vec3 vNormal;
out vec3 vTint;
void main() {
  vPosition = aPosition * uScale + aOffset;
  vNormal = aNormal;
  vTint = aTint;
  gl_Position = uViewProjection * vec4(vPosition, 1.0);
}
)";

// Lambert from a key and a fill light plus Blinn-Phong on the key, over a sky/ground hemisphere
// ambient. Lights are white so grey materials stay grey. The colour is uColor times the vertex's
// tint (attribute 3: per contact sphere its kind's colour, white for meshes). Output is gamma
// encoded. Shared by the opaque and the translucent surface shaders.
namespace {
const char* const kSurfaceShading = R"(
in vec3 vPosition;
in vec3 vNormal;
in vec3 vTint;
uniform vec3 uColor;
uniform vec3 uEye;
uniform vec3 uKey;
uniform vec3 uFill;
uniform vec3 uUp;
uniform float uSpecular;
uniform int uFlat;
vec3 shade(vec3 n, vec3 v) {
  vec3 albedo = uColor * vTint;
  if (uFlat == 1) return pow(albedo, vec3(1.0 / 2.2));
  if (dot(n, v) < 0.0) n = -n;  // the inside of an open mesh
  float key = max(dot(n, uKey), 0.0);
  float fill = max(dot(n, uFill), 0.0);
  float hemi = 0.5 + 0.5 * dot(n, uUp);
  vec3 ambient = mix(vec3(0.08), vec3(0.22), hemi);
  float specular = key > 0.0 ? pow(max(dot(n, normalize(uKey + v)), 0.0), 48.0) * uSpecular : 0.0;
  vec3 color = albedo * (ambient + 0.80 * key + 0.28 * fill) + vec3(specular);
  return pow(clamp(color, 0.0, 1.0), vec3(1.0 / 2.2));
}
)";
}  // namespace

const std::string kSurfaceFragmentShader =
    std::string("#version 330 core\n") + kSurfaceShading + R"(
out vec4 outColor;
void main() {
  outColor = vec4(shade(normalize(vNormal), normalize(uEye - vPosition)), 1.0);
}
)";

// The contact view's bodies: weighted blended order-independent transparency (McGuire & Bavoil,
// "Weighted Blended Order-Independent Transparency", JCGT 2013). With one blend function for both
// targets, glBlendFuncSeparate(ONE, ONE, ZERO, ONE_MINUS_SRC_ALPHA):
//   target 0 (RGBA16F, cleared to 0,0,0,1): rgb sums colour·weight, alpha multiplies (1 − α) into
//            the revealage, the share of the opaque image that still shows through;
//   target 1 (R16F, cleared to 0): red sums the weights.
// The weight falls with the distance from the eye in units of the scene's size (their equation 9
// in shape), so nearer layers dominate the average where several overlap. Surfaces seen edge-on
// are more opaque, as a thin shell is, which keeps the bodies' outlines readable.
const std::string kTranslucentFragmentShader =
    std::string("#version 330 core\n") + kSurfaceShading + R"(
uniform float uAlpha;
uniform float uDepthScale;
layout(location = 0) out vec4 outAccumulation;
layout(location = 1) out vec4 outWeight;
void main() {
  vec3 n = normalize(vNormal);
  vec3 v = normalize(uEye - vPosition);
  vec3 color = shade(n, v);
  float edgeOn = 1.0 - abs(dot(n, v));
  float alpha = uFlat == 1 ? uAlpha : min(uAlpha + 0.45 * edgeOn * edgeOn * edgeOn, 0.85);
  float z = length(uEye - vPosition) / uDepthScale;
  float weight = alpha * clamp(10.0 / (1e-5 + z * z * z * z), 1e-2, 3e3);
  outAccumulation = vec4(color * weight, alpha);
  outWeight = vec4(weight, 0.0, 0.0, alpha);
}
)";

// A triangle that covers the viewport, from gl_VertexID alone.
const char* const kFullScreenVertexShader = R"(#version 330 core
void main() {
  vec2 corner = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0);
}
)";

// The translucent layers' weighted average over the opaque image, blended with (SRC_ALPHA,
// ONE_MINUS_SRC_ALPHA): the opaque image keeps the revealage's share. Pixels no translucent
// surface covers are left as they are, byte for byte.
const char* const kCompositeFragmentShader = R"(#version 330 core
uniform sampler2D uAccumulation;
uniform sampler2D uWeight;
out vec4 outColor;
void main() {
  ivec2 pixel = ivec2(gl_FragCoord.xy);
  vec4 accumulation = texelFetch(uAccumulation, pixel, 0);
  float revealage = accumulation.a;
  if (revealage >= 1.0) discard;
  float weight = max(texelFetch(uWeight, pixel, 0).r, 1e-5);
  outColor = vec4(clamp(accumulation.rgb / weight, 0.0, 1.0), 1.0 - revealage);
}
)";

const char* const kGroundVertexShader = R"(#version 330 core
layout(location = 0) in vec3 aPosition;
uniform mat4 uViewProjection;
out vec3 vPosition;
void main() {
  vPosition = aPosition;
  gl_Position = uViewProjection * vec4(aPosition, 1.0);
}
)";

// A procedural grid (anti-aliased with fwidth) and a fade to the background towards the horizon.
// The camera and the plane are fixed for a sequence, so this is drawn once per sequence; the blob
// shadows are multiplied in per frame.
const char* const kGroundFragmentShader = R"(#version 330 core
in vec3 vPosition;
uniform vec3 uOrigin;
uniform vec3 uAxisU;
uniform vec3 uAxisV;
uniform vec3 uNormal;
uniform vec3 uEye;
uniform vec3 uKey;
uniform float uSpacing;
uniform vec2 uFade;
uniform vec3 uBackground;
out vec4 outColor;
float gridLine(vec2 uv) {
  vec2 d = abs(fract(uv - 0.5) - 0.5) / max(fwidth(uv), vec2(1e-6));
  return 1.0 - min(min(d.x, d.y), 1.0);
}
void main() {
  vec3 p = vPosition - uOrigin;
  vec2 uv = vec2(dot(p, uAxisU), dot(p, uAxisV)) / uSpacing;
  // Lines fade out where cells shrink to a few pixels, before they would alias into moiré.
  float density = max(fwidth(uv).x, fwidth(uv).y);
  float line = max(0.45 * gridLine(uv) * (1.0 - smoothstep(0.15, 0.4, density)),
                   0.8 * gridLine(uv / 4.0) * (1.0 - smoothstep(0.6, 1.6, density)));
  vec3 color = mix(vec3(0.50), vec3(0.30), line);
  color *= 0.55 + 0.45 * max(dot(uNormal, uKey), 0.0);
  color = pow(clamp(color, 0.0, 1.0), vec3(1.0 / 2.2));
  float fade = smoothstep(uFade.x, uFade.y, length(vPosition - uEye));
  outColor = vec4(mix(color, uBackground, fade), 1.0);
}
)";

// One body's blob shadow: a square on the ground plane around the point under the body, as far
// from the centre as the shadow can change an 8-bit value (BlobShadow::extent()), drawn as a
// triangle strip of four vertices without attributes.
const char* const kShadowVertexShader = R"(#version 330 core
uniform mat4 uViewProjection;
uniform vec3 uCenter;
uniform vec3 uAxisU;
uniform vec3 uAxisV;
uniform float uExtent;
out vec3 vPosition;
void main() {
  vec2 corner = vec2(float(gl_VertexID & 1), float(gl_VertexID >> 1)) * 2.0 - 1.0;
  vPosition = uCenter + uExtent * (corner.x * uAxisU + corner.y * uAxisV);
  gl_Position = uViewProjection * vec4(vPosition, 1.0);
}
)";

// The shadow's factor on the ground's colour, for multiplicative blending (DST_COLOR, ZERO). The
// ground is gamma encoded, so the linear factor is encoded too: (c·L)^(1/2.2) =
// c^(1/2.2)·L^(1/2.2). Where the ground fades into the background the shadow fades with it.
const char* const kShadowFragmentShader = R"(#version 330 core
in vec3 vPosition;
uniform vec3 uCenter;
uniform float uSigma;
uniform float uStrength;
uniform vec3 uEye;
uniform vec2 uFade;
out vec4 outColor;
void main() {
  vec3 lateral = vPosition - uCenter;
  float light = 1.0 - uStrength * exp(-dot(lateral, lateral) / (uSigma * uSigma));
  float fade = smoothstep(uFade.x, uFade.y, length(vPosition - uEye));
  outColor = vec4(vec3(mix(pow(light, 1.0 / 2.2), 1.0, fade)), 1.0);
}
)";

}  // namespace softbake
