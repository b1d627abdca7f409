#version 330 core
#include "common.glsl"
in vec4 vColor;
in float vMap;
out vec4 fColor;

void main() {
  fColor = vMap >= 0.0 ? vec4(viridis(vMap), 1.0) : vColor;
}
