#include "engine/key_map.h"

// clang-format off
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
// clang-format on

#include <algorithm>
#include <cmath>

namespace fp::engine {

namespace {

void turnPalm(KeyTargets& t, double sign) {
  input::MouseHand& hand = t.session.mouseHand();
  hand.yawOffset = std::clamp(hand.yawOffset + sign * M_PI / 12.0, -M_PI / 2, M_PI / 2);
}

void gesture(KeyTargets& t, input::Gesture g) {
  t.session.mouseHand().gesture().setTarget(g);
}

}  // namespace

const std::vector<KeyBinding>& keyBindings() {
  using K = KeyTargets;
  static const std::vector<KeyBinding> table = {
      {{GLFW_KEY_1}, 0, "1", "flat hand", true, false, [](K& t) { gesture(t, input::Gesture::Flat); }},
      {{GLFW_KEY_2}, 0, "2", "fist", true, false, [](K& t) { gesture(t, input::Gesture::Fist); }},
      {{GLFW_KEY_3}, 0, "3", "point", true, false, [](K& t) { gesture(t, input::Gesture::Point); }},
      {{GLFW_KEY_G},
       0,
       "G",
       "cycle the gestures",
       true,
       false,
       [](K& t) {
         input::GestureAnimator& g = t.session.mouseHand().gesture();
         g.setTarget(input::Gesture((int(g.target()) + 1) % 3));
       }},
      {{GLFW_KEY_Q}, 0, "Q", "turn the palm left", true, false, [](K& t) { turnPalm(t, 1.0); }},
      {{GLFW_KEY_E}, 0, "E", "turn the palm right", true, false, [](K& t) { turnPalm(t, -1.0); }},
      {{GLFW_KEY_SPACE},
       0,
       "Space",
       "pause or run",
       false,
       false,
       [](K& t) { t.session.paused = !t.session.paused; }},
      {{GLFW_KEY_N},
       0,
       "N",
       "one solver step",
       false,
       false,
       [](K& t) {
         t.session.paused = true;
         t.session.requests().singleStep = true;
       }},
      {{GLFW_KEY_R},
       0,
       "R",
       "reset the scene (applies parameters marked *)",
       false,
       false,
       [](K& t) { t.session.requests().reset = true; }},
      {{GLFW_KEY_EQUAL, GLFW_KEY_KP_ADD},
       0,
       "+",
       "time scale up",
       false,
       false,
       [](K& t) { t.session.timeScale = std::min(4.0, t.session.timeScale * 1.25); }},
      {{GLFW_KEY_MINUS, GLFW_KEY_KP_SUBTRACT},
       0,
       "-",
       "time scale down",
       false,
       false,
       [](K& t) { t.session.timeScale = std::max(0.05, t.session.timeScale / 1.25); }},
      {{GLFW_KEY_V},
       0,
       "V",
       "water or particle view",
       false,
       false,
       [](K& t) {
         using View = render::RenderSettings::View;
         t.settings.view = t.settings.view == View::Fluid ? View::Particles : View::Fluid;
       }},
      {{GLFW_KEY_F5},
       0,
       "F5",
       "record the hand / stop and save",
       true,
       false,
       [](K& t) { toggleHandRecording(t.session, t.panel); }},
      {{GLFW_KEY_F6},
       0,
       "F6",
       "replay the recording / stop",
       true,
       false,
       [](K& t) { toggleHandReplay(t.session, t.panel); }},
      {{GLFW_KEY_F8},
       0,
       "F8",
       "record a video (ffmpeg)",
       false,
       false,
       [](K& t) { t.panel.recordVideo = !t.panel.recordVideo; }},
      {{GLFW_KEY_F9},
       0,
       "F9",
       "record frames as PNG",
       false,
       false,
       [](K& t) { t.panel.recordFrames = !t.panel.recordFrames; }},
      {{GLFW_KEY_F12}, 0, "F12", "screenshot", false, false, [](K& t) { t.panel.screenshot = true; }},
      {{GLFW_KEY_F11},
       0,
       "F11",
       "fullscreen",
       false,
       false,
       [](K& t) { t.panel.fullscreen = !t.panel.fullscreen; }},
      {{GLFW_KEY_TAB},
       0,
       "Tab",
       "show or hide the panel",
       false,
       false,
       [](K& t) { t.panel.visible = !t.panel.visible; }},
      {{GLFW_KEY_F1, GLFW_KEY_H},
       0,
       "F1, H",
       "this help",
       false,
       false,
       [](K& t) { t.panel.help = !t.panel.help; }},
      {{GLFW_KEY_ESCAPE}, 0, "Esc", "close the help", false, false, [](K& t) { t.panel.help = false; }},
      {{GLFW_KEY_Q}, GLFW_MOD_CONTROL, "Ctrl+Q", "quit", false, true, [](K& t) { t.panel.quit = true; }},
  };
  return table;
}

bool applyKey(int key, int mods, KeyTargets& targets, bool typing, bool handKeys) {
  const KeyBinding* best = nullptr;
  for (const KeyBinding& b : keyBindings()) {
    if (std::find(b.keys.begin(), b.keys.end(), key) == b.keys.end() || (mods & b.mods) != b.mods)
      continue;
    if (!best || b.mods > best->mods)
      best = &b;
  }
  if (!best || (typing && !best->evenWhenTyping) || (best->hand && !handKeys))
    return false;
  best->apply(targets);
  return true;
}

}  // namespace fp::engine
