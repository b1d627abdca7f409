#include "engine/imgui_layer.h"

// gl_api first: it brings GLEW, which must precede any other GL header (GLFW's included)
#include "render/gl_api.h"
// clang-format off
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>
// clang-format on

#include "engine/gl_window.h"

namespace fp::engine {

ImGuiLayer::ImGuiLayer(GlWindow& window) {
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini dropped into the working directory
  ImGui::StyleColorsDark();
  ImGui::GetStyle().Alpha = 0.95f;
  ImGui_ImplGlfw_InitForOpenGL(window.handle(), true);
  if (!ImGui_ImplOpenGL3_Init("#version 330 core")) {
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
    throw WindowUnavailable("the ImGui OpenGL3 back-end cannot start on this context");
  }
}

ImGuiLayer::~ImGuiLayer() {
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
}

void ImGuiLayer::newFrame() {
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
}

int ImGuiLayer::render() {
  ImGui::Render();
  ImDrawData* data = ImGui::GetDrawData();
  ImGui_ImplOpenGL3_RenderDrawData(data);
  return data ? data->TotalVtxCount : 0;
}

void ImGuiLayer::renderAgain() {
  if (ImDrawData* data = ImGui::GetDrawData())
    ImGui_ImplOpenGL3_RenderDrawData(data);
}

}  // namespace fp::engine
