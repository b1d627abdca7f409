#version 330 core
#include "common.glsl"
// Opaque colliders (propeller, hand): sky ambient, sun diffuse and a highlight, lit from both sides.
in vec3 vWorld;
in vec3 vNormal;
in vec3 vLocal;
uniform vec3 uColor;
uniform vec3 uEye;
uniform float uShininess;
out vec4 fColor;

void main() {
  vec3 n = normalize(vNormal);
  vec3 v = normalize(uEye - vWorld);
  if (dot(n, v) < 0.0) n = -n;
  vec3 ambient = 0.45 * skyColor(n);
  float diffuse = max(dot(n, kSunDir), 0.0);
  float spec = pow(max(dot(n, normalize(kSunDir + v)), 0.0), uShininess);
  vec3 c = uColor * (ambient + 0.75 * diffuse * kSunColor) + 0.35 * spec * kSunColor;
  fColor = vec4(c, 1.0);
}
