#version 330 core
#include "common.glsl"
// Spray: small soft white droplets, blended over the water.
flat in vec3 vCenter;
flat in float vRadius;
flat in float vHighlight;
flat in float vValue;
uniform mat4 uProj;
uniform vec2 uViewport;
out vec4 fColor;

void main() {
  vec3 hit;
  float chord;
  if (!raySphere(viewRay(gl_FragCoord.xy, uViewport, uProj), vCenter, vRadius, hit, chord)) discard;
  float core = chord / (2.0 * vRadius);  // 1 at the centre, 0 at the rim
  fColor = vec4(vec3(0.96, 0.98, 1.0) * (0.8 + 0.2 * core), 0.9 * smoothstep(0.0, 0.5, core));
  gl_FragDepth = windowDepth(uProj, hit);
}
