#version 330 core
// Sphere impostors, one point sprite a particle, ray-cast per fragment (the fragment shaders use viewRay).
layout(location = 0) in vec3 aCenter;    // world [m]
layout(location = 1) in float aRadius;   // [m]
layout(location = 2) in float aSplitAge; // time since the particle's split [s], < 0: never split
layout(location = 3) in float aValue;    // colour-map coordinate in [0, 1] (particle view)
uniform mat4 uView;
uniform mat4 uProj;
uniform vec2 uViewport;       // size of the pass's viewport [px]
uniform float uMaxPointSize;  // the context's largest point size [px]
uniform float uSpriteScale;  // sprites this much larger than the sphere (room for the glass it wets)
uniform float uHighlightDuration;  // <= 0: no highlight
flat out vec3 vCenter;
flat out float vRadius;
flat out float vHighlight;
flat out float vValue;

void main() {
  vCenter = (uView * vec4(aCenter, 1.0)).xyz;
  vRadius = aRadius;
  bool fresh = uHighlightDuration > 0.0 && aSplitAge >= 0.0 && aSplitAge < uHighlightDuration;
  vHighlight = fresh ? 1.0 - aSplitAge / uHighlightDuration : 0.0;
  vValue = aValue;
  gl_Position = uProj * vec4(vCenter, 1.0);
  // One vertex a particle: four times less vertex work than a quad, which is what bounds a software rasteriser.
  // The silhouette seen off-axis is stretched by 1/cos of the angle to the view axis; 1.1 more holds it from
  // more than three radii away.
  float z = max(-vCenter.z, 1e-6);
  float stretch = min(length(vCenter) / z, 2.0);
  float diameter = 2.0 * vRadius * uProj[1][1] * 0.5 * uViewport.y / z;
  gl_PointSize = clamp(1.1 * uSpriteScale * stretch * diameter + 2.0, 1.0, uMaxPointSize);
}
