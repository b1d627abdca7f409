#include "engine/panel.h"

#include <imgui.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <utility>

#include "engine/key_map.h"
#include "engine/presets.h"
#include "engine/view_control.h"

namespace fp::engine {

namespace {

// The table's groups in panel order; a group the table gains later still shows, after these.
const char* const kGroupOrder[] = {"adaptivity", "splash", "solver", "time", "fluid", "robustness"};

/// One widget for any table's entry: the value's type picks the widget, the table's setter checks the range.
template <class S>
bool entryWidget(S& values, const sim::ParamEntry<S>& info, std::string& message) {
  using Table = sim::ParamTableOf<S>;
  const std::string label = info.key + (info.live ? "" : " *");
  std::string error;
  bool edited = false;
  // Widgets edit a copy; the table's setter stores it (or says why not).
  sim::visit(info, std::as_const(values),
             sim::Overloaded{
                 [&](double v) {
                   const double range = info.max - info.min;
                   const float speed = float(std::max(std::abs(v) * 0.005, std::min(range, 10.0) * 1e-3));
                   if (ImGui::DragScalar(label.c_str(), ImGuiDataType_Double, &v, speed, &info.min, &info.max,
                                         "%.4g", ImGuiSliderFlags_AlwaysClamp)) {
                     edited = true;
                     error = Table::setScalar(values, info, v);
                   }
                 },
                 [&](float v) {
                   const float range = float(info.max - info.min);
                   const float speed = std::max(std::abs(v) * 0.005f, std::min(range, 10.0f) * 1e-3f);
                   if (ImGui::DragFloat(label.c_str(), &v, speed, float(info.min), float(info.max), "%.4g",
                                        ImGuiSliderFlags_AlwaysClamp)) {
                     edited = true;
                     error = Table::setScalar(values, info, double(v));
                   }
                 },
                 [&](int v) {
                   if (ImGui::DragInt(label.c_str(), &v, 0.2f, int(info.min), int(info.max), "%d",
                                      ImGuiSliderFlags_AlwaysClamp)) {
                     edited = true;
                     error = Table::setScalar(values, info, double(v));
                   }
                 },
                 [&](bool v) {
                   if (ImGui::Checkbox(label.c_str(), &v)) {
                     edited = true;
                     error = Table::setScalar(values, info, v ? 1.0 : 0.0);
                   }
                 },
                 [&](std::uint64_t v) {
                   ImU64 u = ImU64(v);
                   if (ImGui::InputScalar(label.c_str(), ImGuiDataType_U64, &u)) {
                     edited = true;
                     error = Table::setScalar(values, info, double(u));
                   }
                 },
                 [&](std::array<double, 3> v) {
                   if (ImGui::DragScalarN(label.c_str(), ImGuiDataType_Double, v.data(), 3, 0.05f, &info.min,
                                          &info.max, "%.3g", ImGuiSliderFlags_AlwaysClamp)) {
                     edited = true;
                     error = Table::setVec3(values, info, v);
                   }
                 },
                 [&](const sim::Choice& c) {
                   int index = c.index;
                   std::vector<const char*> names;
                   for (const std::string& n : info.choices)
                     names.push_back(n.c_str());
                   if (ImGui::Combo(label.c_str(), &index, names.data(), int(names.size()))) {
                     edited = true;
                     error = Table::setScalar(values, info, double(index));
                   }
                 }});
  if (ImGui::IsItemHovered()) {
    ImGui::SetTooltip("%s [%s]\nrange [%g, %g]%s", info.description.c_str(), info.unit.c_str(), info.min,
                      info.max, info.live ? "" : "\n* applies on Reset (R)");
  }
  if (!error.empty())
    message = error;
  return edited && error.empty();
}

void plot(const char* label, const Series& s, const char* format, float lo = 0.0f) {
  char overlay[64];
  std::snprintf(overlay, sizeof(overlay), format, double(s.last()));
  const std::vector<float>& v = s.values();
  float hi = lo;
  for (float x : v)
    hi = std::max(hi, x);
  ImGui::PlotLines(label, v.empty() ? nullptr : v.data(), int(v.size()), 0, overlay, lo,
                   hi > lo ? hi * 1.1f : lo + 1.0f, ImVec2(0.0f, 36.0f));
}

void statistics(const AppSession& session) {
  const SessionStats& s = session.stats();
  plot("fps", s.fps, "%.1f frames/s");
  plot("ms/step", s.msPerStep, "%.2f ms per step");
  plot("particles", s.particles, "%.0f particles");
  plot("of uniform-high", s.highShare, "%.1f %% of uniform-high");
  plot("splits/s", s.splitsPerSecond, "%.0f splits per sim s");
  plot("merges/s", s.mergesPerSecond, "%.0f merges per sim s");
  plot("density err", s.densityError, "%.3f %% density error");
  plot("real time", s.realTimeFactor, "x %.2f real time");
  ImGui::TextWrapped("frame %.1f ms: %d steps, %.1f ms simulating, %.1f ms waited", s.frameMs, s.steps,
                     s.simMs, s.waitMs);
  ImGui::Text("sim time %.3f s, uniform-high count %.0f", session.simulation().time(), s.uniformHighCount);
}

void runControls(AppSession& session, PanelState& state) {
  const std::string current = std::filesystem::path(session.scenePath()).filename().string();
  if (ImGui::BeginCombo("scene", current.c_str())) {
    for (const std::string& path : state.scenes) {
      const std::string name = std::filesystem::path(path).filename().string();
      if (ImGui::Selectable(name.c_str(), name == current))
        session.requests().scenePath = path;
    }
    ImGui::EndCombo();
  }
  if (ImGui::Button(session.paused ? "Run (Space)" : "Pause (Space)"))
    session.paused = !session.paused;
  ImGui::SameLine();
  if (ImGui::Button("Step (N)")) {
    session.paused = true;
    session.requests().singleStep = true;
  }
  ImGui::SameLine();
  if (ImGui::Button("Reset (R)"))
    session.requests().reset = true;
  // issue 15: the state to come back to, and the way back
  ImGui::SameLine();
  if (ImGui::Button("Save state")) {
    try {
      session.saveStateNow();
      state.message = "state saved to " + session.savedStatePath();
    } catch (const sim::InputError& e) {
      state.message = e.what();
    }
  }
  if (!session.savedStatePath().empty()) {
    ImGui::SameLine();
    if (ImGui::Button("Reset to saved state"))
      session.requests().resetToSavedState = true;
  }
  float scale = float(session.timeScale);
  if (ImGui::SliderFloat("time scale", &scale, 0.05f, 4.0f, "%.2f", ImGuiSliderFlags_Logarithmic))
    session.timeScale = double(scale);
  ImGui::Checkbox("fixed step (1 frame = 1/frame rate)", &session.fixedStep);
  if (state.headset) {
    if (ImGui::Button("Recentre the tank (menu button)"))
      state.recentre = true;
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("moves the tank onto a table half a metre in front of the headset");
  }
  ImGui::Text("real-time factor %.2f%s", double(session.stats().realTimeFactor.last()),
              session.stats().realTimeFactor.last() < 0.95f * float(session.timeScale) ? " (slowed)" : "");
  if (ImGui::Button("Screenshot (F12)"))
    state.screenshot = true;
  ImGui::SameLine();
  ImGui::Checkbox("record frames (F9)", &state.recordFrames);
  ImGui::SameLine();
  ImGui::Checkbox("record video (F8)", &state.recordVideo);
  ImGui::SameLine();
  ImGui::Checkbox("fullscreen (F11)", &state.fullscreen);
  if (!session.error().empty())
    ImGui::TextColored(ImVec4(1, 0.4f, 0.3f, 1), "%s (R resets)", session.error().c_str());
  if (session.restartPending())
    ImGui::TextColored(ImVec4(1, 0.8f, 0.3f, 1), "parameters marked * apply on Reset");
  if (session.recovery().rollbacks > 0)  // issue 15: what the last rollback did
    ImGui::TextColored(ImVec4(1, 0.8f, 0.3f, 1), "%s", session.recovery().message.c_str());
}

void handControls(AppSession& session, PanelState& state) {
  input::MouseHand& hand = session.mouseHand();
  int g = int(hand.gesture().target());
  ImGui::RadioButton("flat (1)", &g, int(input::Gesture::Flat));
  ImGui::SameLine();
  ImGui::RadioButton("fist (2)", &g, int(input::Gesture::Fist));
  ImGui::SameLine();
  ImGui::RadioButton("point (3)", &g, int(input::Gesture::Point));
  hand.gesture().setTarget(input::Gesture(g));
  float size = float(session.handScale());
  if (ImGui::SliderFloat("hand size *", &size, 0.5f, 3.0f, "%.2f"))
    session.setHandScale(double(size));
  float turn = float(hand.yawOffset * 180.0 / M_PI);
  if (ImGui::SliderFloat("palm turn [deg]", &turn, -90.0f, 90.0f, "%.0f"))
    hand.yawOffset = double(turn) * M_PI / 180.0;
  const input::HandPose p = session.handPose();
  ImGui::Text("palm at (%.3f, %.3f, %.3f) m, grip %.2f, point %.2f", p.position.x(), p.position.y(),
              p.position.z(), p.grip, p.point);
  static char path[256];
  std::snprintf(path, sizeof(path), "%s", state.recordingPath.c_str());
  if (ImGui::InputText("recording", path, sizeof(path)))
    state.recordingPath = path;
  if (ImGui::Button(session.recording() ? "Stop and save (F5)" : "Record hand (F5)"))
    toggleHandRecording(session, state);
  ImGui::SameLine();
  if (ImGui::Button(session.replaying() ? "Stop replay (F6)" : "Replay file (F6)"))
    toggleHandReplay(session, state);
}

void renderControls(render::RenderSettings& s, std::string& message) {
  std::string group;
  for (const auto& info : render::RenderSettingsTable::get().entries()) {
    // the colour field only matters to the particle view
    if (info.key == "color_field" && s.view != render::RenderSettings::View::Particles)
      continue;
    if (info.group != group) {
      group = info.group;
      ImGui::TextDisabled("%s", group.c_str());
    }
    entryWidget(s, info, message);
  }
}

void presetControls(AppSession& session, PanelState& state, render::RenderSettings& settings) {
  static char path[256];
  std::snprintf(path, sizeof(path), "%s", state.presetPath.c_str());
  if (ImGui::InputText("preset file", path, sizeof(path)))
    state.presetPath = path;
  if (ImGui::Button("Save preset")) {
    try {
      savePreset(state.presetPath, Preset{session.mode(), session.editParams(), settings});
      state.message = "preset saved to " + state.presetPath;
    } catch (const sim::InputError& e) {
      state.message = e.what();
    }
  }
  ImGui::SameLine();
  if (ImGui::Button("Load preset")) {
    try {
      const Preset p = loadPreset(state.presetPath, Preset{session.mode(), session.editParams(), settings});
      session.editParams() = p.params;
      settings = p.render;
      if (p.mode != session.mode())
        session.requests().mode = p.mode;
      state.message = "preset loaded from " + state.presetPath;
    } catch (const sim::InputError& e) {
      state.message = e.what();
    }
  }
}

void modeSelector(AppSession& session) {
  static const sim::AdaptivityMode modes[] = {sim::AdaptivityMode::UniformLow,
                                              sim::AdaptivityMode::UniformHigh, sim::AdaptivityMode::Surface,
                                              sim::AdaptivityMode::FluidPlaying};
  if (ImGui::BeginCombo("mode", sim::modeName(session.mode()))) {
    for (sim::AdaptivityMode m : modes) {
      if (ImGui::Selectable(sim::modeName(m), m == session.mode()))
        session.requests().mode = m;
    }
    ImGui::EndCombo();
  }
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("changing the mode rebuilds the simulation from the scene");
}

void parameterGroup(AppSession& session, const std::string& group, std::string& message) {
  for (const sim::ParamInfo& info : sim::ParamTable::sim().entries()) {
    if (info.group == group)
      parameterWidget(session.editParams(), info, message);
  }
}

}  // namespace

bool parameterWidget(sim::SimParams& params, const sim::ParamInfo& info, std::string& message) {
  return entryWidget(params, info, message);
}

void drawPanel(AppSession& session, PanelState& state, render::RenderSettings& settings) {
  if (!state.visible)
    return;
  ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(440, 0), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSizeConstraints(ImVec2(300, 100), ImVec2(FLT_MAX, ImGui::GetIO().DisplaySize.y - 16));
  ImGui::Begin("FluidPlaying (Tab hides, F1 help)", &state.visible);
  ImGui::PushItemWidth(-170.0f);
  runControls(session, state);
  if (ImGui::CollapsingHeader("statistics", ImGuiTreeNodeFlags_DefaultOpen))
    statistics(session);
  if (!state.headset && ImGui::CollapsingHeader("hand"))
    handControls(session, state);
  std::vector<std::string> groups(std::begin(kGroupOrder), std::end(kGroupOrder));
  for (const sim::ParamInfo& info : sim::ParamTable::sim().entries()) {
    if (std::find(groups.begin(), groups.end(), info.group) == groups.end())
      groups.push_back(info.group);
  }
  for (const std::string& group : groups) {
    if (!ImGui::CollapsingHeader(group.c_str(), group == "adaptivity" ? ImGuiTreeNodeFlags_DefaultOpen : 0))
      continue;
    ImGui::PushID(group.c_str());
    if (group == "adaptivity")
      modeSelector(session);
    parameterGroup(session, group, state.message);
    ImGui::PopID();
  }
  if (ImGui::CollapsingHeader("rendering"))
    renderControls(settings, state.message);
  if (ImGui::CollapsingHeader("presets"))
    presetControls(session, state, settings);
  if (!state.message.empty())
    ImGui::TextWrapped("%s", state.message.c_str());
  ImGui::PopItemWidth();
  ImGui::End();
}

const std::vector<std::pair<const char*, const char*>>& controls() {
  static const std::vector<std::pair<const char*, const char*>> list = [] {
    std::vector<std::pair<const char*, const char*>> rows = ViewControl::controls();
    for (const KeyBinding& b : keyBindings())
      rows.emplace_back(b.name, b.help);
    return rows;
  }();
  return list;
}

const std::vector<std::pair<const char*, const char*>>& headsetControls() {
  static const std::vector<std::pair<const char*, const char*>> list = [] {
    std::vector<std::pair<const char*, const char*>> rows;
    for (const KeyBinding& b : keyBindings()) {
      if (!b.hand)
        rows.emplace_back(b.name, b.help);
    }
    return rows;
  }();
  return list;
}

void toggleHandRecording(AppSession& session, PanelState& state) {
  state.message = session.toggleRecording(state.recordingPath);
}

void toggleHandReplay(AppSession& session, PanelState& state) {
  if (std::string message = session.toggleReplay(state.recordingPath); !message.empty())
    state.message = std::move(message);
}

void drawHelp(PanelState& state) {
  if (!state.help)
    return;
  const ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x * 0.5f, io.DisplaySize.y * 0.5f), ImGuiCond_Always,
                          ImVec2(0.5f, 0.5f));
  ImGui::SetNextWindowBgAlpha(0.85f);
  ImGui::Begin("controls", &state.help, ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoCollapse);
  if (ImGui::BeginTable("keys", 2)) {
    for (const auto& [key, action] : state.headset ? headsetControls() : controls()) {
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(key);
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(action);
    }
    ImGui::EndTable();
  }
  ImGui::End();
}

}  // namespace fp::engine
