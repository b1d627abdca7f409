#version 330 core
#include "common.glsl"
// Thickness pass, blended additively: the water crossed by each pixel's ray, and the part of it that belongs to
// freshly split children (tinted red in the composite).
in vec3 vViewPos;
flat in vec3 vCenter;
flat in float vRadius;
flat in float vHighlight;
flat in float vValue;
uniform mat4 uProj;
out vec2 fThickness;

void main() {
  vec3 hit;
  float chord;
  if (!raySphere(vViewPos, vCenter, vRadius, hit, chord)) discard;
  // spheres on a lattice of spacing 2r fill pi/6 of the space: scale the summed chords back to water depth
  float t = chord * 1.9099;
  fThickness = vec2(t, t * vHighlight);
  gl_FragDepth = windowDepth(uProj, hit);
}
