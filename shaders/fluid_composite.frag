#version 330 core
#include "common.glsl"
// Shading of the water from the filtered depth and the thickness: normals from depth differences, Fresnel
// reflection of the environment, refraction of the scene behind, Beer-Lambert absorption, a sun highlight, and
// the red tint of freshly split children. Pixels without water pass the scene through.
in vec2 vUv;
uniform sampler2D uSceneColor;
uniform sampler2D uSceneDepth;  // window depth of the scene
uniform sampler2D uFluidDepth;  // RG: filtered eye depth [m] (0: none), particle radius [m]
uniform sampler2D uThickness;   // half resolution: water crossed [m], of it freshly split [m], in RG or BA
uniform bool uThicknessInBA;    // the half-resolution filter's texture, thickness smoothed
uniform mat4 uProj;
uniform mat4 uInvView;
uniform vec3 uAbsorption;       // [1/m]
uniform float uRefraction;      // offset at full thickness [uv]
uniform float uFineRadius;      // [m]
uniform float uHighlightDensity;  // [1/m]
out vec4 fColor;

ivec2 gSize;

vec3 viewPosition(ivec2 p, float z) {
  vec2 ndc = (vec2(p) + 0.5) / vec2(gSize) * 2.0 - 1.0;
  return vec3((ndc.x + uProj[2][0]) * z / uProj[0][0], (ndc.y + uProj[2][1]) * z / uProj[1][1], -z);
}

float depthAt(ivec2 p) {
  return texelFetch(uFluidDepth, clamp(p, ivec2(0), gSize - 1), 0).x;
}

// The difference towards the neighbour with the smaller depth step, so normals do not bend over an edge.
vec3 difference(ivec2 p, vec3 center, ivec2 step) {
  float zf = depthAt(p + step);
  float zb = depthAt(p - step);
  vec3 forward = zf > 0.0 ? viewPosition(p + step, zf) - center : vec3(0.0);
  vec3 backward = zb > 0.0 ? center - viewPosition(p - step, zb) : vec3(0.0);
  if (zf <= 0.0) return backward;
  if (zb <= 0.0) return forward;
  return abs(forward.z) < abs(backward.z) ? forward : backward;
}

void main() {
  gSize = textureSize(uFluidDepth, 0);
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec2 fluid = texelFetch(uFluidDepth, p, 0).xy;
  if (fluid.x <= 0.0) {
    fColor = texelFetch(uSceneColor, p, 0);
    gl_FragDepth = texelFetch(uSceneDepth, p, 0).x;
    return;
  }
  vec3 pos = viewPosition(p, fluid.x);
  vec3 n = cross(difference(p, pos, ivec2(1, 0)), difference(p, pos, ivec2(0, 1)));
  n = dot(n, n) > 0.0 ? normalize(n) : vec3(0.0, 0.0, 1.0);
  vec3 v = normalize(-pos);
  if (dot(n, v) < 0.0) n = -n;

  vec2 uv = (vec2(p) + 0.5) / vec2(gSize);
  vec4 t4 = textureLod(uThickness, uv, 0.0);
  vec2 thickness = uThicknessInBA ? t4.zw : t4.xy;
  // the offset saturates over 8 fine radii of water, whatever the size of the particle in front
  vec2 refracted = uv - n.xy * uRefraction * (1.0 - exp(-thickness.x / (8.0 * uFineRadius)));
  vec3 behind = textureLod(uSceneColor, clamp(refracted, vec2(0.0), vec2(1.0)), 0.0).rgb;
  vec3 transmitted = exp(-uAbsorption * thickness.x);
  vec3 deep = vec3(0.02, 0.16, 0.24);  // light scattered back by deep water
  vec3 body = behind * transmitted + deep * (1.0 - transmitted);
  // children seen through the water: a red tint that grows with their share of the path, never opaque paint
  float red = 0.8 * (1.0 - exp(-uHighlightDensity * thickness.y));
  body = mix(body, vec3(0.86, 0.07, 0.05) * (0.55 + 0.45 * transmitted.g), red);

  vec3 nw = mat3(uInvView) * n;
  vec3 vw = mat3(uInvView) * v;
  float fresnel = 0.02 + 0.98 * pow(1.0 - max(dot(n, v), 0.0), 5.0);
  vec3 reflection = skyColor(reflect(-vw, nw));
  float spec = pow(max(dot(nw, normalize(kSunDir + vw)), 0.0), 400.0);
  vec3 c = mix(body, reflection, fresnel) + 1.5 * spec * kSunColor;
  fColor = vec4(c, 1.0);
  gl_FragDepth = windowDepth(uProj, pos);
}
