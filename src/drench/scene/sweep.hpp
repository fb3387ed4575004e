#pragma once
/// What `drench sweep` runs and what it writes: the plan of settings, one CSV row per run from its
/// summary.json, the Pareto front of wall time against an error, and the report. The runs themselves are
/// separate `drench run` processes (demos/sweep_command.cpp), so that a run that blows up or aborts is a row
/// with its status rather than the end of the sweep.
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include <drench/compare/run_comparison.hpp>

namespace drench {

/// One `--vary key=v1,v2,...` argument: a scene path as `--set` takes it and the values it takes in turn.
struct SweepAxis {
  std::string key;                  ///< e.g. "time.dt" or "emitters[0].speed"
  std::vector<std::string> values;  ///< JSON values as written, e.g. "0.004", "\"wcsph\"", "[1, 2]"
};

/// Parses `key=v1,v2,...`. Values are split at commas outside brackets, braces and quotes, so a JSON array
/// or object is one value.
/// @throws SceneError naming the argument when there is no `=`, the key is empty, a value is empty, or the
///         brackets or quotes do not balance.
SweepAxis parse_sweep_axis(const std::string& argument);

/// One `--case LABEL:key=value;key=value` argument: settings that go together (no-slip needs both
/// `coupling.slip` and "friction" in `effects`), run as one setting.
struct SweepCase {
  std::string label;                     ///< e.g. "no-slip"
  std::vector<std::string> assignments;  ///< `key=value` as `--set` takes them
};

/// Parses `LABEL:key=value;key=value...`; `;` inside brackets or quotes belongs to the value.
/// @throws SceneError naming the argument when the label or an assignment is empty or has no `=`.
SweepCase parse_sweep_case(const std::string& argument);

/// One run of a sweep: its settings on top of the scene's (and the sweep's `--set`s).
struct SweepRun {
  std::string label;                     ///< "scene" for the scene as it is, else e.g. "time.dt=0.004"
  std::vector<std::string> assignments;  ///< `key=value`, applied after the sweep's own overrides
  int repeat = 0;                        ///< 0 .. repeats - 1
};

/// The most runs a sweep may have (settings x repeats): a sweep of 10,000 runs of a second each takes hours
/// already, and each setting is checked before the first run (a 99 x 99 x 100 grid took 28 s to plan).
inline constexpr double kMaxSweepRuns = 10000;

/// The runs of a sweep, each setting `repeats` times in a row.
/// Grid (`one_at_a_time` false): every combination of the axes' values, then the cases.
/// One at a time: the scene as it is, then each axis's values alone (skipping a value equal to the scene's,
/// which would repeat the first run), then the cases.
/// @param scene  the scene document after the sweep's `--set`s, to compare values with
/// @throws SceneError when an assignment cannot be applied to `scene` (apply_override's errors), when
///         `repeats` < 1, or when the sweep would have more than kMaxSweepRuns runs (counted before any is
///         planned).
std::vector<SweepRun> plan_sweep(const nlohmann::json& scene, const std::vector<SweepAxis>& axes,
                                 const std::vector<SweepCase>& cases, bool one_at_a_time, int repeats);

/// The CSV's columns after the run number, label, repeat and the axes' keys, in order. Each is a number,
/// empty when the run does not have it (e.g. `leaks` without "leak_audit"), except `status`.
const std::vector<std::string>& sweep_columns();

/// The row of one run: sweep_columns() from its summary, or, when `summary` is null (the run died before
/// writing one), `status` from `failure`. The status is "ok", the summary's step flags, or the failure.
std::vector<std::string> sweep_row(const nlohmann::json* summary, const std::string& failure);

/// The columns `drench sweep --reference` adds after sweep_columns(): each of observable_names() (the largest
/// difference from the reference over the frames, unit in the name; compare/run_comparison.hpp), then
/// `worst_relative_error` (the largest of their relative errors) and `worst_observable` (whose it is).
const std::vector<std::string>& reference_columns();

/// The reference columns of one run from its comparison; every field empty when `comparison` is null (the
/// run could not be compared), an observable's field empty when the runs do not have it.
std::vector<std::string> reference_row(const RunComparison* comparison);

/// A number of a row as the CSV holds it, or NaN for an empty field.
double sweep_number(const std::string& field);

/// The indices of the points no other point beats on both (lower is better on both), by time ascending.
/// Points with a non-finite coordinate are never on the front.
std::vector<std::size_t> pareto_front(const std::vector<std::pair<double, double>>& time_error);

}  // namespace drench
