// The window's key map without a window (label unit): every key is declared once, the help overlay lists
// every declared key, and a press does what its help line says (Ctrl+Q even while the panel has the keyboard,
// the hand keys only where there is a mouse hand).
#include <gtest/gtest.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <cmath>
#include <set>
#include <string>

#include "engine/key_map.h"
#include "engine/panel.h"
#include "engine/view_control.h"

using namespace fp;
using namespace fp::engine;

TEST(KeyMap, EveryKeyDeclaredOnceAndListedInTheHelp) {
  std::set<std::pair<int, int>> seen;
  std::set<std::string> help;
  for (const auto& [input, action] : controls())
    help.insert(input);
  for (const KeyBinding& b : keyBindings()) {
    EXPECT_FALSE(b.keys.empty());
    EXPECT_NE(std::string(b.help), "");
    EXPECT_TRUE(b.apply != nullptr) << b.name;
    for (int key : b.keys)
      EXPECT_TRUE(seen.insert({key, b.mods}).second) << b.name << " declares a key another binding has";
    EXPECT_EQ(help.count(b.name), 1u) << b.name << " is not in the help";
  }
  for (const auto& [input, action] : ViewControl::controls())
    EXPECT_EQ(help.count(input), 1u) << input;
  EXPECT_EQ(controls().size(), keyBindings().size() + ViewControl::controls().size());
  // the headset's mirror lists the keys that act there: none of the mouse hand's
  std::size_t handKeys = 0;
  for (const KeyBinding& b : keyBindings())
    handKeys += b.hand;
  EXPECT_GT(handKeys, 0u);
  EXPECT_EQ(headsetControls().size(), keyBindings().size() - handKeys);
}

TEST(KeyMap, PressesDoWhatTheHelpSays) {
  SessionConfig config;
  config.scenePath = FP_SOURCE_DIR "/assets/scenes/tiny_dam_break.json";
  AppSession session(config);
  PanelState panel;
  render::RenderSettings settings;
  KeyTargets t{session, panel, settings};
  EXPECT_TRUE(applyKey(GLFW_KEY_R, 0, t, false));
  EXPECT_TRUE(session.requests().reset);
  EXPECT_TRUE(applyKey(GLFW_KEY_KP_ADD, 0, t, false));
  EXPECT_NEAR(session.timeScale, 1.25, 1e-12);
  EXPECT_TRUE(applyKey(GLFW_KEY_MINUS, 0, t, false));
  EXPECT_NEAR(session.timeScale, 1.0, 1e-12);
  const auto view = settings.view;
  EXPECT_TRUE(applyKey(GLFW_KEY_V, 0, t, false));
  EXPECT_NE(settings.view, view);
  // Q alone turns the palm; Ctrl+Q quits, even while the panel has the keyboard; other keys wait then
  const double yaw = session.mouseHand().yawOffset;
  EXPECT_TRUE(applyKey(GLFW_KEY_Q, 0, t, false));
  EXPECT_NEAR(session.mouseHand().yawOffset, yaw + M_PI / 12.0, 1e-12);
  EXPECT_FALSE(panel.quit);
  EXPECT_FALSE(applyKey(GLFW_KEY_TAB, 0, t, true));
  EXPECT_TRUE(panel.visible);
  EXPECT_TRUE(applyKey(GLFW_KEY_Q, GLFW_MOD_CONTROL, t, true));
  EXPECT_TRUE(panel.quit);
  // the headset mode's mirror has no mouse hand
  EXPECT_FALSE(applyKey(GLFW_KEY_2, 0, t, false, false));
  EXPECT_TRUE(applyKey(GLFW_KEY_2, 0, t, false, true));
  EXPECT_EQ(session.mouseHand().gesture().target(), input::Gesture::Fist);
  EXPECT_FALSE(applyKey(GLFW_KEY_K, 0, t, false));  // no binding
}
