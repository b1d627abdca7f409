#version 330 core
// One direction of the narrow-range depth filter (Truong and Yuksel 2018): a Gaussian over samples within a
// depth range around the centre. Samples far in front belong to another sheet and are skipped; samples far
// behind are clamped to the range; background samples are skipped, so silhouettes stay where they are.
// The filter is as wide as a few radii of the centre's particle, so fine and coarse particles are smoothed at
// their own scale.
in vec2 vUv;
uniform sampler2D uDepth;   // RG: eye depth [m] (0: no fluid), particle radius [m]
uniform ivec2 uDirection;   // (1, 0) or (0, 1)
uniform float uPixelsPerMetre;  // at eye depth 1 m
uniform float uRadius;      // half-width in particle radii
uniform float uMaxPixels;   // cap on the half-width
uniform float uRange;       // kept depth range in particle radii
out vec2 fDepth;

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  ivec2 last = textureSize(uDepth, 0) - 1;
  vec2 c = texelFetch(uDepth, p, 0).xy;
  if (c.x <= 0.0) {
    fDepth = c;
    return;
  }
  float halfWidth = min(uMaxPixels, uRadius * c.y * uPixelsPerMetre / c.x);
  int n = int(ceil(halfWidth));
  float sigma = max(0.5 * halfWidth, 0.5);
  float range = uRange * c.y;
  float sum = 0.0;
  float weights = 0.0;
  for (int i = -n; i <= n; ++i) {
    float z = texelFetch(uDepth, clamp(p + i * uDirection, ivec2(0), last), 0).x;
    if (z <= 0.0 || z < c.x - range) continue;
    z = min(z, c.x + range);
    float w = exp(-float(i * i) / (2.0 * sigma * sigma));
    sum += w * z;
    weights += w;
  }
  fDepth = vec2(sum / weights, c.y);
}
