#pragma once
/// The window's keys: one declaration per key with its action and the help overlay's line, so the F1 help is
/// the table the keys are handled by. Keys held down for a continuous motion (W, S, Z, X) belong to the
/// camera and mouse control (engine/view_control.h), which declares them the same way.

#include <vector>

#include "engine/panel.h"

namespace fp::engine {

/// What a key acts on.
struct KeyTargets {
  AppSession& session;
  PanelState& panel;
  render::RenderSettings& settings;
};

/// One key (or a few keys that are the same key: = and keypad +) and what it does.
struct KeyBinding {
  std::vector<int> keys;        ///< GLFW key codes
  int mods = 0;                 ///< GLFW modifier bits that must be held (Ctrl+Q)
  const char* name = "";        ///< as the help shows it
  const char* help = "";        ///< what it does
  bool hand = false;            ///< acts on the mouse hand (not in the headset mode)
  bool evenWhenTyping = false;  ///< also while the panel has the keyboard
  void (*apply)(KeyTargets&) = nullptr;
};

/// every key of the window, in the help overlay's order
const std::vector<KeyBinding>& keyBindings();

/// Applies the press of `key` with modifiers `mods`: the binding with the most matching modifiers wins.
/// `typing`: the panel has the keyboard (only evenWhenTyping keys act); `handKeys`: the mouse hand exists.
/// Returns false when no binding took the key.
bool applyKey(int key, int mods, KeyTargets& targets, bool typing, bool handKeys = true);

}  // namespace fp::engine
