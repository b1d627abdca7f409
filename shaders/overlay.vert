#version 330 core
// Screen-space overlay (the legend) in pixels from the top-left of the viewport.
layout(location = 0) in vec2 aPixel;
layout(location = 1) in vec4 aColor;
layout(location = 2) in float aMap;  // >= 0: take the colour from the colour map at this coordinate
uniform vec2 uViewport;
out vec4 vColor;
out float vMap;

void main() {
  vColor = aColor;
  vMap = aMap;
  gl_Position = vec4(aPixel.x / uViewport.x * 2.0 - 1.0, 1.0 - aPixel.y / uViewport.y * 2.0, 0.0, 1.0);
}
