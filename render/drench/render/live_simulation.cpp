#include <drench/render/live_simulation.hpp>

#include <chrono>
#include <exception>
#include <utility>

#include <drench/surface/surface_reconstruction.hpp>

namespace drench::render {

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

LiveSimulation::LiveSimulation(Factory make, bool paused) : m_make(std::move(make)), m_paused(paused) {
  m_simulation = m_make();
  m_idle = m_simulation->finished();
  publish();
  m_thread = std::thread([this] { loop(); });
}

LiveSimulation::~LiveSimulation() {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_quit = true;
  }
  m_wake.notify_all();
  m_thread.join();
}

void LiveSimulation::set_paused(bool paused) {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_paused = paused;
    m_step_requests = 0;
  }
  m_wake.notify_all();
}

bool LiveSimulation::paused() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_paused;
}

void LiveSimulation::step_once() {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    if (!m_paused || m_idle) return;
    ++m_step_requests;
  }
  m_wake.notify_all();
}

void LiveSimulation::restart() {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_restart = true;
  }
  m_wake.notify_all();
}

bool LiveSimulation::take_latest(Snapshot& out) {
  std::lock_guard<std::mutex> lock(m_mutex);
  if (!m_fresh) return false;
  std::swap(out, m_latest);
  m_fresh = false;
  return true;
}

std::int64_t LiveSimulation::total_steps() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_total_steps;
}

double LiveSimulation::stepping_seconds() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_stepping_seconds;
}

std::string LiveSimulation::error() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_error;
}

void LiveSimulation::publish() {
  const Simulation& sim = *m_simulation;
  Snapshot& s = m_back;
  s.serial = ++m_serial;
  s.generation = m_generation;
  s.steps = sim.steps_done();
  s.time = sim.time();
  // Assignment into the recycled buffers: after the first few snapshots no step allocates for them.
  s.positions = sim.particles().positions;
  s.velocities = sim.particles().velocities;
  if (const ClothEngine* cloth = sim.cloth()) {
    // Between steps positions_t1 is where the cloth is now (scene_runner.cpp writes frames from it too).
    s.cloth.positions = cloth->mesh().positions_t1;
    s.cloth.triangles = cloth->mesh().triangles;
  } else {
    s.cloth.positions.clear();
    s.cloth.triangles.clear();
  }
  const std::uint64_t contacts = sim.coupling_stats().contacts;
  s.contacts = contacts - m_last_contacts;
  m_last_contacts = contacts;
  s.leaks = sim.leak_stats().leaks;
  // Until half a second of stepping has been timed, the rate so far.
  s.steps_per_second = m_rate > 0 ? m_rate : m_rate_seconds > 0 ? m_rate_steps / m_rate_seconds : 0.0;
  s.finished = sim.finished();
  s.stopped = m_stopped;
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    std::swap(m_back, m_latest);
    m_fresh = true;
  }
}

void LiveSimulation::loop() {
  std::unique_lock<std::mutex> lock(m_mutex);
  while (true) {
    m_wake.wait(lock, [&] { return m_quit || m_restart || (!m_idle && (!m_paused || m_step_requests > 0)); });
    if (m_quit) return;
    if (m_restart) {
      m_restart = false;
      m_step_requests = 0;
      lock.unlock();
      // The old Simulation goes first: two of them at once would double the memory for a moment.
      m_simulation.reset();
      std::string error;
      try {
        m_simulation = m_make();
        ++m_generation;
        m_last_contacts = 0;
        m_rate = m_rate_seconds = 0.0;
        m_rate_steps = 0;
        m_stopped.clear();
        publish();
      } catch (const std::exception& e) {
        error = e.what();
      }
      lock.lock();
      m_error = error;
      m_idle = !error.empty() || m_simulation->finished();
      continue;
    }
    if (m_paused) --m_step_requests;
    lock.unlock();

    const auto start = std::chrono::steady_clock::now();
    const StepStatus status = m_simulation->step();
    const double seconds = seconds_since(start);
    m_rate_seconds += seconds;
    ++m_rate_steps;
    if (m_rate_seconds >= 0.5) {
      m_rate = m_rate_steps / m_rate_seconds;
      m_rate_seconds = 0.0;
      m_rate_steps = 0;
    }
    if (!status.ok()) m_stopped = status.describe();
    publish();

    lock.lock();
    ++m_total_steps;
    m_stepping_seconds += seconds;
    m_idle = m_simulation->finished() || !m_stopped.empty();
    if (m_idle) m_step_requests = 0;
  }
}

LiveSurface::LiveSurface(Scalar particle_spacing, const SurfaceSettings& settings, TriangleMesh obstacles)
    : m_spacing(particle_spacing), m_settings(settings), m_obstacles(std::move(obstacles)) {
  m_thread = std::thread([this] { loop(); });
}

LiveSurface::~LiveSurface() {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_quit = true;
  }
  m_wake.notify_all();
  m_thread.join();
}

bool LiveSurface::request(const Snapshot& snapshot) {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    if (m_busy) return false;
    m_particles = snapshot.positions;
    m_cloth_positions = snapshot.cloth.positions;
    m_cloth_triangles = snapshot.cloth.triangles;
    m_serial = snapshot.serial;
    m_generation = snapshot.generation;
    m_busy = m_requested = true;
  }
  m_wake.notify_all();
  return true;
}

bool LiveSurface::take(TriangleMesh& mesh, std::uint64_t& serial, std::uint64_t& generation,
                       std::string& error) {
  std::lock_guard<std::mutex> lock(m_mutex);
  if (!m_done) return false;
  std::swap(mesh, m_result);
  serial = m_serial;
  generation = m_generation;
  error = m_error;
  m_done = m_busy = false;
  return true;
}

double LiveSurface::last_seconds() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_seconds;
}

void LiveSurface::loop() {
  std::unique_lock<std::mutex> lock(m_mutex);
  while (true) {
    m_wake.wait(lock, [&] { return m_quit || m_requested; });
    if (m_quit) return;
    m_requested = false;
    // The inputs stay put while busy: request() refuses until take() has the result.
    lock.unlock();
    const auto start = std::chrono::steady_clock::now();
    std::vector<SurfaceObstacle> obstacles;
    if (!m_cloth_triangles.empty()) obstacles.push_back({&m_cloth_positions, &m_cloth_triangles});
    if (!m_obstacles.triangles.empty()) obstacles.push_back({&m_obstacles.positions, &m_obstacles.triangles});
    TriangleMesh result;
    std::string error;
    try {
      SurfaceMesh mesh = reconstruct_surface(m_particles, m_spacing, m_settings, obstacles);
      result.positions = std::move(mesh.positions);
      result.triangles = std::move(mesh.triangles);
    } catch (const std::exception& e) {
      error = e.what();
    }
    const double seconds = seconds_since(start);
    lock.lock();
    m_result = std::move(result);
    m_error = error;
    m_seconds = seconds;
    m_done = true;
  }
}

}  // namespace drench::render
