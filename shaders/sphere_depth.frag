#version 330 core
#include "common.glsl"
// Depth pass: the eye depth of the nearest sphere surface and that sphere's radius (for the filter).
in vec3 vViewPos;
flat in vec3 vCenter;
flat in float vRadius;
flat in float vHighlight;
flat in float vValue;
uniform mat4 uProj;
out vec2 fDepth;

void main() {
  vec3 hit;
  float chord;
  if (!raySphere(vViewPos, vCenter, vRadius, hit, chord)) discard;
  fDepth = vec2(-hit.z, vRadius);
  gl_FragDepth = windowDepth(uProj, hit);
}
