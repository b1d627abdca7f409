#pragma once
/// The ImGui panel: scene and mode, run controls, live statistics with plots, the hand, every simulation
/// parameter of the table grouped as the table groups them (built from sim::ParamTable, never listed by
/// hand), the render settings (built from render::RenderSettingsTable) and presets; and the help overlay with
/// the controls.

#include <string>
#include <utility>
#include <vector>

#include "engine/app_session.h"
#include "render/fluid_renderer.h"

namespace fp::engine {

/// What the panel keeps between frames and asks of the window.
struct PanelState {
  bool visible = true;                               ///< Tab
  bool help = false;                                 ///< F1 / H
  std::string presetPath = "preset.json";            ///< file of Save / Load preset
  std::string recordingPath = "hand_recording.csv";  ///< where a hand recording is saved
  std::string message;                               ///< one status line (saved files, errors)
  bool screenshot = false;                           ///< set by the button: write a screenshot this frame
  bool recordFrames = false;                         ///< write every frame's view as PNG
  bool recordVideo = false;                          ///< write every frame's view into video_NNN.mp4
  bool fullscreen = false;                           ///< toggled by the button or F11
  bool quit = false;                                 ///< Ctrl+Q: the window asks the loop to stop
  bool headset = false;             ///< the headset mode's mirror: no mouse hand, a Recentre button
  bool recentre = false;            ///< set by the Recentre button: place the tank in front of the head
  std::vector<std::string> scenes;  ///< scene files for the selector
};

/// Draws the panel; edits go to the session's parameters and requests and to the render settings.
void drawPanel(AppSession& session, PanelState& state, render::RenderSettings& settings);
/// Draws the help overlay when state.help is set.
void drawHelp(PanelState& state);
/// The mouse and keyboard controls: (input, action), as the help overlay and the README list them: the
/// mouse and held keys of engine/view_control, then the keys of engine/key_map.
const std::vector<std::pair<const char*, const char*>>& controls();
/// The keys of the headset mode's mirror window (no mouse hand): the help overlay's rows there.
const std::vector<std::pair<const char*, const char*>>& headsetControls();

/// Starts or stops (and saves) the hand recording at state.recordingPath (F5 and its button).
void toggleHandRecording(AppSession& session, PanelState& state);
/// Starts or stops replaying state.recordingPath (F6 and its button).
void toggleHandReplay(AppSession& session, PanelState& state);

/// Draws one parameter's widget from its table entry; returns true when the value changed (and was in range).
bool parameterWidget(sim::SimParams& params, const sim::ParamInfo& info, std::string& message);

}  // namespace fp::engine
