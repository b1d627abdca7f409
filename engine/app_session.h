#pragma once
/// The simulation side of the interactive app, shared by the desktop window, the headless hand replay and
/// (later) the OpenXR mode: the scene and its simulation with the virtual hand attached, real-time pacing,
/// the solver steps of a frame run as a task on the TBB workers while the caller renders the last completed
/// state, the live parameters, hand replay and recording, and the statistics the panel plots.
///
/// Between frames the simulation is idle: finishSteps() joins the task, then the caller reads the state,
/// applies its edits and starts the next frame's steps with startSteps().

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "input/hand_driver.h"
#include "input/joint_hand.h"
#include "input/mouse_hand.h"
#include "input/pose_track.h"
#include "sim/parallel.h"
#include "sim/simulation.h"

namespace fp::engine {

/// How a session starts.
struct SessionConfig {
  std::string scenePath;              ///< scene JSON
  std::string mode;                   ///< resolution mode override (empty: the scene's)
  std::optional<std::uint64_t> seed;  ///< seed override
  std::vector<std::string> sets;      ///< "KEY=VALUE" parameter settings over the scene's, in order
  std::string handScript;             ///< pose-track CSV replayed from simulated time 0 (empty: mouse)
  bool fixedStep = false;             ///< every frame advances exactly 1 / frame_rate of simulated time
  double timeScale = 1.0;             ///< simulated seconds per wall second wanted, in (0, 4]
  double handScale = 1.0;             ///< hand size factor (1: adult)
  bool hand = true;                   ///< attach the virtual hand (false: the scene alone)
  std::string loadState;              ///< saved state restored after the build (--load-state; empty: none)
  std::string saveState;   ///< state file written by saveStateNow() and every saveStateEvery frames
  int saveStateEvery = 0;  ///< frames between saves of saveState (0: only at the run's end)
  /// an instability rolls back to the last good in-memory snapshot (window, headset) instead of pausing
  /// with error() set (headless: the run reports it and ends)
  bool recover = false;
  /// the steps run on a thread of their own instead of a TBB task (the headset: they run while the main
  /// thread draws even with --threads 1, where TBB has no worker, and a frame may leave them running)
  bool stepThread = false;
  /// a solver slower than the display for the frame-pacing tests (--debug-slow-steps N,MS): the first
  /// `slowSteps` solver steps of the session each take `slowStepSeconds` [s] longer
  int slowSteps = 0;
  double slowStepSeconds = 0.0;
};

/// What the session did about the last instability (the panel shows it).
struct RecoveryReport {
  int rollbacks = 0;      ///< rollbacks since the build
  double failedAt = 0;    ///< simulated time of the instability [s]
  double restoredTo = 0;  ///< simulated time of the snapshot restored [s] (or 0 after a rebuild)
  double dtCap = 0;       ///< time-step cap of the recovery [s] (0: none now)
  double capUntil = 0;    ///< simulated time the cap ends [s]
  std::string message;    ///< one line: what happened and what was done
};

/// A time series for the panel's plots: the last `capacity` values.
class Series {
 public:
  /// keeps the last `capacity` values
  explicit Series(std::size_t capacity = 300) : m_capacity(capacity) {}
  /// appends a value, dropping the oldest beyond capacity
  void push(float v);
  /// the values, oldest first
  const std::vector<float>& values() const { return m_values; }
  /// the newest value (0 when empty)
  float last() const { return m_values.empty() ? 0.0f : m_values.back(); }

 private:
  std::size_t m_capacity;
  std::vector<float> m_values;
};

/// Live statistics, one sample a frame.
struct SessionStats {
  Series fps;              ///< frames per wall second
  Series msPerStep;        ///< wall milliseconds per solver step
  Series particles;        ///< fluid particle count
  Series highShare;        ///< particle count over the uniform-high count [%]
  Series splitsPerSecond;  ///< splits per simulated second
  Series mergesPerSecond;  ///< merges per simulated second
  Series densityError;     ///< mean density error of the last step [%]
  Series realTimeFactor;   ///< simulated over wall time, smoothed
  // the last frame
  int steps = 0;                ///< solver steps of the last frame
  double simMs = 0;             ///< wall time of the last frame's steps (on the workers) [ms]
  double waitMs = 0;            ///< time the frame waited for the steps to finish [ms]
  double frameMs = 0;           ///< wall time of the last frame [ms]
  double uniformHighCount = 0;  ///< particles of the scene at uniform-high resolution
};

/// Requests collected during a frame and applied between frames.
struct SessionRequests {
  bool reset = false;                       ///< rebuild the simulation from the scene
  bool singleStep = false;                  ///< one solver step while paused
  bool resetToSavedState = false;           ///< restore the saved state (savedStatePath()), else reset
  std::optional<sim::AdaptivityMode> mode;  ///< rebuild in another mode
  std::optional<std::string> scenePath;     ///< load another scene
};

/// The session. Not copyable; one per app.
class AppSession {
 public:
  /// Loads the scene, attaches the hand above the water and builds the simulation. Throws sim::InputError,
  /// std::invalid_argument for a bad mode or setting.
  explicit AppSession(const SessionConfig& config);
  ~AppSession();
  AppSession(const AppSession&) = delete;
  AppSession& operator=(const AppSession&) = delete;

