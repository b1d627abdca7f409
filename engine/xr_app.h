#pragma once
/// The headset mode of `fluidplaying --xr`: the one app loop (engine/app_loop) with an OpenXR platform.
/// Frames are paced by xrWaitFrame, both eyes are drawn by the one renderer with their own pose and
/// asymmetric field of view, the tracked hands (or the controllers) drive the session's tracked hands, and
/// the tank stands on a table half a metre in front of the user.

#include <ostream>

#include "engine/cli.h"

namespace fp::engine {

/// Runs the headset mode until the runtime ends the session, Ctrl+C, or --frames; returns the exit code.
/// Throws XrUnavailable (engine/xr_program.h) when there is no runtime, no HMD or no GL support, before the
/// scene is built.
int runXrApp(const CliOptions& options, std::ostream& out);

}  // namespace fp::engine
