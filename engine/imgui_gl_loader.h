#pragma once
// Force-included into Debian's imgui_impl_opengl3.cpp (IMGUI_IMPL_OPENGL_LOADER_CUSTOM): its GL calls go
// through render/gl_api, loaded once per context by the renderer's loader.
#include "render/gl_api.h"
