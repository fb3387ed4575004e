#include "sweep_command.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <thread>

#include <drench/common/error.hpp>
#include <drench/common/parallel.hpp>
#include <drench/common/program.hpp>
#include <drench/compare/run_comparison.hpp>
#include <drench/io/atomic_file.hpp>
#include <drench/io/ply_reader.hpp>
#include <drench/scene/output_folder.hpp>
#include <drench/scene/run_frames.hpp>
#include <drench/scene/scene_loader.hpp>
#include <drench/scene/scene_resources.hpp>

#include "stop_signal.hpp"

extern char** environ;

namespace drench {

namespace fs = std::filesystem;

namespace {

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char c : text)
    quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

/// A run's setting, for the report's tables and the plot's labels.
const std::string& setting_of(const SweepRun& run) {
  return run.label;
}

std::string cpu_model() {
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  while (std::getline(cpuinfo, line)) {
    if (line.rfind("model name", 0) == 0) {
      const std::size_t colon = line.find(':');
      if (colon != std::string::npos) return line.substr(colon + 2);
    }
  }
  return "unknown CPU";
}

std::string last_line(const fs::path& file) {
  std::ifstream in(file);
  std::string line, last;
  while (std::getline(in, line)) {
    // The progress line's carriage returns leave only its last state on a line.
    const std::size_t cr = line.find_last_of('\r');
    if (cr != std::string::npos) line = line.substr(cr + 1);
    if (!line.empty()) last = line;
  }
  return last;
}

struct Child {
  pid_t pid = 0;
  std::size_t run = 0;
  std::chrono::steady_clock::time_point start;
  bool timed_out = false;  ///< killed for running past --timeout
};

/// Starts `arguments` with stdout and stderr into `log`, in a process group of its own: a Ctrl-C at the
/// terminal reaches the sweep alone, which passes it on once (a second signal would end a run at once).
/// @throws IoError when it cannot start.
pid_t spawn_logged(const std::vector<std::string>& arguments, const fs::path& log) {
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);
  posix_spawnattr_setpgroup(&attributes, 0);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  std::vector<char*> argv;
  for (const std::string& argument : arguments)
    argv.push_back(const_cast<char*>(argument.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int error = posix_spawn(&pid, argv[0], &actions, &attributes, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  if (error != 0) throw IoError("sweep: cannot start " + arguments[0] + ": " + std::strerror(error));
  return pid;
}

/// The median of the finite values, NaN when there is none.
double median(std::vector<double> values) {
  values.erase(std::remove_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); }),
               values.end());
  if (values.empty()) return std::nan("");
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

std::string format(double value, const char* spec = "%.4g") {
  if (!std::isfinite(value)) return "-";
  char text[32];
  std::snprintf(text, sizeof text, spec, value);
  return text;
}

/// One point of the plot: a setting's medians over its repeats.
struct SettingPoint {
  std::string setting;
  double time = 0, error = 0;
  int runs = 0, failed = 0;
  /// Why it is drawn apart and never on the front, e.g. "leaked", "RUNAWAY_NODE", "timed out"; "" when every
  /// run of it ended "ok" without a leak. A run that leaked, blew up or stopped is no solution, however small
  /// its error over the frames it has.
  std::string apart;
};

/// A status's first words, for a label: "RUNAWAY_NODE: cloth node 3 ..." -> "RUNAWAY_NODE".
std::string short_status(const std::string& status) {
  std::string text = status.substr(0, status.find_first_of(":;"));
  if (text.size() > 30) text = text.substr(0, 30);
  return text;
}

/// The axis label of an error column: the density error is the pressure solver's residual, not how right
/// the result is (issue 42), and says so.
std::string error_label(const std::string& key) {
  if (key.rfind("density_error", 0) == 0) return key + " (solver residual, fraction of rest density)";
  return key;
}

/// DIR/reference.json of a `drench reference` folder. @throws IoError naming the file
nlohmann::json read_reference_record(const std::string& dir) {
  const fs::path file = fs::path(dir) / "reference.json";
  std::ifstream in(file);
  if (!in)
    throw IoError("--reference " + file.string() +
                  ": missing or unreadable; make the folder with `drench reference SCENE --out " + dir + "`");
  try {
    nlohmann::json record = nlohmann::json::parse(in);
    if (!record.contains("scene_sha256") || !record["scene_sha256"].is_string())
      throw IoError("--reference " + file.string() + ": has no scene_sha256");
    return record;
  } catch (const nlohmann::json::exception& e) {
    throw IoError("--reference " + file.string() + ": not JSON: " + e.what());
  }
}

/// The comparison as JSON for runs/NNN.comparison.json: each observable's per-frame differences and the
/// series of both runs over time.
nlohmann::json comparison_json(const RunComparison& c, const RunFrames& reference) {
  nlohmann::json out;
  out["frames"] = c.frames;
  out["times_s"] = std::vector<double>(reference.times.begin(), reference.times.begin() + c.frames);
  out["worst_observable"] = c.worst;
  out["worst_relative_error"] = std::isfinite(c.worst_relative) ? nlohmann::json(c.worst_relative) : nullptr;
  auto numbers = [](const std::vector<double>& values) {
    nlohmann::json list = nlohmann::json::array();
    for (const double v : values)
      list.push_back(std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr));
    return list;
  };
  for (const ObservableError& e : c.observables) {
    out["observables"][e.name] = {
        {"largest", std::isfinite(e.largest) ? nlohmann::json(e.largest) : nullptr},
        {"normaliser", std::isfinite(e.normaliser) ? nlohmann::json(e.normaliser) : nullptr},
        {"relative", std::isfinite(e.relative) ? nlohmann::json(e.relative) : nullptr},
        {"per_frame", numbers(e.per_frame)}};
  }
  for (std::size_t k = 0; k < c.series_names.size(); ++k) {
    out["series"]["run"][c.series_names[k]] = numbers(c.run_series[k]);
    out["series"]["reference"][c.series_names[k]] = numbers(c.reference_series[k]);
  }
  return out;
}