  // ---- between frames (the simulation is idle) ----
  /// Waits for the running steps; records the frame's statistics. Safe to call when none run.
  void finishSteps();
  /// true while steps started by startSteps have not finished (finishSteps would wait); any time
  bool stepsRunning() const { return m_running && !m_stepsDone.load(std::memory_order_acquire); }
  /// Applies requests and edited parameters: live ones at once, the others by rebuilding the simulation.
  void applyRequests();
  /// Starts the steps of one frame on the TBB workers: up to the wall time `wallDt` [s] times the time scale
  /// of simulated time (all of it in fixed-step mode), within `budget` [s] of wall time. Uses the hand pose
  /// set by setHandTarget() (or the replay). Returns at once.
  void startSteps(double wallDt, double budget);

  /// the simulation; read it only between frames
  const sim::Simulation& simulation() const { return *m_sim; }
  /// the parameters as edited (applied by applyRequests)
  sim::SimParams& editParams() { return m_params; }
  /// requests for the next applyRequests
  SessionRequests& requests() { return m_requests; }
  /// the mouse hand (used when no replay runs)
  input::MouseHand& mouseHand() { return m_mouseHand; }
  /// the hand's geometry and colliders
  const input::HandDriver& hand() const { return m_hand; }
  /// the hand's current pose
  input::HandPose handPose() const { return m_handPose; }
  /// statistics for the panel
  const SessionStats& stats() const { return m_stats; }
  /// the scene as loaded (without the hand)
  const sim::SceneDesc& scene() const { return m_scene; }
  /// the scene file
  const std::string& scenePath() const { return m_config.scenePath; }
  /// the resolution mode of the running simulation
  sim::AdaptivityMode mode() const { return m_sim->mode(); }
  /// true when a non-live parameter or the hand size was edited and waits for a reset
  bool restartPending() const { return m_restartPending || m_handScalePending; }
  /// the hand size factor of the running simulation, or the edited one waiting for a reset
  double handScale() const { return m_config.handScale; }
  /// sets the hand size factor in [0.5, 3], applied at the next reset (the hand's colliders are rebuilt)
  void setHandScale(double scale);
  /// the steps never pass simulated time `t` [s] (a run's end; default: none)
  void setEndTime(double t) { m_endTime = t; }
  /// the instability report that paused the run, if any
  const std::string& error() const { return m_error; }

  // ---- saved state (sim/state_io) and recovery ----
  /// the owner's part of a saved state: hand pose, replay start, frame target
  std::vector<double> appState() const;
  /// Writes the state now to `path` (empty: SessionConfig::saveState, else fluidplaying_state.bin); throws
  /// sim::InputError when it cannot be written. Between frames only.
  void saveStateNow(const std::string& path = {});
  /// Restores the state file `path` (built from the same scene, mode, seed and hand size); throws
  /// sim::StateError (one line naming the file; the session unchanged). Between frames only.
  void loadStateFile(const std::string& path);
  /// the state file the panel's "Reset to saved state" restores: the last one loaded or saved (empty: none)
  const std::string& savedStatePath() const { return m_savedStatePath; }
  /// what the last rollback did (SessionConfig::recover)
  const RecoveryReport& recovery() const { return m_recovery; }
  /// the in-memory snapshots kept for a rollback, oldest first: (simulated time, encoded state)
  const std::deque<std::pair<double, std::string>>& snapshots() const { return m_snapshots; }
  /// Called by the app loop when the run ends: writes SessionConfig::saveState when set and the run is
  /// sound. Throws sim::InputError when it cannot be written.
  void endRun();
  /// snapshots kept in memory, and their spacing in simulated time [s]
  static constexpr std::size_t kSnapshots = 4;
  static constexpr double kSnapshotSpacing = 0.25;
  /// the mean density error past which a recovering session treats a step as unstable [-]
  static constexpr double kDensityErrorLimit = 0.2;

  bool paused = false;     ///< no steps (the hand still moves, without velocity)
  double timeScale = 1.0;  ///< simulated seconds per wall second wanted, in (0, 4]
  bool fixedStep = false;  ///< see SessionConfig

  // ---- hand replay and recording ----
  /// replays `track` from the current simulated time (a loaded recording)
  void startReplay(const input::PoseTrack& track);
  /// stops a replay; the mouse takes the hand again
  void stopReplay();
  /// true while a replay drives the hand
  bool replaying() const { return m_replay.has_value(); }
  /// starts recording the hand from the current simulated time
  void startRecording();
  /// stops recording and returns what was recorded
  input::PoseTrack stopRecording();
  /// true while recording
  bool recording() const { return m_recording.has_value(); }
  /// F5 and the panel's button: starts recording the hand, or stops and saves the recording as `path`;
  /// returns the status line (what was saved, or why not)
  std::string toggleRecording(const std::string& path);
  /// F6 and the panel's button: replays the recording in `path`, or stops the replay; returns the status line
  /// (empty, or why the file cannot be replayed)
  std::string toggleReplay(const std::string& path);
  /// the frames' simulated-time targets keep the hand: the pose the mouse hand has now is where the hand is
  /// at the end of the coming frame's steps
  void setHandTarget(const input::HandPose& pose) { m_handTarget = pose; }

