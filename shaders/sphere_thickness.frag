#version 330 core
#include "common.glsl"
// Thickness pass at half resolution, blended additively: the water crossed by each pixel's ray, and the part
// of it that belongs to freshly split children (tinted red in the composite). Water behind the scene's opaque
// surfaces is left out by testing against the full-resolution scene depth.
flat in vec3 vCenter;
flat in float vRadius;
flat in float vHighlight;
flat in float vValue;
uniform mat4 uProj;
uniform vec2 uViewport;
uniform sampler2D uSceneDepth;  // full resolution, twice this pass's
out vec2 fThickness;

void main() {
  vec3 hit;
  float chord;
  if (!raySphere(viewRay(gl_FragCoord.xy, uViewport, uProj), vCenter, vRadius, hit, chord)) discard;
  // spheres on a lattice of spacing 2r fill pi/6 of the space: scale the summed chords back to water depth
  float t = chord * 1.9099;
  ivec2 full = min(ivec2(gl_FragCoord.xy) * 2, textureSize(uSceneDepth, 0) - 1);
  if (windowDepth(uProj, hit) > texelFetch(uSceneDepth, full, 0).x) discard;
  fThickness = vec2(t, t * vHighlight);
}
