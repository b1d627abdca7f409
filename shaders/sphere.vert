#version 330 core
// Sphere impostors, one instance a particle: a camera-facing quad through the centre, ray-cast per fragment.
layout(location = 0) in vec3 aCenter;    // world [m]
layout(location = 1) in float aRadius;   // [m]
layout(location = 2) in float aSplitAge; // time since the particle's split [s], < 0: never split
layout(location = 3) in float aValue;    // colour-map coordinate in [0, 1] (particle view)
uniform mat4 uView;
uniform mat4 uProj;
uniform float uRadiusScale;
uniform float uHighlightDuration;  // <= 0: no highlight
out vec3 vViewPos;
flat out vec3 vCenter;
flat out float vRadius;
flat out float vHighlight;
flat out float vValue;

void main() {
  vec2 corner = vec2(float(gl_VertexID & 1), float(gl_VertexID >> 1)) * 2.0 - 1.0;
  vCenter = (uView * vec4(aCenter, 1.0)).xyz;
  vRadius = aRadius * uRadiusScale;
  // 1.3 radii hold the perspective silhouette of a sphere seen from more than three radii away
  vViewPos = vCenter + vec3(corner * (1.3 * vRadius), 0.0);
  bool fresh = uHighlightDuration > 0.0 && aSplitAge >= 0.0 && aSplitAge < uHighlightDuration;
  vHighlight = fresh ? 1.0 - aSplitAge / uHighlightDuration : 0.0;
  vValue = aValue;
  gl_Position = uProj * vec4(vViewPos, 1.0);
}