  // ---- tracked hands (headset, joint recordings): any number, each driven part by part ----
  /// Tracked hands attached at the next build (and rebuilt with every reset), one per entry: its colliders
  /// are sized from the entry's joints (input::jointHandColliders) and start parked above the water.
  void setTrackedHands(const std::vector<std::pair<input::HandSide, input::HandJoints>>& references);
  /// number of tracked hands
  std::size_t trackedHandCount() const { return m_tracked.size(); }
  /// Where tracked hand k's parts are at the end of the coming frame's steps; nothing: tracking lost (the
  /// hand eases out of the water and back, input::HandPresence). Call between frames, or while the steps run
  /// (AppPlatform::inputWhileStepping): the targets of the frames until the next startSteps are queued, and
  /// its steps pass through each in turn.
  void setTrackedHandTarget(std::size_t k,
                            const std::optional<std::array<input::PartPose, input::HandModel::kParts>>& parts,
                            double frameDt);
  /// tracked hand k's parts now
  const std::array<input::PartPose, input::HandModel::kParts>& trackedHandParts(std::size_t k) const {
    return m_tracked[k].parts;
  }
  /// index of tracked hand k's first collider in the simulation
  std::size_t trackedHandFirstCollider(std::size_t k) const { return m_tracked[k].first; }

  /// the mean real-time factor since construction or the last reset (simulated / wall time)
  double meanRealTimeFactor() const;

 private:
  void build();
  void runSteps(double target, double budget, bool oneStep);
  void restoreAppState(const std::vector<double>& extra);
  void rollBack(const std::string& why);
  /// `next` with the running simulation's values of every parameter that is not live (they wait for a
  /// reset); true when one of them differed (a reset is pending)
  bool keepNonLive(sim::SimParams& next) const;
  void takeSnapshot();

  SessionConfig m_config;
  sim::SceneDesc m_scene;
  sim::SimParams m_params;
  sim::AdaptivityMode m_mode = sim::AdaptivityMode::UniformHigh;
  std::unique_ptr<sim::Simulation> m_sim;
  input::HandDriver m_hand{input::HandModel(), 0};
  input::HandPose m_restPose;
  input::HandPose m_handPose;
  input::HandPose m_handTarget;
  input::MouseHand m_mouseHand;
  input::PoseTrack m_segment;  // this frame's hand motion: two keys, or the replay
  std::optional<input::PoseTrack> m_replay;
  double m_replayStart = 0.0;
  std::optional<input::PoseTrack> m_recording;
  double m_recordStart = 0.0;
  SessionRequests m_requests;
  bool m_restartPending = false;
  bool m_singleStep = false;
  bool m_handScalePending = false;
  std::string m_error;
  SessionStats m_stats;
  std::string m_savedStatePath;
  RecoveryReport m_recovery;
  std::deque<std::pair<double, std::string>> m_snapshots;  // oldest first
  std::deque<sim::SimParams> m_snapshotEdits;              // the edited parameters at each snapshot
  int m_framesDone = 0;

  struct TrackedHand {
    input::HandSide side = input::HandSide::Right;
    input::HandJoints reference;
    std::size_t first = 0;
    std::array<input::PartPose, input::HandModel::kParts> parts{};   // now
    std::array<input::PartPose, input::HandModel::kParts> target{};  // at the end of the frame's steps
    std::vector<input::PartMotion::Parts> through;  // the targets set since the last steps started
    input::PartMotion motion;
    input::HandPresence presence{0.0, 1.0};
  };
  std::vector<TrackedHand> m_tracked;

  sim::TaskGroup m_task;
  std::thread m_thread;                 // the steps' thread (SessionConfig::stepThread)
  std::atomic<bool> m_stepsDone{true};  // set by the steps when they finish
  int m_slowStepsDone = 0;              // written by the steps (SessionConfig::slowSteps)
  bool m_running = false;
  double m_targetTime = 0.0;
  double m_endTime = std::numeric_limits<double>::infinity();
  double m_frameStartSim = 0.0;
  std::uint64_t m_stepsBefore = 0;
  std::uint64_t m_splitsBefore = 0;
  std::uint64_t m_mergesBefore = 0;
  double m_stepWallSeconds = 0.0;  // written by the task
  int m_taskSteps = 0;             // written by the task
  std::string m_taskError;         // written by the task
  double m_wallTotal = 0.0;
  double m_simTotal = 0.0;
  std::chrono::steady_clock::time_point m_lastFinish;
};

/// The pose the hand rests at above the water of `scene`: centred over the fluid, fingertips a little above
/// it.
input::HandPose restingHandPose(const sim::SceneDesc& scene, const input::HandModel& model);

/// scene files listed for the panel's scene selector: assets/scenes/*.json here, else in the source tree
std::vector<std::string> availableScenes();

}  // namespace fp::engine
