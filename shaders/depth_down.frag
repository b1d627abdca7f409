#version 330 core
// The depth filter runs at half resolution: this pass reduces each 2x2 block of the sphere depth to one texel,
// the mean inverse depth of the block's samples within the filter's range of the nearest one (for a plane the
// value at the block's centre) and the nearest sample's radius. A block without water has no depth. The
// thickness (same resolution) comes along in B and A, so the filter smooths it with the depth.
in vec2 vUv;
uniform sampler2D uDepth;  // full resolution, RG: eye depth [m] (0: no fluid), particle radius [m]
uniform sampler2D uThickness;  // half resolution, RG: water crossed [m], of it freshly split [m]
uniform float uRange;      // kept depth range in fine particle radii
uniform float uFineRadius; // [m]
out vec4 fDepth;  // eye depth, radius, water crossed, of it freshly split

void main() {
  ivec2 base = ivec2(gl_FragCoord.xy) * 2;
  ivec2 last = textureSize(uDepth, 0) - 1;
  vec2 s[4];
  s[0] = texelFetch(uDepth, min(base, last), 0).xy;
  s[1] = texelFetch(uDepth, min(base + ivec2(1, 0), last), 0).xy;
  s[2] = texelFetch(uDepth, min(base + ivec2(0, 1), last), 0).xy;
  s[3] = texelFetch(uDepth, min(base + ivec2(1, 1), last), 0).xy;
  vec2 nearest = vec2(0.0);
  for (int k = 0; k < 4; ++k) {
    if (s[k].x > 0.0 && (nearest.x <= 0.0 || s[k].x < nearest.x)) nearest = s[k];
  }
  vec2 thickness = texelFetch(uThickness, ivec2(gl_FragCoord.xy), 0).xy;
  if (nearest.x <= 0.0) {
    fDepth = vec4(0.0, 0.0, thickness);
    return;
  }
  float w0 = 1.0 / nearest.x;
  float range = uRange * uFineRadius * w0 * w0;
  float sum = 0.0;
  float n = 0.0;
  for (int k = 0; k < 4; ++k) {
    if (s[k].x > 0.0 && w0 - 1.0 / s[k].x < range) {
      sum += 1.0 / s[k].x;
      n += 1.0;
    }
  }
  fDepth = vec4(n / sum, nearest.y, thickness);
}
