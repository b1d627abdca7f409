#version 330 core
#include "common.glsl"
// Particle view: lit spheres coloured by the inspected quantity, or one debug colour (the spray's green).
flat in vec3 vCenter;
flat in float vRadius;
flat in float vHighlight;
flat in float vValue;
uniform mat4 uView;
uniform mat4 uProj;
uniform vec2 uViewport;
uniform vec4 uFlatColor;  // alpha > 0: this colour instead of the colour map
out vec4 fColor;

void main() {
  vec3 hit;
  float chord;
  if (!raySphere(viewRay(gl_FragCoord.xy, uViewport, uProj), vCenter, vRadius, hit, chord)) discard;
  vec3 n = (hit - vCenter) / vRadius;
  vec3 l = mat3(uView) * kSunDir;
  vec3 v = normalize(-hit);
  vec3 base = uFlatColor.a > 0.0 ? uFlatColor.rgb : viridis(vValue);
  float spec = pow(max(dot(n, normalize(l + v)), 0.0), 60.0);
  fColor = vec4(base * (0.35 + 0.65 * max(dot(n, l), 0.0)) + 0.25 * spec, 1.0);
  gl_FragDepth = windowDepth(uProj, hit);
}
