// Shared by the renderer's shaders through #include "common.glsl": the environment, the sphere impostor and the
// colour map.

// Direction towards the sun, world space, unit length.
const vec3 kSunDir = vec3(0.4082483, 0.8164966, 0.4082483);
const vec3 kSunColor = vec3(1.0, 0.95, 0.85);

// The environment: a sky gradient above the horizon, a dim ground below it, and the sun.
vec3 skyColor(vec3 dir) {
  vec3 d = normalize(dir);
  vec3 zenith = vec3(0.22, 0.42, 0.78);
  vec3 horizon = vec3(0.78, 0.85, 0.93);
  vec3 ground = vec3(0.32, 0.31, 0.29);
  vec3 c = d.y > 0.0 ? mix(horizon, zenith, pow(d.y, 0.6)) : mix(horizon, ground, pow(-d.y, 0.35));
  float s = max(dot(d, kSunDir), 0.0);
  return c + kSunColor * (pow(s, 800.0) * 6.0 + pow(s, 24.0) * 0.12);
}

// A point on the view ray through window position `fragCoord` of a viewport `viewport` pixels large (view
// space, perspective camera at the origin, any off-centre projection).
vec3 viewRay(vec2 fragCoord, vec2 viewport, mat4 proj) {
  vec2 ndc = fragCoord / viewport * 2.0 - 1.0;
  return vec3((ndc.x + proj[2][0]) / proj[0][0], (ndc.y + proj[2][1]) / proj[1][1], -1.0);
}

// The view ray through `p` (view space, perspective camera at the origin) against the sphere (c, r): false on
// a miss, else the nearer hit and the length of the chord inside the sphere.
bool raySphere(vec3 p, vec3 c, float r, out vec3 hit, out float chord) {
  vec3 d = normalize(p);
  float b = dot(d, c);
  float h = b * b - dot(c, c) + r * r;
  if (h < 0.0) {
    hit = vec3(0.0);
    chord = 0.0;
    return false;
  }
  h = sqrt(h);
  hit = d * (b - h);
  chord = 2.0 * h;
  return true;
}

// Window depth in [0, 1] of a view-space point under projection `proj` and the default depth range.
float windowDepth(mat4 proj, vec3 p) {
  vec4 clip = proj * vec4(p, 1.0);
  return 0.5 * clip.z / clip.w + 0.5;
}

// Viridis colour map (polynomial fit), t in [0, 1].
vec3 viridis(float t) {
  const vec3 c0 = vec3(0.2777273272234177, 0.005407344544966578, 0.3340998053353061);
  const vec3 c1 = vec3(0.1050930431085774, 1.404613529898575, 1.384590162594685);
  const vec3 c2 = vec3(-0.3308618287255563, 0.214847559468213, 0.09509516302823659);
  const vec3 c3 = vec3(-4.634230498983486, -5.799100973351585, -19.33244095627987);
  const vec3 c4 = vec3(6.228269936347081, 14.17993336680509, 56.69055260068105);
  const vec3 c5 = vec3(4.776384997670288, -13.74514537774601, -65.35303263337234);
  const vec3 c6 = vec3(-5.435455855934631, 4.645852612178535, 26.3124352495832);
  t = clamp(t, 0.0, 1.0);
  return c0 + t * (c1 + t * (c2 + t * (c3 + t * (c4 + t * (c5 + t * c6)))));
}