std::string gnuplot_label(std::string text) {
  std::replace(text.begin(), text.end(), '"', '\'');
  return "\"" + text + "\"";
}

/// pareto.png through gnuplot; an empty string, or why there is no plot.
std::string plot_pareto(const fs::path& dir, const std::vector<SettingPoint>& points,
                        const std::vector<std::size_t>& front, const std::string& error_key) {
  const std::string gnuplot = find_program("gnuplot");
  if (gnuplot.empty())
    return "no pareto.png: gnuplot is not installed (Debian: sudo apt-get install gnuplot-nox)";
  std::ostringstream all, best, apart;
  bool positive = true;
  double low = INFINITY, high = 0;
  for (const SettingPoint& p : points) {
    if (!std::isfinite(p.time) || !std::isfinite(p.error)) continue;
    (p.apart.empty() ? all : apart) << format(p.time, "%.9g") << ' ' << format(p.error, "%.9g") << ' '
                                    << gnuplot_label(p.apart.empty() ? p.setting
                                                                     : p.setting + " (" + p.apart + ")")
                                    << '\n';
    positive = positive && p.error > 0;
    low = std::min(low, p.error);
    high = std::max(high, p.error);
  }
  for (const std::size_t i : front)
    best << format(points[i].time, "%.9g") << ' ' << format(points[i].error, "%.9g") << ' '
         << gnuplot_label(points[i].setting) << '\n';
  write_file_atomic((dir / "pareto_all.dat").string(), all.str());
  write_file_atomic((dir / "pareto_apart.dat").string(), apart.str());
  write_file_atomic((dir / "pareto_front.dat").string(), best.str());
  const std::string temporary = (dir / ("pareto.png.tmp-" + std::to_string(::getpid()))).string();
  std::ostringstream script;
  script << "set terminal pngcairo size 1100,700 font ',10' noenhanced\n"
         << "set output '" << temporary << "'\n"
         << "set xlabel 'wall time of the run (s)'\n"
         << "set ylabel '" << error_label(error_key) << "'\n"
         << "set grid\nset key top right\n"
         << "set title 'Each setting (median of its runs); the Pareto front: no other setting is both faster "
            "and more accurate'\n"
         << (positive && high > 20 * low ? "set logscale y\n" : "") << "plot '"
         << (dir / "pareto_all.dat").string()
         << "' using 1:2 with points pt 7 ps 1.1 lc rgb '#999999' title 'settings', \\\n"
         << (apart.str().empty() ? ""
                                 : "  '" + (dir / "pareto_apart.dat").string() +
                                       "' using 1:2 with points pt 2 ps 1.4 lw 2 lc rgb '#c0392b' title "
                                       "'not ok: leaked, blew up, stopped or too fast (never on the front)', "
                                       "\\\n  '' using 1:2:3 with "
                                       "labels left offset 0.8,0.6 font ',9' tc rgb '#c0392b' notitle, \\\n")
         << "  '" << (dir / "pareto_front.dat").string()
         << "' using 1:2 with linespoints pt 7 ps 1.4 lw 2 lc rgb '#1f5fa8' title 'Pareto front', \\\n"
         << "  '' using 1:2:3 with labels left offset 0.8,0.6 font ',9' notitle\n";
  write_file_atomic((dir / "pareto.gp").string(), script.str());
  if (run_program({gnuplot, (dir / "pareto.gp").string()}) != 0 || !fs::exists(temporary)) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    return "no pareto.png: gnuplot failed on " + (dir / "pareto.gp").string();
  }
  fs::rename(temporary, dir / "pareto.png");
  return "";
}

}  // namespace

