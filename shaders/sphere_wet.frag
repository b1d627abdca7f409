#version 330 core
#include "common.glsl"
// Depth pass, second draw: water wets the glass. A sphere within uWetReach radii of a side of
// the container (chosen by the renderer) wets the disc of the glass in front of it, 1.5 radii wide so
// that a lattice of spacing 2r covers the glass without gaps: where the view ray enters the container there
// and passes near the sphere, the water's surface is the glass itself, flat, not the bumps of the lattice
// behind it. Drawn after sphere_depth.frag into the same target, nearer, so the depth test keeps it.
flat in vec3 vCenter;
flat in float vRadius;
flat in float vHighlight;
flat in float vValue;
uniform mat4 uProj;
uniform vec2 uViewport;
uniform mat4 uViewToContainer;  // view space to the container's local frame
uniform vec3 uContainerHalf;    // inner half extents [m]
uniform float uWetReach;        // how far inside the glass a sphere's centre still wets it, in its radii
out vec2 fDepth;

// The distance along the unit view ray `d` at which it enters the container through a side, or -1; `gap`: how
// far the point `c` (view space) lies inside that side.
float glassEntry(vec3 d, vec3 c, out float gap) {
  vec3 o = (uViewToContainer * vec4(0.0, 0.0, 0.0, 1.0)).xyz;
  vec3 dl = mat3(uViewToContainer) * d;
  vec3 cl = (uViewToContainer * vec4(c, 1.0)).xyz;
  vec3 inv = 1.0 / dl;
  vec3 t0 = (-uContainerHalf - o) * inv;
  vec3 t1 = (uContainerHalf - o) * inv;
  vec3 tn = min(t0, t1);
  vec3 tf = max(t0, t1);
  float tin = max(max(tn.x, tn.y), tn.z);
  float tout = min(min(tf.x, tf.y), tf.z);
  gap = 1e30;
  if (tin <= 0.0 || tin > tout) return -1.0;
  vec3 inside = uContainerHalf - abs(cl);
  if (tin == tn.x) gap = inside.x;
  else if (tin == tn.z) gap = inside.z;
  else return -1.0;  // the bottom is seen from below only, the open top is no glass
  return tin;
}

void main() {
  vec3 d = normalize(viewRay(gl_FragCoord.xy, uViewport, uProj));
  float gap;
  float tin = glassEntry(d, vCenter, gap);
  float miss = length(vCenter - d * dot(vCenter, d));
  if (tin <= 0.0 || gap >= uWetReach * vRadius || miss >= 1.5 * vRadius ||
      distance(d * tin, vCenter) >= (uWetReach + 1.0) * vRadius)
    discard;
  vec3 hit = d * tin;
  fDepth = vec2(-hit.z, vRadius);
  gl_FragDepth = windowDepth(uProj, hit);
}
