// Hostile input and hard cases (issue 39): output that cannot be lost or mixed, and the command line.
// Each test runs the built `drench` command (DRENCH_EXECUTABLE) as a user does, in a folder of its own, on
// a small tank of water (864 particles of 4 cm) or a small jet on a 9 x 9 cloth.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <drench/scene/output_folder.hpp>
#include <drench/scene/reconstruct_run.hpp>
#include <drench/scene/scene_runner.hpp>

#include "../drench_command.hpp"
#include "../temp_dir.hpp"

namespace {

using drench::test::read_text;

namespace fs = std::filesystem;
using drench::test::TempDir;
using nlohmann::json;

/// The tank at 4 cm: `duration` seconds at dt 2.5 ms, a frame every 1 / `frame_rate` s.
std::string tank_scene(double duration, double frame_rate, bool surface = false) {
  json scene = json::parse(R"({
    "gravity": [0, -9.81, 0],
    "fluid": {"rest_density": 1000, "particle_spacing": 0.04, "pressure_solver": "pcisph",
              "viscosity": {"method": "artificial", "coefficient": 0.1}},
    "emitters": [{"type": "box", "min": [0, 0, 0], "max": [0.4, 0.3, 0.4]}],
    "boundaries": [{"type": "box", "min": [0, 0, 0], "max": [0.4, 0.6, 0.4], "open_top": true, "layers": 2}],
    "effects": ["viscosity"]
  })");
  scene["time"] = {{"dt", 0.0025}, {"duration", duration}, {"frame_rate", frame_rate}};
  if (surface) scene["effects"].push_back("surface");
  return scene.dump(2);
}

/// A jet of at most 200 particles on a 9 x 9 cloth pinned at its corners: frames 0 to 5.
std::string cloth_scene() {
  return R"({
    "gravity": [0, -9.81, 0],
    "fluid": {"rest_density": 1000, "particle_spacing": 0.02, "pressure_solver": "pcisph"},
    "emitters": [{"type": "nozzle", "center": [0, 0.1, 0], "direction": [0, -1, 0], "radius": 0.03,
                  "speed": 1.0, "max_particles": 200}],
    "cloth": {"mesh": "patch", "center": [0, 0, 0], "size": [0.3, 0.3], "nodes": [9, 9],
              "area_density": 0.2, "pinned": "corners"},
    "coupling": {"cloth_thickness": 0.002},
    "time": {"dt": 0.002, "duration": 0.1, "frame_rate": 50},
    "effects": ["coupling"]
  })";
}

/// Every regular file under `dir` (relative name -> contents).
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    if (entry.is_regular_file())
      files[fs::relative(entry.path(), dir).generic_string()] = read_text(entry.path());
  return files;
}

/// Every entry under `dir`, folders included (relative names).
std::vector<std::string> entries(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    names.push_back(fs::relative(entry.path(), dir).generic_string());
  std::sort(names.begin(), names.end());
  return names;
}

/// Starts `drench ARGUMENTS...` in `cwd` with stdout and stderr into `log`, its address space limited to
/// `memory_limit` bytes when that is not 0.
pid_t start_drench(const std::vector<std::string>& arguments, const fs::path& cwd, const fs::path& log,
                   rlim_t memory_limit = 0) {
  std::vector<std::string> argv_strings = {DRENCH_EXECUTABLE};
  argv_strings.insert(argv_strings.end(), arguments.begin(), arguments.end());
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (memory_limit > 0) {
      const rlimit limit = {memory_limit, memory_limit};
      ::setrlimit(RLIMIT_AS, &limit);
    }
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0 || ::chdir(cwd.c_str()) != 0) ::_exit(127);
    ::dup2(fd, STDOUT_FILENO);
    ::dup2(fd, STDERR_FILENO);
    std::vector<char*> argv;
    for (std::string& argument : argv_strings)
      argv.push_back(argument.data());
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  return pid;
}

