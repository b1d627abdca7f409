#version 330 core
#include "common.glsl"
// The floor: a filtered checkerboard of tiles uTile wide that fades into the environment far from the scene.
in vec3 vWorld;
in vec3 vNormal;
in vec3 vLocal;
uniform float uTile;
uniform vec3 uCenter;
uniform float uFadeRadius;
uniform vec3 uEye;
out vec4 fColor;

void main() {
  vec2 p = vWorld.xz / uTile;
  vec2 w = fwidth(p) + 1e-4;
  // box-filtered checker: no moire towards the horizon
  vec2 i = 2.0 * (abs(fract((p - 0.5 * w) * 0.5) - 0.5) - abs(fract((p + 0.5 * w) * 0.5) - 0.5)) / w;
  float checker = 0.5 - 0.5 * i.x * i.y;
  vec3 base = mix(vec3(0.70, 0.69, 0.66), vec3(0.60, 0.59, 0.56), checker);
  vec3 lit = base * (0.55 * skyColor(vec3(0.0, 1.0, 0.0)) + 0.6 * kSunDir.y * kSunColor);
  float d = length(vWorld.xz - uCenter.xz) / uFadeRadius;
  // fade into the environment seen in the same direction, so the floor has no visible edge
  fColor = vec4(mix(lit, skyColor(vWorld - uEye), smoothstep(0.4, 1.0, d)), 1.0);
}
