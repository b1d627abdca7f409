#version 330 core
// Back to full resolution after the half-resolution filter: the filtered inverse depth interpolated
// bilinearly from the four nearest half-resolution texels that hold water within the filter's range of this
// pixel's own sphere depth. The outline of the water stays the full-resolution one: a pixel without a sphere
// stays empty, and one whose neighbourhood holds no such texel keeps its own depth. Pinholes excepted: a
// pixel that looks through a gap between the spheres of the surface (it sees water more than uHoleDepth fine
// radii behind all four texels around it) takes the filtered surface; left as they were, a few such pixels
// turned normals by 60-90 degrees and doubled the rms angle of a resting surface made of particles of two
// sizes. (Gaps that show no water at all are left: filling them changed no figure.)
in vec2 vUv;
uniform sampler2D uDepth;     // full resolution, RG: eye depth [m] (0: no fluid), particle radius [m]
uniform sampler2D uFiltered;  // half resolution, filtered, same layout
uniform float uRange;         // kept depth range in fine particle radii
uniform float uFineRadius;    // [m]
uniform float uHoleDepth;     // in fine radii; 0: no hole is filled
out vec2 fDepth;

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec2 c = texelFetch(uDepth, p, 0).xy;
  if (c.x <= 0.0) {
    fDepth = c;
    return;
  }
  ivec2 last = textureSize(uFiltered, 0) - 1;
  // this pixel's centre in half-resolution texel coordinates: texel i covers pixels 2i and 2i + 1
  vec2 t = (vec2(p) + 0.5) * 0.5 - 0.5;
  ivec2 i0 = ivec2(floor(t));
  vec2 f = t - vec2(i0);
  float w0 = 1.0 / c.x;
  float range = uRange * uFineRadius * w0 * w0;
  float sum = 0.0;
  float weights = 0.0;
  // the interpolation over every texel with water, and the farthest of them
  float sumAll = 0.0;
  float weightsAll = 0.0;
  float farthest = 1e30;  // inverse depth
  float radius = 0.0;
  int texels = 0;
  for (int k = 0; k < 4; ++k) {
    ivec2 o = ivec2(k & 1, k >> 1);
    vec2 s = texelFetch(uFiltered, clamp(i0 + o, ivec2(0), last), 0).xy;
    float w = (o.x == 1 ? f.x : 1.0 - f.x) * (o.y == 1 ? f.y : 1.0 - f.y);
    if (s.x <= 0.0) continue;
    ++texels;
    float wz = 1.0 / s.x;
    if (wz < farthest) {
      farthest = wz;
      radius = s.y;
    }
    sumAll += w * wz;
    weightsAll += w;
    if (abs(wz - w0) < range && w > 0.0) {
      sum += w * wz;
      weights += w;
    }
  }
  bool hole = uHoleDepth > 0.0 && texels == 4 && c.x - 1.0 / farthest > uHoleDepth * uFineRadius;
  if (hole)
    fDepth = vec2(weightsAll / sumAll, radius);
  else
    fDepth = weights > 0.0 ? vec2(weights / sum, c.y) : c;
}
