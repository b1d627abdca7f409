#version 330 core
// One direction of the depth filter: a narrow-range filter (after Truong and Yuksel 2018) taken over mirrored
// pairs of samples in inverse depth. For a plane, 1/z is linear across the screen, so the mean of the samples
// at +i and -i equals the centre's and a plane stays a plane at any slope, however grazing the view; the
// one-sided range test of the original filter bends planes seen at grazing angles. A pair whose mean lies far
// in front of the centre belongs to another sheet and is skipped, one far behind is clamped to the range, a
// pair with a background sample is skipped: silhouettes stay where they are.
// The width is set by the finest particle radius in world space, the same for fine and coarse particles, so
// the surface has one smoothing scale where resolutions meet.
// At half resolution the texture also holds the thickness (B; A: its freshly split part, kept as drawn): the
// same taps blur it with a Gaussian of uThicknessBlur fine radii, so that coarse particles, whose summed
// chords show their large spacing as blotches, give the water the colour fine ones give.
in vec2 vUv;
uniform sampler2D uDepth;       // RG: eye depth [m] (0: no fluid), particle radius [m]; BA: thickness
uniform ivec2 uDirection;       // (1, 0) or (0, 1)
uniform float uPixelsPerMetre;  // at eye depth 1 m
uniform float uRadius;          // half-width in fine particle radii
uniform float uFineRadius;      // [m]
uniform float uMaxPixels;       // cap on the half-width
uniform float uRange;           // kept depth range in fine particle radii
uniform int uMaxTaps;           // most sample pairs a pixel
uniform float uThicknessBlur;   // sigma of the thickness blur in fine radii, 0: none
out vec4 fDepth;

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  ivec2 last = textureSize(uDepth, 0) - 1;
  vec4 c = texelFetch(uDepth, p, 0);
  if (c.x <= 0.0) {
    fDepth = c;
    return;
  }
  float halfWidth = min(uMaxPixels, uRadius * uFineRadius * uPixelsPerMetre / c.x);
  // at most uMaxTaps pairs: a wide filter samples every stride-th pixel (the next pass smooths the rest)
  int n = min(int(ceil(halfWidth)), uMaxTaps);
  float stride = max(halfWidth / float(n), 1.0);
  float sigma = max(0.5 * halfWidth, 0.5);
  float w0 = 1.0 / c.x;
  // the range in inverse depth: d(1/z) = dz / z^2
  float range = uRange * uFineRadius * w0 * w0;
  float sum = 0.0;
  float weights = 1.0;
  float sigmaT = max(uThicknessBlur * uFineRadius * uPixelsPerMetre / c.x, 1e-3);
  float tsum = c.z;
  float tweights = 1.0;
  for (int i = 1; i <= n; ++i) {
    float x = floor(float(i) * stride + 0.5);
    ivec2 o = int(x) * uDirection;
    vec4 a = texelFetch(uDepth, clamp(p + o, ivec2(0), last), 0);
    vec4 b = texelFetch(uDepth, clamp(p - o, ivec2(0), last), 0);
    float wt = uThicknessBlur > 0.0 ? exp(-x * x / (2.0 * sigmaT * sigmaT)) : 0.0;
    tsum += wt * (a.z + b.z);
    tweights += 2.0 * wt;
    float za = a.x;
    float zb = b.x;
    if (za <= 0.0 || zb <= 0.0) continue;
    // deviation of the pair's mean from the centre, in inverse depth (> 0: in front)
    float d = 0.5 * (1.0 / za + 1.0 / zb) - w0;
    if (d > range) continue;
    d = max(d, -range);
    float w = exp(-x * x / (2.0 * sigma * sigma));
    sum += 2.0 * w * d;
    weights += 2.0 * w;
  }
  fDepth = vec4(1.0 / (w0 + sum / weights), c.y, tsum / tweights, c.w);
}
