#version 330 core
// One direction of the thickness blur at half resolution: a Gaussian of `uBlur` fine radii (in world space at
// the water's depth there). The thickness summed from spheres shows the particles' lattice, and coarse
// particles show it as blotches of their own large spacing in the water's colour and refraction; smoothed over
// a width set by the finest radius, fine and coarse particles give the same colour. The part of freshly split
// children (G) stays as drawn.
in vec2 vUv;
uniform sampler2D uThickness;  // half resolution, RG: water crossed [m], of it freshly split [m]
uniform sampler2D uDepth;      // full resolution, RG: eye depth [m] (0: no fluid), particle radius [m]
uniform ivec2 uDirection;      // (1, 0) or (0, 1)
uniform float uPixelsPerMetre; // of this pass, at eye depth 1 m
uniform float uBlur;           // sigma in fine particle radii
uniform float uFineRadius;     // [m]
uniform int uMaxTaps;          // most samples a side
out vec2 fThickness;

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec2 c = texelFetch(uThickness, p, 0).xy;
  float z = texelFetch(uDepth, min(p * 2, textureSize(uDepth, 0) - 1), 0).x;
  if (c.x <= 0.0 || z <= 0.0) {
    fThickness = c;
    return;
  }
  ivec2 last = textureSize(uThickness, 0) - 1;
  float sigma = uBlur * uFineRadius * uPixelsPerMetre / z;
  int n = min(int(ceil(2.0 * sigma)), uMaxTaps);
  float stride = max(2.0 * sigma / float(max(n, 1)), 1.0);
  float sum = c.x;
  float weights = 1.0;
  for (int i = 1; i <= n; ++i) {
    float x = floor(float(i) * stride + 0.5);
    ivec2 o = int(x) * uDirection;
    float w = exp(-x * x / (2.0 * sigma * sigma));
    sum += w * (texelFetch(uThickness, clamp(p + o, ivec2(0), last), 0).x +
                texelFetch(uThickness, clamp(p - o, ivec2(0), last), 0).x);
    weights += 2.0 * w;
  }
  fThickness = vec2(sum / weights, c.y);
}
