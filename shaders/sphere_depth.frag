#version 330 core
#include "common.glsl"
// Depth pass: the eye depth of the nearest sphere surface and that sphere's radius (for the filter).
flat in vec3 vCenter;
flat in float vRadius;
flat in float vHighlight;
flat in float vValue;
uniform mat4 uProj;
uniform vec2 uViewport;
out vec2 fDepth;

void main() {
  vec3 hit;
  float chord;
  if (!raySphere(viewRay(gl_FragCoord.xy, uViewport, uProj), vCenter, vRadius, hit, chord)) discard;
  fDepth = vec2(-hit.z, vRadius);
  gl_FragDepth = windowDepth(uProj, hit);
}
