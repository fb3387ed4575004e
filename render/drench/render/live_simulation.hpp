#pragma once
/// The simulation side of `drench view`: a Simulation stepped on its own thread, publishing snapshots that
/// the window takes without waiting for a step; and the fluid's surface reconstructed on a thread of its own
/// from the snapshot the window hands it. No OpenGL here, so that tests drive it without a display.

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <drench/common/triangle_mesh.hpp>
#include <drench/common/types.hpp>
#include <drench/scene/simulation.hpp>
#include <drench/surface/surface_settings.hpp>

namespace drench::render {

/// The state of a simulation after one of its steps, copied out of it for drawing.
struct Snapshot {
  std::uint64_t serial = 0;       ///< 1 for the first snapshot, + 1 for each one published after it
  std::uint64_t generation = 0;   ///< 0 for the first Simulation, + 1 at each restart
  std::int64_t steps = 0;         ///< steps done by this generation's Simulation
  Scalar time = 0;                ///< simulated time (unit: s)
  Vec3Array positions;            ///< N particle centres (unit: m)
  Vec3Array velocities;           ///< N velocities (unit: m/s)
  TriangleMesh cloth;             ///< the cloth's nodes now and its triangles; empty without cloth
  std::uint64_t contacts = 0;     ///< particle-triangle contacts in the last step (0 without coupling)
  std::uint64_t leaks = 0;        ///< leaks found by the audit over all steps (0 without "leak_audit")
  double steps_per_second = 0.0;  ///< stepping rate over the last half second of stepping (unit: 1/s)
  bool finished = false;          ///< the scene's duration is done: no more steps until a restart
  std::string stopped;            ///< why stepping stopped early (a non-finite state), else ""
};

/// A Simulation stepping on its own thread. It publishes a Snapshot after every step into a slot the
/// window swaps out under a mutex (three buffers: the thread's, the slot, the window's), so neither side
/// ever waits for the other's work, only for a swap of vectors. The thread stops at the scene's duration
/// or at a step that reports a non-finite state, and waits for a restart.
class LiveSimulation {
 public:
  /// Builds a fresh Simulation of the scene; called once here and once per restart, on the stepping thread.
  using Factory = std::function<std::unique_ptr<Simulation>()>;

  /// Builds the first Simulation on the calling thread (so that a bad scene throws here, before any window
  /// opens), publishes its initial state and starts the thread, paused or not. The thread steps with drench's
  /// thread count (common/parallel.hpp), which is the process's. While the surface worker (LiveSurface)
  /// reconstructs at the same time, whichever of the two starts a parallel loop while the other's loop holds
  /// the pool runs that loop on its own thread: results are the same, the two never wait for each other.
  /// @throws whatever `make` throws (SceneError for a scene that cannot be built)
  LiveSimulation(Factory make, bool paused);
  /// Stops the thread after the step it is in, and joins it.
  ~LiveSimulation();
  LiveSimulation(const LiveSimulation&) = delete;
  LiveSimulation& operator=(const LiveSimulation&) = delete;

  /// Pauses or resumes stepping; a step under way finishes.
  void set_paused(bool paused);
  bool paused() const;
  /// While paused, asks for one more step (each call one step); ignored while running.
  void step_once();
  /// Throws the Simulation away after the step under way and builds a new one from the factory (on the
  /// stepping thread, so the window goes on drawing meanwhile); pausing is kept.
  void restart();

  /// When a snapshot was published since the last call, swaps it into `out` (whose old buffers the thread
  /// reuses) and returns true; else leaves `out` alone and returns false. Never waits for a step.
  bool take_latest(Snapshot& out);

  /// Steps done over all generations, and the wall time spent in them (unit: s), for the exit line.
  std::int64_t total_steps() const;
  double stepping_seconds() const;
  /// The message of an exception a restart threw (the thread then idles), else "".
  std::string error() const;

 private:
  void loop();
  /// Copies `m_simulation`'s state into the thread's buffer and swaps it into the slot.
  void publish();

  Factory m_make;
  std::unique_ptr<Simulation> m_simulation;  // only the stepping thread touches it once it runs
  Snapshot m_back;                           // the stepping thread's buffer
  std::uint64_t m_generation = 0;
  std::uint64_t m_serial = 0;
  std::uint64_t m_last_contacts = 0;
  double m_rate_seconds = 0.0;  // stepping time since the rate was last updated (unit: s)
  std::int64_t m_rate_steps = 0;
  double m_rate = 0.0;
  std::string m_stopped;  // Snapshot::stopped

  mutable std::mutex m_mutex;  // guards everything below
  std::condition_variable m_wake;
  Snapshot m_latest;
  bool m_fresh = false;
  bool m_paused = false;
  bool m_idle = false;  // finished, stopped or failed: wait for a restart
  std::int64_t m_step_requests = 0;
  bool m_restart = false;
  bool m_quit = false;
  std::int64_t m_total_steps = 0;
  double m_stepping_seconds = 0.0;
  std::string m_error;

  std::thread m_thread;  // started by the constructor's body, once every member is built
};

/// The fluid's surface (surface_reconstruction.hpp) rebuilt on a thread of its own from snapshots the window
/// hands it, one at a time: a request while one is under way is refused, so the window asks at most once
/// per drawn frame and the surface trails the particles by one reconstruction.
class LiveSurface {
 public:
  /// @param particle_spacing  the scene's fluid.particle_spacing (unit: m), > 0
  /// @param settings  the scene's `surface`
  /// @param obstacles  the scene's static obstacles, which the surface respects as it does the cloth
  LiveSurface(Scalar particle_spacing, const SurfaceSettings& settings, TriangleMesh obstacles);
  ~LiveSurface();
  LiveSurface(const LiveSurface&) = delete;
  LiveSurface& operator=(const LiveSurface&) = delete;

  /// Starts reconstructing `snapshot`'s particles (against its cloth) unless a reconstruction is under way
  /// or waiting to be taken; returns whether it started. Copies what it needs.
  bool request(const Snapshot& snapshot);
  /// When a reconstruction has finished, swaps its mesh into `mesh`, sets `serial` and `generation` to
  /// those of the snapshot it was made from and returns true. A failed reconstruction (SceneError for a
  /// non-finite particle) gives an empty mesh and its message in `error`.
  bool take(TriangleMesh& mesh, std::uint64_t& serial, std::uint64_t& generation, std::string& error);
  /// Wall time of the last reconstruction (unit: s).
  double last_seconds() const;

 private:
  void loop();

  Scalar m_spacing;
  SurfaceSettings m_settings;
  TriangleMesh m_obstacles;

  mutable std::mutex m_mutex;  // guards everything below
  std::condition_variable m_wake;
  bool m_busy = false;  // a request is being worked on or its result waits to be taken
  bool m_requested = false;
  bool m_done = false;
  bool m_quit = false;
  Vec3Array m_particles, m_cloth_positions;
  std::vector<Triangle> m_cloth_triangles;
  std::uint64_t m_serial = 0, m_generation = 0;
  TriangleMesh m_result;
  std::string m_error;
  double m_seconds = 0.0;

  std::thread m_thread;  // started by the constructor's body, once every member is built
};

}  // namespace drench::render
