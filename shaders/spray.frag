#version 330 core
#include "common.glsl"
// Spray: small clear droplets that reflect the sky and fade towards their rim, and foam where a droplet
// lies on the water (within a few radii of the filtered surface): white, soft and more opaque. Blended
// over the water.
flat in vec3 vCenter;
flat in float vRadius;
flat in float vHighlight;
flat in float vValue;
uniform mat4 uProj;
uniform mat4 uInvView;
uniform vec2 uViewport;
uniform sampler2D uFluidDepth;  // RG: filtered eye depth of the water [m] (0: none), particle radius
uniform float uFoamDepth;       // droplets closer than this to the water surface are foam [m]
out vec4 fColor;

void main() {
  vec3 hit;
  float chord;
  if (!raySphere(viewRay(gl_FragCoord.xy, uViewport, uProj), vCenter, vRadius, hit, chord)) discard;
  float core = chord / (2.0 * vRadius);  // 1 at the centre, 0 at the rim
  float water = texelFetch(uFluidDepth, ivec2(gl_FragCoord.xy), 0).x;
  float foam = water > 0.0 ? 1.0 - smoothstep(0.0, uFoamDepth, abs(-vCenter.z - water)) : 0.0;
  vec3 n = (hit - vCenter) / vRadius;
  vec3 v = normalize(-hit);
  float fresnel = 0.02 + 0.98 * pow(1.0 - max(dot(n, v), 0.0), 5.0);
  vec3 nw = mat3(uInvView) * n;
  vec3 vw = mat3(uInvView) * v;
  vec3 droplet = mix(vec3(0.55, 0.75, 0.85), skyColor(reflect(-vw, nw)), fresnel) +
                 kSunColor * pow(max(dot(nw, normalize(kSunDir + vw)), 0.0), 200.0);
  vec3 foamColor = vec3(0.92, 0.95, 0.97) * (0.85 + 0.15 * core);
  float alpha = mix(0.45 * smoothstep(0.0, 0.6, core) + 0.3 * fresnel, 0.8 * smoothstep(0.0, 0.8, core), foam);
  fColor = vec4(mix(droplet, foamColor, foam), alpha);
  gl_FragDepth = windowDepth(uProj, hit);
}
