#version 330 core
#include "common.glsl"
// The environment behind everything.
in vec2 vUv;
uniform mat4 uProj;
uniform mat4 uInvView;
out vec4 fColor;

void main() {
  vec2 ndc = vUv * 2.0 - 1.0;
  vec3 dirView = vec3((ndc.x + uProj[2][0]) / uProj[0][0], (ndc.y + uProj[2][1]) / uProj[1][1], -1.0);
  fColor = vec4(skyColor(mat3(uInvView) * dirView), 1.0);
}