/// The exit status of `pid`, 128 + the signal when a signal ended it, or -1 when it is still running after
/// `timeout_s` (it is then killed).
int wait_exit(pid_t pid, double timeout_s) {
  const auto start = std::chrono::steady_clock::now();
  while (true) {
    int status = 0;
    const pid_t done = ::waitpid(pid, &status, WNOHANG);
    if (done == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() > timeout_s) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      return -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

/// Runs `drench ARGUMENTS...` to its end (at most 60 s) and returns its exit status.
int run_drench(const std::vector<std::string>& arguments, const fs::path& cwd, const fs::path& log) {
  return wait_exit(start_drench(arguments, cwd, log), 60.0);
}

/// Waits up to `timeout_s` for a file matching `predicate` under `dir`; false when none came.
template <class Predicate>
bool wait_for_file(const fs::path& dir, double timeout_s, Predicate predicate) {
  const auto start = std::chrono::steady_clock::now();
  while (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() < timeout_s) {
    std::error_code ec;
    for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
      if (predicate(it->path())) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return false;
}

/// A run of the tank into `out`: `frames` frames at 100 per second.
int run_tank(const TempDir& dir, const fs::path& out, int frames, std::vector<std::string> extra = {}) {
  const std::string scene = dir.write("tank.json", tank_scene(0.01 * (frames - 1), 100));
  std::vector<std::string> arguments = {"run", scene, "--out", out.string(), "--threads", "1", "--quiet"};
  arguments.insert(arguments.end(), extra.begin(), extra.end());
  return run_drench(arguments, dir.path(), dir.path() / "log.txt");
}

// `--out ''` wrote into the working directory and overwrote its summary.json and scene.json.
TEST(HostileOutput, AnEmptyOutIsRefusedAndTheWorkingDirectoryIsUntouched) {
  const TempDir dir;
  const std::string scene = dir.write("tank.json", tank_scene(0.01, 100));
  const TempDir work("work");
  work.write("summary.json", "a user's own summary\n");
  work.write("scene.json", "a user's own scene\n");
  const auto before = snapshot(work.path());
  EXPECT_EQ(run_drench({"run", scene, "--out", "", "--quiet"}, work.path(), dir.path() / "log.txt"), 1);
  const std::string log = read_text(dir.path() / "log.txt");
  EXPECT_NE(log.find("drench: --out '': must name a folder"), std::string::npos) << log;
  EXPECT_EQ(snapshot(work.path()), before);
  EXPECT_EQ(entries(work.path()), (std::vector<std::string>{"scene.json", "summary.json"}));

  // A file is not a folder either.
  const std::string file = work.write("notes.txt", "not a folder\n");
  EXPECT_EQ(run_drench({"run", scene, "--out", file, "--quiet"}, work.path(), dir.path() / "log.txt"), 1);
  EXPECT_NE(read_text(dir.path() / "log.txt").find("--out " + file + ": exists and is not a folder"),
            std::string::npos)
      << read_text(dir.path() / "log.txt");
  EXPECT_EQ(read_text(file), "not a folder\n");

  // Nor a link to nothing, which failed with a bare "File exists" after the scene was read.
  const fs::path link = work.path() / "dangling";
  fs::create_symlink(work.path() / "nowhere", link);
  EXPECT_EQ(
      run_drench({"run", scene, "--out", link.string(), "--quiet"}, work.path(), dir.path() / "log.txt"), 1);
  EXPECT_NE(read_text(dir.path() / "log.txt")
                .find("--out " + link.string() + ": a symbolic link to " +
                      (work.path() / "nowhere").string() + ", which does not exist"),
            std::string::npos)
      << read_text(dir.path() / "log.txt");
}

// An --out holding an earlier run kept its frames, and reconstruct and render then saw both runs.
TEST(HostileOutput, AReusedFolderIsRefusedWithoutOverwriteAndLeftAsItWas) {
  const TempDir dir;
  const fs::path out = dir.path() / "out";
  ASSERT_EQ(run_tank(dir, out, 6), 0) << read_text(dir.path() / "log.txt");
  ASSERT_TRUE(fs::exists(out / "frames/fluid_0005.ply"));
  const json manifest = json::parse(read_text(out / drench::kOutputManifest));
  EXPECT_EQ(manifest["command"], "run");
  EXPECT_EQ(manifest["files"], json(drench::run_output_patterns()));

  const auto before = snapshot(out);
  EXPECT_EQ(run_tank(dir, out, 3), 1);
  const std::string log = read_text(dir.path() / "log.txt");
  EXPECT_NE(log.find("--out " + out.string() + ": the folder is not empty (it holds " +
                     (out / drench::kOutputManifest).string() + ")"),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("add --overwrite"), std::string::npos) << log;
  EXPECT_EQ(snapshot(out), before) << "a refused run changed the folder";
}

TEST(HostileOutput, OverwriteRemovesTheEarlierRunsFrames) {
  const TempDir dir;
  const fs::path out = dir.path() / "out";
  ASSERT_EQ(run_tank(dir, out, 6), 0) << read_text(dir.path() / "log.txt");
  ASSERT_TRUE(fs::exists(out / "frames/fluid_0005.ply"));
  // A temporary that a killed writer left is the earlier run's too.
  std::ofstream(out / "frames/fluid_0006.ply.tmp-12345") << "half a frame";
  ASSERT_EQ(run_tank(dir, out, 3, {"--overwrite"}), 0) << read_text(dir.path() / "log.txt");
  EXPECT_EQ(entries(out / "frames"),
            (std::vector<std::string>{"fluid_0000.ply", "fluid_0001.ply", "fluid_0002.ply"}));
  EXPECT_EQ(json::parse(read_text(out / "summary.json"))["frames"], 3);
}

TEST(HostileOutput, OverwriteRefusesAndDeletesNothingWhenAFileIsNotDrenchs) {
  const TempDir dir;
  const fs::path out = dir.path() / "out";
  ASSERT_EQ(run_tank(dir, out, 4), 0) << read_text(dir.path() / "log.txt");
  std::ofstream(out / "frames/notes.txt") << "the user's notes\n";
  const auto before = snapshot(out);
  EXPECT_EQ(run_tank(dir, out, 2, {"--overwrite"}), 1);
  const std::string log = read_text(dir.path() / "log.txt");
  EXPECT_NE(log.find((out / "frames/notes.txt").string() + " was not written by drench"), std::string::npos)
      << log;
  EXPECT_NE(log.find("nothing deleted"), std::string::npos) << log;
  EXPECT_EQ(snapshot(out), before);

  // Without a manifest nothing in the folder is known to be drench's.
  const fs::path other = dir.path() / "other";
  fs::create_directories(other / "frames");
  std::ofstream(other / "frames/fluid_0000.ply") << "someone else's frame";
  EXPECT_EQ(run_tank(dir, other, 2, {"--overwrite"}), 1);
  EXPECT_NE(read_text(dir.path() / "log.txt").find("but no drench_run.json"), std::string::npos)
      << read_text(dir.path() / "log.txt");
  EXPECT_EQ(read_text(other / "frames/fluid_0000.ply"), "someone else's frame");
}

// --overwrite trusted any drench_run.json: a run's deleted a sweep's folder and a sweep's a run's, and a
// forged manifest listing "*" and "*/*" had foreign files deleted.
TEST(HostileOutput, OverwriteTrustsOnlyItsOwnCommandsManifestAndFileNames) {
  const TempDir dir;
  const fs::path out = dir.path() / "out";
  ASSERT_EQ(run_tank(dir, out, 2), 0) << read_text(dir.path() / "log.txt");
  const auto run_files = snapshot(out);
  const std::string scene = dir.write("sweep.json", tank_scene(0.01, 100));
  EXPECT_EQ(run_drench({"sweep", scene, "--vary", "time.dt=0.0025,0.002", "--out", out.string(),
                        "--overwrite", "--quiet"},
                       dir.path(), dir.path() / "log.txt"),
            1);
  EXPECT_NE(read_text(dir.path() / "log.txt")
                .find("says the folder holds the output of drench run, not of drench sweep; nothing deleted"),
            std::string::npos)
      << read_text(dir.path() / "log.txt");
  EXPECT_TRUE(snapshot(out) == run_files) << "the sweep changed the run's folder";

  const fs::path forged = dir.path() / "forged";
  fs::create_directories(forged / "docs");
  std::ofstream(forged / "notes.txt") << "the user's notes\n";
  std::ofstream(forged / "docs/thesis.tex") << "the user's thesis\n";
  for (const std::string command : {"sweep", "run"}) {
    std::ofstream(forged / drench::kOutputManifest)
        << json{{"drench_version", DRENCH_VERSION}, {"command", command}, {"files", {"*", "*/*"}}}.dump();
    const auto before = snapshot(forged);
    EXPECT_EQ(run_tank(dir, forged, 2, {"--overwrite"}), 1) << command;
    const std::string log = read_text(dir.path() / "log.txt");
    if (command == "sweep")
      EXPECT_NE(log.find("holds the output of drench sweep, not of drench run"), std::string::npos) << log;
    else
      EXPECT_NE(log.find((forged / "docs").string() + " was not written by drench (drench run writes no such "
                                                      "file); nothing deleted"),
                std::string::npos)
          << log;
    EXPECT_TRUE(snapshot(forged) == before) << command << ": the refused run changed the folder";
  }
}

// drench reference wrote reference.json and exited 0 after a run whose pressure solve never reached its
// eta (PRESSURE_NOT_CONVERGED, a warning for a plain run): not the converged answer a reference must be.
TEST(HostileOutput, AReferenceWhosePressureSolveDidNotConvergeHasNoReferenceJson) {
  const TempDir dir;
  const fs::path out = dir.path() / "reference";
  const std::string scene = dir.write("tank.json", tank_scene(0.01, 100));
  // eta / 1e6 is a density error of 1e-9, which PCISPH's 100 iterations do not reach.
  EXPECT_EQ(run_drench({"reference", scene, "--out", out.string(), "--eta-divisor", "1e6", "--threads", "1",
                        "--quiet"},
                       dir.path(), dir.path() / "log.txt"),
            2);
  const std::string log = read_text(dir.path() / "log.txt");
  EXPECT_NE(log.find("has no reference.json (PRESSURE_NOT_CONVERGED"), std::string::npos) << log;
  EXPECT_TRUE(fs::exists(out / "summary.json"));
  EXPECT_FALSE(fs::exists(out / "reference.json"));
}

/// Starts a 600 s tank run, waits for its frame 1 and sends `signal`; returns the exit status.
int interrupt_run(const TempDir& dir, const fs::path& out, int signal) {
  const std::string scene = dir.write("long.json", tank_scene(600, 100));
  const pid_t pid = start_drench({"run", scene, "--out", out.string(), "--threads", "1", "--quiet"},
                                 dir.path(), dir.path() / "log.txt");
  const bool started =
      wait_for_file(out, 30.0, [](const fs::path& p) { return p.filename() == "fluid_0001.ply"; });
  EXPECT_TRUE(started) << read_text(dir.path() / "log.txt");
  ::kill(pid, signal);
  return wait_exit(pid, 30.0);
}

// SIGINT ended a run with no summary.json.
TEST(HostileOutput, SigintEndsARunWithAnInterruptedSummaryAndExit130) {
  const TempDir dir;
  const fs::path out = dir.path() / "out";
  EXPECT_EQ(interrupt_run(dir, out, SIGINT), 130) << read_text(dir.path() / "log.txt");
  ASSERT_TRUE(fs::exists(out / "summary.json")) << read_text(dir.path() / "log.txt");
  const json summary = json::parse(read_text(out / "summary.json"));
  EXPECT_EQ(summary["status"], "interrupted");
  EXPECT_GE(summary["steps"].get<int>(), 4) << "frame 1 was written at step 4";
  EXPECT_LT(summary["steps"].get<int>(), 240000);
  // The frames on disk are those the summary counts: the step under way finished with its frame.
  int frames = 0;
  for (const auto& entry : fs::directory_iterator(out / "frames")) {
    EXPECT_EQ(entry.path().extension(), ".ply") << "a temporary was left: " << entry.path();
    ++frames;
  }
  EXPECT_EQ(frames, summary["frames"].get<int>());
  EXPECT_NE(read_text(dir.path() / "log.txt").find("interrupted"), std::string::npos);
}

TEST(HostileOutput, SigtermEndsARunWithAnInterruptedSummaryAndExit143) {
  const TempDir dir;
  const fs::path out = dir.path() / "out";
  EXPECT_EQ(interrupt_run(dir, out, SIGTERM), 143) << read_text(dir.path() / "log.txt");
  EXPECT_EQ(json::parse(read_text(out / "summary.json"))["status"], "interrupted");
}

/// A tank run with the surface effect (frames 0 to 4), then reconstructed once, so that the folder holds a
/// reconstruct.json and its surfaces.
fs::path run_with_reconstruction(const TempDir& dir) {
  const fs::path out = dir.path() / "out";
  const std::string scene = dir.write("tank.json", tank_scene(0.04, 100, true));
  EXPECT_EQ(run_drench({"run", scene, "--out", out.string(), "--threads", "1", "--quiet"}, dir.path(),
                       dir.path() / "log.txt"),
            0)
      << read_text(dir.path() / "log.txt");
  EXPECT_EQ(run_drench({"reconstruct", out.string(), "--threads", "1", "--quiet"}, dir.path(),
                       dir.path() / "log.txt"),
            0)
      << read_text(dir.path() / "log.txt");
  EXPECT_TRUE(fs::exists(out / "reconstruct.json"));
  return out;
}

/// Starts `drench reconstruct` of the run in `out` on a fine grid (about 1 s a frame here), sends SIGINT once
/// its first new surface is staged, and returns its exit status.
int interrupt_reconstruct_after_its_first_surface(const TempDir& dir, const fs::path& out) {
  const pid_t pid = start_drench(
      {"reconstruct", out.string(), "--set", "surface.cell_size=0.004", "--threads", "1", "--quiet"},
      dir.path(), dir.path() / "log.txt");
  const bool started = wait_for_file(out, 30.0, [](const fs::path& p) {
    return p.parent_path().filename().string().rfind("reconstruct.tmp-", 0) == 0 &&
           p.filename() == "surface_0000.ply";
  });
  EXPECT_TRUE(started) << read_text(dir.path() / "log.txt");
  ::kill(pid, SIGINT);
  return wait_exit(pid, 30.0);
}

// SIGINT during reconstruct left surfaces at two cell sizes under a reconstruct.json of one.
TEST(HostileOutput, AnInterruptedReconstructLeavesTheEarlierSurfacesByteForByte) {
  const TempDir dir;
  const fs::path out = run_with_reconstruction(dir);
  const auto before = snapshot(out);
  EXPECT_EQ(interrupt_reconstruct_after_its_first_surface(dir, out), 130)
      << "the reconstruction ended before the signal? " << read_text(dir.path() / "log.txt");
  EXPECT_EQ(snapshot(out), before) << "the surfaces or reconstruct.json changed";
  for (const std::string& name : entries(out))
    EXPECT_EQ(name.find("reconstruct.tmp-"), std::string::npos) << "left behind: " << name;
}

// SIGINT during the last frame: reconstruct exited 0 and put the new surfaces in place, since the stop was
// checked only before each frame.
TEST(HostileOutput, ASignalDuringTheLastFrameStillLeavesTheEarlierSurfaces) {
  const TempDir dir;
  const fs::path out = dir.path() / "out";
  const std::string scene = dir.write("tank.json", tank_scene(0.01, 100, true));  // frames 0 and 1
  ASSERT_EQ(run_drench({"run", scene, "--out", out.string(), "--threads", "1", "--quiet"}, dir.path(),
                       dir.path() / "log.txt"),
            0)
      << read_text(dir.path() / "log.txt");
  const auto before = snapshot(out);
  // Frame 0's staged surface marks the start of frame 1, the last.
  EXPECT_EQ(interrupt_reconstruct_after_its_first_surface(dir, out), 130)
      << read_text(dir.path() / "log.txt");
  EXPECT_TRUE(snapshot(out) == before) << "the surfaces changed";  // not EXPECT_EQ: it would print the frames
  EXPECT_FALSE(fs::exists(out / "reconstruct.json"));
}

// A frame that is a FIFO blocked render and reconstruct forever (SIGTERM ignored), and /dev/zero as a frame
// ran render out of memory after 41 s. Both are refused at once, naming the frame.
TEST(HostileOutput, AFrameThatIsNotARegularFileIsRefusedAtOnce) {
  const TempDir dir;
  const fs::path out = dir.path() / "out";
  ASSERT_EQ(run_tank(dir, out, 3), 0) << read_text(dir.path() / "log.txt");
  const fs::path frame = out / "frames/fluid_0001.ply";
  for (const std::string kind : {"fifo", "/dev/zero"}) {
    fs::remove(frame);
    if (kind == "fifo")
      ASSERT_EQ(::mkfifo(frame.c_str(), 0600), 0);
    else
      fs::create_symlink(kind, frame);
    const auto before = entries(out);
    for (const std::vector<std::string>& command :
         {std::vector<std::string>{"render", out.string(), "--size", "64x36", "--quiet"},
          std::vector<std::string>{"reconstruct", out.string(), "--threads", "1", "--quiet"}}) {
      const auto start = std::chrono::steady_clock::now();
      EXPECT_EQ(wait_exit(start_drench(command, dir.path(), dir.path() / "log.txt"), 20.0), 1)
          << kind << " " << command[0] << ": " << read_text(dir.path() / "log.txt");
      EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 10.0);
      EXPECT_NE(read_text(dir.path() / "log.txt")
                    .find(frame.string() + ": cannot read: not a regular file (a FIFO, device or socket)"),
                std::string::npos)
          << kind << " " << command[0] << ": " << read_text(dir.path() / "log.txt");
      EXPECT_EQ(entries(out), before) << kind << " " << command[0] << " wrote into the run";
    }
  }
}

// The same through the library's stop flag, deterministically: set before the first frame is made.
TEST(HostileOutput, AReconstructStoppedByItsFlagWritesNothing) {
  const TempDir dir;
  const fs::path out = run_with_reconstruction(dir);
  const auto before = snapshot(out);
  const std::atomic<bool> stop{true};
  drench::ReconstructOptions options;
  options.run_dir = out.string();
  options.overrides = {"surface.cell_size=0.01"};
  options.progress = false;
  options.stop = &stop;
  const drench::ReconstructResult result = drench::reconstruct_run(options);
  EXPECT_TRUE(result.interrupted);
  EXPECT_EQ(result.frames, 0);
  EXPECT_EQ(snapshot(out), before);
  EXPECT_EQ(entries(out).size(), before.size() + 1) << "only the frames/ folder beside the files";
}

// render drew a frame whose cloth file was missing.
TEST(HostileOutput, RenderRefusesARunWithAMissingFrameFileNamingIt) {
  const TempDir dir;
  const fs::path out = dir.path() / "out";
  const std::string scene = dir.write("cloth.json", cloth_scene());
  ASSERT_EQ(run_drench({"run", scene, "--out", out.string(), "--threads", "1", "--quiet"}, dir.path(),
                       dir.path() / "log.txt"),
            0)
      << read_text(dir.path() / "log.txt");
  ASSERT_TRUE(fs::exists(out / "frames/cloth_0005.ply"));
  fs::remove(out / "frames/cloth_0003.ply");
  EXPECT_EQ(
      run_drench({"render", out.string(), "--size", "64x36", "--quiet"}, dir.path(), dir.path() / "log.txt"),
      1);
  EXPECT_NE(read_text(dir.path() / "log.txt")
                .find((out / "frames/cloth_0003.ply").string() + ": missing, while the run has a cloth"),
            std::string::npos)
      << read_text(dir.path() / "log.txt");
  EXPECT_FALSE(fs::exists(out / "render"));

  // A gap in the numbering: --video would have stopped there without a word.
  fs::remove(out / "frames/fluid_0003.ply");
  EXPECT_EQ(run_drench({"render", out.string(), "--size", "64x36", "--video", "--quiet"}, dir.path(),
                       dir.path() / "log.txt"),
            1);
  EXPECT_NE(
      read_text(dir.path() / "log.txt")
          .find((out / "frames/fluid_0003.ply").string() +
                ": missing, while frame 0004 exists (the frames must be numbered from 0 without a gap)"),
      std::string::npos)
      << read_text(dir.path() / "log.txt");
  EXPECT_FALSE(fs::exists(out / "render"));
}

// render --out DIR2 overwrote another program's frame_0000.png, and DIR/render took any file beside its own.
TEST(HostileOutput, RenderWritesOnlyIntoAFolderItOwns) {
  const TempDir dir;
  const fs::path out = dir.path() / "out";
  ASSERT_EQ(run_tank(dir, out, 2), 0) << read_text(dir.path() / "log.txt");
  const auto render = [&](std::vector<std::string> extra) {
    std::vector<std::string> arguments = {"render", out.string(), "--size", "64x36", "--quiet"};
    arguments.insert(arguments.end(), extra.begin(), extra.end());
    return run_drench(arguments, dir.path(), dir.path() / "log.txt");
  };
  const fs::path foreign = dir.path() / "pictures";
  fs::create_directories(foreign);
  std::ofstream(foreign / "frame_0000.png") << "the user's picture";
  for (const bool overwrite : {false, true}) {
    EXPECT_EQ(render(overwrite ? std::vector<std::string>{"--out", foreign.string(), "--overwrite"}
                               : std::vector<std::string>{"--out", foreign.string()}),
              1);
    EXPECT_NE(read_text(dir.path() / "log.txt").find((foreign / "frame_0000.png").string()),
              std::string::npos)
        << read_text(dir.path() / "log.txt");
    EXPECT_EQ(read_text(foreign / "frame_0000.png"), "the user's picture");
    EXPECT_EQ(entries(foreign), std::vector<std::string>{"frame_0000.png"});
  }

  // A folder of its own: new, then again only with --overwrite, which clears the earlier frames.
  const fs::path images = dir.path() / "images";
  ASSERT_EQ(render({"--out", images.string()}), 0) << read_text(dir.path() / "log.txt");
  EXPECT_EQ(entries(images),
            (std::vector<std::string>{"drench_run.json", "frame_0000.png", "frame_0001.png"}));
  EXPECT_EQ(render({"--out", images.string()}), 1);
  EXPECT_NE(read_text(dir.path() / "log.txt").find("add --overwrite"), std::string::npos)
      << read_text(dir.path() / "log.txt");
  std::ofstream(images / "frame_0007.png") << "an earlier render's frame";
  EXPECT_EQ(render({"--out", images.string(), "--overwrite"}), 0) << read_text(dir.path() / "log.txt");
  EXPECT_EQ(entries(images),
            (std::vector<std::string>{"drench_run.json", "frame_0000.png", "frame_0001.png"}));

  // The run's own render/ folder: an earlier render's files are replaced, anything else refuses.
  ASSERT_EQ(render({}), 0) << read_text(dir.path() / "log.txt");
  ASSERT_EQ(render({}), 0) << read_text(dir.path() / "log.txt");
  std::ofstream(out / "render/notes.txt") << "the user's notes";
  const auto before = snapshot(out);
  EXPECT_EQ(render({}), 1);
  EXPECT_NE(read_text(dir.path() / "log.txt")
                .find((out / "render/notes.txt").string() + " was not written by drench render"),
            std::string::npos)
      << read_text(dir.path() / "log.txt");
  EXPECT_TRUE(snapshot(out) == before);
}

/// The longest run of digits in `text`.
std::size_t longest_digit_run(const std::string& text) {
  std::size_t longest = 0, run = 0;
  for (const char c : text) {
    run = std::isdigit(static_cast<unsigned char>(c)) ? run + 1 : 0;
    longest = std::max(longest, run);
  }
  return longest;
}

// Command-line errors exited 105 or 109 (CLI11's codes) with a 309-digit number in the message.
TEST(HostileOutput, CommandLineErrorsExit1WithAShortMessage) {
  const TempDir dir;
  const std::string scene = dir.write("tank.json", tank_scene(0.01, 100));
  const fs::path log = dir.path() / "log.txt";
  const std::string huge = "1" + std::string(308, '0');
  for (const std::vector<std::string>& arguments :
       {std::vector<std::string>{"run", scene, "--out", "o", "--steps", huge},
        std::vector<std::string>{"run", scene, "--out", "o", "--steps", "1e308"},
        std::vector<std::string>{"run", scene, "--out", "o", "--threads", "99999999999999999999"},
        std::vector<std::string>{"run", scene, "--out", "o", "--steps", "-3"},
        std::vector<std::string>{"run", scene, "--out", "o", "--bogus"},
        std::vector<std::string>{"run", scene}, std::vector<std::string>{"frobnicate"}}) {
    std::string command;
    for (const std::string& argument : arguments)
      command += " " + argument.substr(0, 30);
    EXPECT_EQ(run_drench(arguments, dir.path(), log), 1) << command << "\n" << read_text(log);
    const std::string message = read_text(log);
    EXPECT_LE(longest_digit_run(message), 40u) << command << "\n" << message;
    EXPECT_LT(message.size(), 400u) << command << "\n" << message;
    EXPECT_EQ(message.rfind("drench: ", 0), 0u) << command << "\n" << message;
  }
  EXPECT_FALSE(fs::exists(dir.path() / "o"));
  // An empty --camera, render --out or sweep --reference meant "not given", and was ignored.
  for (const std::vector<std::string>& arguments :
       {std::vector<std::string>{"render", "o", "--camera", ""},
        std::vector<std::string>{"render", "o", "--out", ""},
        std::vector<std::string>{"sweep", scene, "--vary", "time.dt=0.001", "--out", "o", "--reference",
                                 ""}}) {
    EXPECT_EQ(run_drench(arguments, dir.path(), log), 1)
        << arguments[0] << " " << arguments[arguments.size() - 2];
    EXPECT_NE(read_text(log).find("drench: " + arguments[arguments.size() - 2] + ": must not be empty"),
              std::string::npos)
        << read_text(log);
  }
  // An OMP_NUM_THREADS drench cannot read meant every CPU, without a word.
  const char* const outer = std::getenv("OMP_NUM_THREADS");
  const std::string kept = outer ? outer : "";
  ASSERT_EQ(::setenv("OMP_NUM_THREADS", "abc", 1), 0);
  EXPECT_EQ(run_drench({"run", scene, "--out", "o", "--quiet"}, dir.path(), log), 1);
  EXPECT_NE(read_text(log).find("drench: OMP_NUM_THREADS='abc' is not a whole number in [1, "),
            std::string::npos)
      << read_text(log);
  EXPECT_EQ(run_drench({"run", scene, "--out", "o", "--quiet", "--threads", "1"}, dir.path(), log), 0)
      << read_text(log);
  if (outer)
    ::setenv("OMP_NUM_THREADS", kept.c_str(), 1);
  else
    ::unsetenv("OMP_NUM_THREADS");
  EXPECT_EQ(run_drench({"--help"}, dir.path(), log), 0) << read_text(log);
  EXPECT_NE(read_text(log).find("Subcommands:"), std::string::npos) << read_text(log);
  EXPECT_EQ(run_drench({"--version"}, dir.path(), log), 0) << read_text(log);
  EXPECT_EQ(read_text(log), std::string(DRENCH_VERSION) + "\n");
}

// What --overwrite may remove: the manifest's files and their temporaries, nothing beside them.
TEST(HostileOutput, ManifestPatternsCoverOnlyDrenchsFiles) {
  using drench::output_pattern_covers;
  EXPECT_TRUE(output_pattern_covers("frames/fluid_*.ply", "frames/fluid_0001.ply"));
  EXPECT_TRUE(output_pattern_covers("frames/fluid_*.ply", "frames/fluid_0001.ply.tmp-4242"));
  EXPECT_FALSE(output_pattern_covers("frames/fluid_*.ply", "frames/fluid_0001.ply.tmp-"));
  EXPECT_FALSE(output_pattern_covers("frames/fluid_*.ply", "frames/fluid_0001.ply.tmp-42x"));
  EXPECT_FALSE(output_pattern_covers("frames/fluid_*.ply", "frames/fluid_0001.ply.bak"));
  EXPECT_FALSE(output_pattern_covers("frames/fluid_*.ply", "frames/old/fluid_0001.ply"));
  EXPECT_FALSE(output_pattern_covers("frames/fluid_*.ply", "fluid_0001.ply"));
  EXPECT_FALSE(output_pattern_covers("summary.json", "summary.json.orig"));
  EXPECT_TRUE(
      output_pattern_covers("reconstruct.tmp-*/surface_*.ply", "reconstruct.tmp-77/surface_0003.ply"));
  const auto covered = [](const std::string& file) {
    for (const std::string& pattern : drench::sweep_output_patterns())
      if (output_pattern_covers(pattern, file)) return true;
    return false;
  };
  EXPECT_TRUE(covered("runs/001/frames/cloth_0000.ply"));
  EXPECT_TRUE(covered("runs/012.log"));
  EXPECT_TRUE(covered("runs/001/drench_run.json"));
  EXPECT_FALSE(covered("runs/001/notes.txt"));
  EXPECT_FALSE(covered("notes.txt"));
}

// A huge scene aborted with an uncaught std::bad_alloc (exit 134), and surface.cell_size=1e-7 with an
// uncaught openvdb::ArithmeticError. Either is now one line and exit 1 (before the simulation started) or 2
// (after), or a refusal of the value (1); never an abort.
TEST(HostileOutput, OutOfMemoryAndForeignErrorsAreOneLineNotAnAbort) {
  const TempDir dir;
  const std::string scene = dir.write("tank.json", tank_scene(0.01, 100));
  const fs::path log = dir.path() / "log.txt";
  // 48 million particles of 1 mm, in an address space of 1.5 GB.
  const int out_of_memory = wait_exit(start_drench({"run", scene, "--out", (dir.path() / "huge").string(),
                                                    "--quiet", "--set", "fluid.particle_spacing=0.001"},
                                                   dir.path(), log, rlim_t(1500) << 20),
                                      60.0);
  EXPECT_EQ(out_of_memory, 1) << read_text(log);
  std::string message = read_text(log);
  EXPECT_EQ(message.rfind("drench: ", 0), 0u) << message;
  EXPECT_EQ(std::count(message.begin(), message.end(), '\n'), 1) << message;
  EXPECT_FALSE(fs::exists(dir.path() / "huge")) << "refused before the folder was made";

  const int foreign = run_drench({"run", scene, "--out", (dir.path() / "vdb").string(), "--quiet", "--set",
                                  "effects=[\"surface\"]", "--set", "surface.cell_size=1e-7"},
                                 dir.path(), log);
  EXPECT_TRUE(foreign == 1 || foreign == 2) << foreign << "\n" << read_text(log);
  message = read_text(log);
  EXPECT_EQ(message.rfind("drench: ", 0), 0u) << message;
  EXPECT_EQ(std::count(message.begin(), message.end(), '\n'), 1) << message;
}

// NaN figures were written as a bare null in summary.json.
TEST(HostileOutput, ANonFiniteSummaryFigureIsNullWithANoteSayingWhich) {
  json summary = {{"steps", 3},
                  {"energy_drift", std::nan("")},
                  {"density_error", {{"mean", 0.01}, {"max", std::numeric_limits<double>::infinity()}}},
                  {"list", {1.0, -std::numeric_limits<double>::infinity()}}};
  drench::apply_non_finite_rule(summary);
  const json written = json::parse(summary.dump());
  EXPECT_TRUE(written["energy_drift"].is_null());
  EXPECT_TRUE(written["density_error"]["max"].is_null());
  EXPECT_EQ(written["density_error"]["mean"], 0.01);
  EXPECT_EQ(written["non_finite"],
            json({{"energy_drift", "nan"}, {"density_error.max", "inf"}, {"list[1]", "-inf"}}));
  // Applied twice (make_summary, then run_scene after its own keys), the notes stay.
  drench::apply_non_finite_rule(summary);
  EXPECT_EQ(json::parse(summary.dump()), written);
}

// A sweep into a folder that holds an earlier sweep: refused, or replaced with --overwrite.
TEST(HostileOutput, ASweepIntoAReusedFolderIsRefusedUnlessOverwrite) {
  const TempDir dir;
  const std::string scene = dir.write("tank.json", tank_scene(0.02, 0));
  const fs::path out = dir.path() / "sweep";
  const fs::path log = dir.path() / "log.txt";
  const std::vector<std::string> sweep = {"sweep",      scene,       "--vary", "time.dt=0.005", "--out",
                                          out.string(), "--threads", "1",      "--quiet"};
  ASSERT_EQ(run_drench(sweep, dir.path(), log), 0) << read_text(log);
  ASSERT_TRUE(fs::exists(out / "runs/001/summary.json")) << read_text(log);
  EXPECT_TRUE(fs::exists(out / "runs/001.log"));
  const auto before = snapshot(out);
  EXPECT_EQ(run_drench(sweep, dir.path(), log), 1);
  EXPECT_NE(read_text(log).find("the folder is not empty"), std::string::npos) << read_text(log);
  EXPECT_EQ(snapshot(out), before);
  std::vector<std::string> again = sweep;
  again.push_back("--overwrite");
  EXPECT_EQ(run_drench(again, dir.path(), log), 0) << read_text(log);
  EXPECT_TRUE(fs::exists(out / "runs/001/summary.json"));
  EXPECT_EQ(json::parse(read_text(out / drench::kOutputManifest))["command"], "sweep");
}

// SIGINT to a sweep: passed on once to the run under way, which ends "interrupted"; the next is not started.
TEST(HostileOutput, ASweepPassesSigintOnToItsRunAndExits130) {
  const TempDir dir;
  const std::string scene = dir.write("long.json", tank_scene(600, 100));
  const fs::path out = dir.path() / "sweep";
  const pid_t pid = start_drench(
      {"sweep", scene, "--vary", "time.dt=0.0025,0.002", "--out", out.string(), "--threads", "1", "--quiet"},
      dir.path(), dir.path() / "log.txt");
  const bool started =
      wait_for_file(out, 30.0, [](const fs::path& p) { return p.filename() == "fluid_0001.ply"; });
  EXPECT_TRUE(started) << read_text(dir.path() / "log.txt");
  ::kill(pid, SIGINT);
  EXPECT_EQ(wait_exit(pid, 30.0), 130) << read_text(dir.path() / "log.txt");
  EXPECT_EQ(json::parse(read_text(out / "runs/001/summary.json"))["status"], "interrupted");
  EXPECT_FALSE(fs::exists(out / "runs/002"));
  const std::string csv = read_text(out / "sweep.csv");
  EXPECT_NE(csv.find("\n1,time.dt=0.0025,0,0.0025,interrupted,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\n2,time.dt=0.002,0,0.002,not run: the sweep was interrupted,"), std::string::npos)
      << csv;
}

}  // namespace