int run_sweep(const SweepOptions& options) {
  // The reference first: the columns and the error's default depend on it.
  const bool with_reference = !options.reference_dir.empty();
  nlohmann::json reference_record;
  RunFrames reference;
  const ComparisonSettings& measure = options.comparison;
  if (with_reference) {
    reference_record = read_reference_record(options.reference_dir);
    reference = read_run_frames(options.reference_dir);
    check_comparison_settings(measure, reference);
    // Every frame of the reference read once now: a damaged one was found only after all the runs.
    for (std::size_t n = 0; n < reference.fluid_files.size(); ++n) {
      (void)read_ply(reference.fluid_files[n]);
      if (!reference.cloth_files.empty()) (void)read_ply(reference.cloth_files[n]);
    }
  } else if (!measure.gauges_x.empty() || measure.gauge_width > 0 || measure.gauge_depth > 0 ||
             measure.cell_size > 0) {
    throw SceneError(std::string(!measure.gauges_x.empty() ? "--gauge"
                                 : measure.gauge_width > 0 ? "--gauge-width"
                                 : measure.gauge_depth > 0 ? "--gauge-depth"
                                                           : "--cell-size") +
                     " measures the runs against a reference: it needs --reference");
  }
  if (measure.gauges_x.empty() && (measure.gauge_width > 0 || measure.gauge_depth > 0))
    throw SceneError(std::string(measure.gauge_width > 0 ? "--gauge-width" : "--gauge-depth") +
                     " sets the gauges' columns: it needs at least one --gauge");
  std::vector<std::string> columns = sweep_columns();
  if (with_reference) columns.insert(columns.end(), reference_columns().begin(), reference_columns().end());
  std::string error_key = options.error_key;
  if (error_key.empty())
    error_key = !with_reference                 ? "density_error_mean"
                : reference.cloth_files.empty() ? "front_m"
                                                : "cloth_rms_m";
  const auto error_column = std::find(columns.begin(), columns.end(), error_key);
  if (error_column == columns.end() || error_key == "status" || error_key == "worst_observable") {
    std::string known;
    for (std::size_t c = 1; c < columns.size(); ++c)
      if (columns[c] != "worst_observable") known += (c > 1 ? ", " : "") + columns[c];
    throw SceneError("--error " + error_key + ": not a column" +
                     (with_reference ? "" : " (the errors against a reference need --reference)") +
                     "; one of " + known);
  }
  // An observable this reference does not have would be an empty column, and no plot.
  const std::vector<std::string>& all_observables = observable_names();
  if (with_reference &&
      std::find(all_observables.begin(), all_observables.end(), error_key) != all_observables.end()) {
    const std::vector<std::string> reported =
        reported_observables(!reference.cloth_files.empty(), !measure.gauges_x.empty());
    if (std::find(reported.begin(), reported.end(), error_key) == reported.end()) {
      std::string list;
      for (const std::string& name : reported)
        list += (list.empty() ? "" : ", ") + name;
      throw SceneError("--error " + error_key + ": the reference " + options.reference_dir +
                       (reference.cloth_files.empty() ? " has no cloth" : " has a cloth") +
                       (measure.gauges_x.empty() ? " and there is no --gauge" : "") +
                       ", so the sweep measures only " + list + ", worst_relative_error");
    }
  }
  if (options.jobs < 1) throw SceneError("--jobs must be >= 1");
  check_output_folder(options.out_dir, "--out", "sweep", sweep_output_patterns(), options.overwrite);

  // Every setting is validated as `drench run` would before anything is written or started.
  const nlohmann::json scene = read_scene_document(options.scene_path, options.overrides);
  parse_scene(scene, scene_source(options.scene_path, options.overrides));
  if (with_reference) {
    // A reference of another scene (or of other --set's) would measure the difference of two scenes.
    const std::string sha = sha256_hex(canonical_scene_text(scene));
    if (reference_record["scene_sha256"] != sha) {
      throw SceneError("--reference " + options.reference_dir + ": made of a scene whose scene_sha256 is " +
                       reference_record["scene_sha256"].get<std::string>() +
                       ", the sweep's scene with its --set's has " + sha +
                       "; make the reference with the same scene file and --set's as the sweep");
    }
  }
  const std::vector<SweepRun> runs =
      plan_sweep(scene, options.axes, options.cases, options.one_at_a_time, options.repeats);
  // And each run's resources, as `drench run` checks them: the runs side by side share the memory, and
  // all of them write to the same disk.
  ResourceLimits limits = machine_limits(options.out_dir, kDefaultMaxOutputBytes);
  limits.memory_bytes /= options.jobs;
  if (options.jobs > 1)
    limits.memory_of = "available to each of --jobs " + std::to_string(options.jobs) +
                       " runs (MemAvailable / " + std::to_string(options.jobs) + ")";
  double output_bytes = 0;
  double setting_output_bytes = 0;
  for (const SweepRun& run : runs) {
    // A repeat is its setting again: checked once.
    if (run.repeat > 0) {
      output_bytes += setting_output_bytes;
      continue;
    }
    std::vector<std::string> all = options.overrides;
    all.insert(all.end(), run.assignments.begin(), run.assignments.end());
    nlohmann::json document = scene;
    for (const std::string& assignment : run.assignments)
      apply_override(document, assignment);
    const SceneConfig config = parse_scene(document, scene_source(options.scene_path, all));
    // Each setting's frames must be at the reference's times: else the error measured includes the flow's
    // motion between the two instants.
    for (std::size_t n = 0; with_reference && n < reference.times.size(); ++n) {
      const double t =
          config.time.frame_rate > 0 ? frame_time(config.time, static_cast<std::int64_t>(n)) : NAN;
      if (!(std::abs(t - reference.times[n]) <= options.comparison.time_tolerance)) {
        throw SceneError("sweep: setting " + run.label + ": its frame " + std::to_string(n) +
                         " would be at t = " + format_number(t) + " s, the reference's is at " +
                         format_number(reference.times[n]) +
                         " s; choose time.frame_rate so that every frame's time is a whole number of every "
                         "setting's time.dt (e.g. 50 frames/s for dt 1, 2 and 4 ms)");
      }
    }
    const ResourceEstimate estimate = estimate_resources(config);
    check_resources(config, estimate, limits);
    setting_output_bytes = estimate.output_bytes.value;
    output_bytes += setting_output_bytes;
  }
  if (!(output_bytes <= limits.disk_bytes)) {
    throw SceneError("sweep: its " + std::to_string(runs.size()) + " runs make about " +
                     format_number(output_bytes) + " bytes of output, more than the " +
                     format_number(limits.disk_bytes) + " bytes free on the disk of --out");
  }

  const fs::path dir = options.out_dir;
  prepare_output_folder(options.out_dir, "--out", "sweep", sweep_output_patterns(), options.overwrite);
  std::error_code error;
  fs::create_directories(dir / "runs", error);
  if (error) throw IoError("sweep: cannot create " + (dir / "runs").string() + ": " + error.message());

  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  const int threads = options.threads > 0 ? options.threads : std::max(1, thread_count() / options.jobs);
  const std::size_t width = std::to_string(runs.size()).size() < 3 ? 3 : std::to_string(runs.size()).size();
  auto run_dir = [&](std::size_t i) {
    std::string number = std::to_string(i + 1);
    return dir / "runs" / (std::string(width - number.size(), '0') + number);
  };
  // Beside the run's folder, not in it: `drench run` writes only into a folder of its own.
  auto run_log = [&](std::size_t i) { return fs::path(run_dir(i).string() + ".log"); };

  // The axes' values as each run had them: its own, else the scene's.
  std::vector<std::string> axis_keys;
  for (const SweepAxis& axis : options.axes)
    if (std::find(axis_keys.begin(), axis_keys.end(), axis.key) == axis_keys.end())
      axis_keys.push_back(axis.key);
  for (const SweepCase& c : options.cases)
    for (const std::string& assignment : c.assignments) {
      const std::string key = assignment.substr(0, assignment.find('='));
      if (std::find(axis_keys.begin(), axis_keys.end(), key) == axis_keys.end()) axis_keys.push_back(key);
    }
  auto value_of = [&](const SweepRun& run, const std::string& key) -> std::string {
    for (auto it = run.assignments.rbegin(); it != run.assignments.rend(); ++it)
      if (it->compare(0, key.size() + 1, key + "=") == 0) return it->substr(key.size() + 1);
    return "";  // the scene's own value
  };

  std::vector<std::vector<std::string>> rows(runs.size());
  std::vector<bool> done(runs.size(), false);
  auto write_csv = [&]() {
    std::ostringstream csv;
    csv << "run,setting,repeat";
    for (const std::string& key : axis_keys)
      csv << ',' << csv_field(key);
    for (const std::string& column : columns)
      csv << ',' << column;
    csv << '\n';
    for (std::size_t i = 0; i < runs.size(); ++i) {
      if (!done[i]) continue;
      csv << i + 1 << ',' << csv_field(setting_of(runs[i])) << ',' << runs[i].repeat;
      for (const std::string& key : axis_keys)
        csv << ',' << csv_field(value_of(runs[i], key));
      for (const std::string& field : rows[i])
        csv << ',' << csv_field(field);
      csv << '\n';
    }
    write_file_atomic((dir / "sweep.csv").string(), csv.str());
  };

  const auto sweep_start = std::chrono::steady_clock::now();
  std::vector<Child> running;
  std::size_t next = 0, finished = 0;
  int failures = 0;
  install_stop_handler(false);
  bool stop_passed_on = false;
  while (finished < runs.size()) {
    if (stop_signal() != 0 && !stop_passed_on) {
      // Each run under way ends after its step as "interrupted"; the runs not started are rows that say so.
      for (const Child& c : running)
        ::kill(c.pid, stop_signal());
      stop_passed_on = true;
      for (; next < runs.size(); ++next) {
        rows[next] = sweep_row(nullptr, "not run: the sweep was interrupted");
        done[next] = true;
        ++finished;
        ++failures;
      }
      write_csv();
      continue;
    }
    while (next < runs.size() && static_cast<int>(running.size()) < options.jobs) {
      const fs::path out = run_dir(next);
      std::vector<std::string> arguments = {options.program, "run",       options.scene_path,      "--out",
                                            out.string(),    "--threads", std::to_string(threads), "--quiet"};
      std::vector<std::string> all = options.overrides;
      all.insert(all.end(), runs[next].assignments.begin(), runs[next].assignments.end());
      for (const std::string& assignment : all) {
        arguments.push_back("--set");
        arguments.push_back(assignment);
      }
      running.push_back({spawn_logged(arguments, run_log(next)), next, std::chrono::steady_clock::now()});
      ++next;
    }
    if (running.empty()) continue;
    int status = 0;
    // Polled rather than blocking, so that a run past --timeout is stopped (a setting that slows to a crawl,
    // a blow-up the CFL limit keeps sub-stepping, is a row, not a sweep that never ends) and a stop signal
    // is passed on at once.
    const pid_t pid = ::waitpid(-1, &status, WNOHANG);
    if (pid < 0) {
      if (errno == EINTR) continue;
      throw IoError(std::string("sweep: waitpid: ") + std::strerror(errno));
    }
    if (pid == 0) {
      const auto now = std::chrono::steady_clock::now();
      for (Child& c : running) {
        if (options.timeout_s > 0 && !c.timed_out &&
            std::chrono::duration<double>(now - c.start).count() > options.timeout_s) {
          ::kill(c.pid, SIGKILL);
          c.timed_out = true;
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      continue;
    }
    const auto child =
        std::find_if(running.begin(), running.end(), [&](const Child& c) { return c.pid == pid; });
    if (child == running.end()) continue;
    const std::size_t i = child->run;
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - child->start).count();
    const bool timed_out = child->timed_out;
    running.erase(child);

    const fs::path out = run_dir(i);
    std::string failure;
    if (timed_out) {
      failure = "timed out: stopped after " + format(options.timeout_s, "%g") + " s";
    } else if (WIFSIGNALED(status)) {
      failure = "killed by signal " + std::to_string(WTERMSIG(status));
    } else if (WIFEXITED(status) && WEXITSTATUS(status) == 1) {
      failure = "error: " + last_line(run_log(i));
    } else if (WIFEXITED(status) &&
               (WEXITSTATUS(status) == 128 + SIGINT || WEXITSTATUS(status) == 128 + SIGTERM) &&
               fs::exists(out / "summary.json")) {
      // A run that a stop signal ended cleanly: its summary's status says "interrupted".
    } else if (WIFEXITED(status) && WEXITSTATUS(status) > 2) {
      failure = "exit " + std::to_string(WEXITSTATUS(status)) + ": " + last_line(run_log(i));
    }
    nlohmann::json summary;
    bool have_summary = false;
    if (std::ifstream in(out / "summary.json"); in) {
      try {
        in >> summary;
        have_summary = true;
      } catch (const nlohmann::json::exception&) {
        failure += failure.empty() ? "unreadable summary.json" : "; unreadable summary.json";
      }
    }
    rows[i] = sweep_row(have_summary ? &summary : nullptr, failure);
    if (with_reference) {
      std::optional<RunComparison> comparison;
      try {
        ComparisonSettings settings = options.comparison;
        // A run that stopped (a blow-up, a timeout) is compared over the frames it has; it is drawn apart.
        settings.allow_shorter = rows[i][0] != "ok";
        comparison = compare_runs(read_run_frames(out.string()), reference, settings);
        write_file_atomic(out.string() + ".comparison.json",
                          comparison_json(*comparison, reference).dump(1) + "\n");
      } catch (const Error& e) {
        rows[i][0] =
            (rows[i][0] == "ok" ? "" : rows[i][0] + "; ") + "not compared with the reference: " + e.what();
      }
      const std::vector<std::string> extra = reference_row(comparison ? &*comparison : nullptr);
      rows[i].insert(rows[i].end(), extra.begin(), extra.end());
    }
    done[i] = true;
    ++finished;
    if (rows[i][0] != "ok") ++failures;
    write_csv();
    if (!options.quiet) {
      const double elapsed =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - sweep_start).count();
      const double eta = elapsed / finished * static_cast<double>(runs.size() - finished);
      std::fprintf(stderr, "sweep [%zu/%zu] %s: %s in %.1f s, %s %s; ETA %.0f s\n", finished, runs.size(),
                   setting_of(runs[i]).c_str(), rows[i][0].c_str(), seconds, error_key.c_str(),
                   rows[i][error_column - columns.begin()].empty()
                       ? "-"
                       : rows[i][error_column - columns.begin()].c_str(),
                   eta);
    }
  }

  // One point per setting: the medians over its repeats; a setting whose every run failed has no point.
  const std::size_t error_index = static_cast<std::size_t>(error_column - columns.begin());
  const std::size_t wall_index =
      static_cast<std::size_t>(std::find(columns.begin(), columns.end(), "wall_s") - columns.begin());
  std::vector<SettingPoint> points;
  std::map<std::string, std::size_t> point_of;
  std::map<std::string, std::vector<double>> times, errors;
  const std::size_t leaks_index =
      static_cast<std::size_t>(std::find(columns.begin(), columns.end(), "leaks") - columns.begin());
  const std::size_t particle_speed_index = static_cast<std::size_t>(
      std::find(columns.begin(), columns.end(), "max_particle_speed_mps") - columns.begin());
  const std::size_t node_speed_index = static_cast<std::size_t>(
      std::find(columns.begin(), columns.end(), "max_node_speed_mps") - columns.begin());
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const std::string setting = setting_of(runs[i]);
    if (!point_of.count(setting)) {
      point_of[setting] = points.size();
      points.push_back({setting, 0, 0, 0, 0, ""});
    }
    SettingPoint& p = points[point_of[setting]];
    ++p.runs;
    if (rows[i][0] != "ok") {
      ++p.failed;
      if (p.apart.empty()) p.apart = short_status(rows[i][0]);
    }
    if (sweep_number(rows[i][leaks_index]) > 0 && p.apart.empty()) p.apart = "leaked";
    // NaN (no summary) compares false: such a run did not end "ok" and is apart already.
    const double fastest =
        std::fmax(sweep_number(rows[i][particle_speed_index]), sweep_number(rows[i][node_speed_index]));
    if (options.speed_bound_mps > 0 && fastest > options.speed_bound_mps && p.apart.empty())
      p.apart = "faster than " + format(options.speed_bound_mps, "%g") + " m/s";
    double e = sweep_number(rows[i][error_index]);
    if (error_key == "energy_drift") e = std::abs(e);
    times[setting].push_back(sweep_number(rows[i][wall_index]));
    errors[setting].push_back(e);
  }
  std::vector<std::pair<double, double>> xy;
  for (SettingPoint& p : points) {
    p.time = median(times[p.setting]);
    p.error = median(errors[p.setting]);
    // Water through the cloth is the failure drench exists to prevent, and a run that blew up or stopped
    // has no answer: such a setting is drawn apart and never on the front.
    xy.emplace_back(!p.apart.empty() ? std::nan("") : p.time, p.error);
  }
  const std::vector<std::size_t> front = pareto_front(xy);
  const std::string plot_note = plot_pareto(dir, points, front, error_key);
  if (!plot_note.empty()) std::fprintf(stderr, "drench: %s\n", plot_note.c_str());

  // The report: what ran, where, and what it cost.
  std::ostringstream md;
  const std::time_t now = std::time(nullptr);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  md << "# Sweep of `" << options.scene_path << "`\n\n"
     << "`" << options.command_line << "`\n\n"
     << runs.size() << " runs (" << points.size() << " settings x " << options.repeats << "), "
     << options.jobs << " at a time with " << threads << " threads each, on " << cpu_model() << " (" << cores
     << " cores), " << date << ", drench " << DRENCH_VERSION << ". " << failures
     << " runs did not end \"ok\". One row per run in "
     << "[sweep.csv](sweep.csv); each run's files in `runs/NNN/`, its output in `runs/NNN.log`.\n\n";
  if (with_reference) {
    md << "Errors against the reference `" << options.reference_dir << "` (" << reference.times.size()
       << " frames; " << reference_record.value("refinement", nlohmann::json::object()).dump()
       << "): each observable's largest difference over the frames, its unit in its name, per run in "
          "`runs/NNN.comparison.json` frame by frame. `density_error_mean` is the pressure solver's "
          "residual, "
          "not the error of the result.\n\n";
  }
  md << "| setting | runs | wall s | fluid s | cloth s | coupling s | surface s | " << error_label(error_key)
     << (with_reference ? " | worst relative error" : "")
     << " | leaks | max particle m/s | status |\n|---|---|---|---|---|---|---|---|"
     << (with_reference ? "---|" : "") << "---|---|---|\n";
  auto column_median = [&](const std::string& setting, const char* column) {
    const std::size_t c =
        static_cast<std::size_t>(std::find(columns.begin(), columns.end(), column) - columns.begin());
    std::vector<double> values;
    for (std::size_t i = 0; i < runs.size(); ++i)
      if (setting_of(runs[i]) == setting && rows[i][0] == "ok") values.push_back(sweep_number(rows[i][c]));
    return median(values);
  };
  for (const SettingPoint& p : points) {
    std::string statuses;
    for (std::size_t i = 0; i < runs.size(); ++i)
      if (setting_of(runs[i]) == p.setting && rows[i][0] != "ok")
        statuses += (statuses.empty() ? "" : "; ") + rows[i][0];
    std::string setting = p.setting;
    std::replace(setting.begin(), setting.end(), '|', '/');
    md << "| `" << setting << "` | " << p.runs << " | " << format(p.time, "%.2f") << " | "
       << format(column_median(p.setting, "fluid_s"), "%.2f") << " | "
       << format(column_median(p.setting, "cloth_s"), "%.2f") << " | "
       << format(column_median(p.setting, "coupling_s"), "%.2f") << " | "
       << format(column_median(p.setting, "surface_s"), "%.2f") << " | " << format(p.error) << " | ";
    if (with_reference) {
      std::string worst;
      for (std::size_t i = 0; i < runs.size() && worst.empty(); ++i)
        if (setting_of(runs[i]) == p.setting) worst = rows[i].back();
      md << format(column_median(p.setting, "worst_relative_error"))
         << (worst.empty() ? "" : " (" + worst + ")") << " | ";
    }
    md << format(column_median(p.setting, "leaks"), "%.0f") << " | "
       << format(column_median(p.setting, "max_particle_speed_mps"), "%.3g") << " | "
       << (!statuses.empty() ? statuses
           : p.apart.empty() ? "ok"
                             : "ok, " + p.apart)
       << " |\n";
  }
  md << "\nThe Pareto front of wall time against " << error_label(error_key)
     << " (no other setting is both faster and more accurate; settings with a run that leaked, blew up or "
        "stopped"
     << (options.speed_bound_mps > 0
             ? ", or went faster than " + format(options.speed_bound_mps, "%g") + " m/s (--speed-bound),"
             : "")
     << " are left out), fastest first:";
  for (std::size_t k = 0; k < front.size(); ++k)
    md << (k ? ", " : " ") << "`" << points[front[k]].setting << "`";
  md << ".\n\n" << (plot_note.empty() ? "![wall time against the error](pareto.png)\n" : plot_note + "\n");
  write_file_atomic((dir / "report.md").string(), md.str());
  return failures;
}

}  // namespace drench
