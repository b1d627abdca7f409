#version 330 core
#include "common.glsl"
// The container: clear glass that reflects the sky more at grazing angles, with darker edges so the box reads.
in vec3 vWorld;
in vec3 vNormal;
in vec3 vLocal;
uniform vec3 uEye;
uniform vec3 uHalfExtents;
uniform float uEdgeWidth;
out vec4 fColor;

void main() {
  vec3 n = normalize(vNormal);
  vec3 v = normalize(uEye - vWorld);
  float nv = abs(dot(n, v));
  float fresnel = 0.04 + 0.96 * pow(1.0 - nv, 5.0);
  vec3 reflection = skyColor(reflect(-v, dot(n, v) < 0.0 ? -n : n));
  vec3 near = step(uHalfExtents - abs(vLocal), vec3(uEdgeWidth));
  bool edge = near.x + near.y + near.z >= 2.0;
  vec3 c = mix(vec3(0.80, 0.90, 0.94), reflection, 0.6);
  float alpha = 0.06 + 0.55 * fresnel;
  if (edge) {
    c = vec3(0.45, 0.55, 0.60);
    alpha = 0.75;
  }
  fColor = vec4(c, alpha);
}
