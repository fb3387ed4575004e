#include <drench/scene/sweep.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <set>

#include <drench/common/error.hpp>
#include <drench/scene/scene_loader.hpp>

namespace drench {

namespace {

/// Splits `text` at `separator` where it is outside brackets, braces and double quotes.
/// @return false when the brackets or quotes do not balance
bool split_top_level(const std::string& text, char separator, std::vector<std::string>& parts) {
  parts.clear();
  std::string current;
  int depth = 0;
  bool quoted = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '\\' && i + 1 < text.size()) {
        current += c;
        current += text[++i];
        continue;
      }
      if (c == '"') quoted = false;
    } else if (c == '"') {
      quoted = true;
    } else if (c == '[' || c == '{') {
      ++depth;
    } else if (c == ']' || c == '}') {
      if (--depth < 0) return false;
    } else if (c == separator && depth == 0) {
      parts.push_back(current);
      current.clear();
      continue;
    }
    current += c;
  }
  parts.push_back(current);
  return depth == 0 && !quoted;
}

std::string number_field(const nlohmann::json& value) {
  if (!value.is_number()) return "";
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value.get<double>());
  return text;
}

/// summary[a][b]... as a CSV field, empty when any step is missing.
std::string field(const nlohmann::json& summary, std::initializer_list<const char*> path) {
  const nlohmann::json* node = &summary;
  for (const char* key : path) {
    if (!node->is_object() || !node->contains(key)) return "";
    node = &(*node)[key];
  }
  return number_field(*node);
}

}  // namespace

SweepAxis parse_sweep_axis(const std::string& argument) {
  const auto fail = [&](const std::string& problem) {
    return SceneError("--vary " + argument + ": " + problem);
  };
  const std::size_t equals = argument.find('=');
  if (equals == std::string::npos) throw fail("expected key=value1,value2,...");
  SweepAxis axis;
  axis.key = argument.substr(0, equals);
  if (axis.key.empty()) throw fail("the key is empty");
  if (!split_top_level(argument.substr(equals + 1), ',', axis.values))
    throw fail("brackets or quotes do not balance");
  for (const std::string& value : axis.values)
    if (value.empty()) throw fail("a value is empty");
  return axis;
}

SweepCase parse_sweep_case(const std::string& argument) {
  const auto fail = [&](const std::string& problem) {
    return SceneError("--case " + argument + ": " + problem);
  };
  const std::size_t colon = argument.find(':');
  if (colon == std::string::npos || colon == 0) throw fail("expected LABEL:key=value;key=value...");
  SweepCase result;
  result.label = argument.substr(0, colon);
  if (!split_top_level(argument.substr(colon + 1), ';', result.assignments))
    throw fail("brackets or quotes do not balance");
  for (const std::string& assignment : result.assignments) {
    const std::size_t equals = assignment.find('=');
    if (equals == std::string::npos || equals == 0) throw fail("'" + assignment + "' is not key=value");
  }
  return result;
}

std::vector<SweepRun> plan_sweep(const nlohmann::json& scene, const std::vector<SweepAxis>& axes,
                                 const std::vector<SweepCase>& cases, bool one_at_a_time, int repeats) {
  if (repeats < 1) throw SceneError("--repeat must be >= 1, got " + std::to_string(repeats));
  // Counted first, in double: a grid of many axes, or --repeat 1e9, would otherwise be built (and each of
  // its settings checked) before it is found too large.
  double count = 1.0;  // the scene (one at a time), or the grid's one combination of no axes
  for (const SweepAxis& axis : axes) {
    const auto values = static_cast<double>(axis.values.size());
    count = one_at_a_time ? count + values : count * values;
  }
  count = (count + static_cast<double>(cases.size())) * repeats;
  if (!(count <= kMaxSweepRuns)) {
    throw SceneError("sweep: " + format_number(count) +
                     " runs ((the --vary settings + the --case's) x --repeat " + std::to_string(repeats) +
                     "); at most " + format_number(kMaxSweepRuns));
  }
  // A setting given twice ran once, or twice under one label: the report would not say which was meant.
  // Values are compared as JSON (1e-3 is 0.001), in a set since an axis may have thousands.
  const auto canonical = [](const std::string& value) {
    const nlohmann::json parsed = nlohmann::json::parse(value, nullptr, false);
    return parsed.is_discarded() ? value : parsed.dump();
  };
  std::set<std::string> keys;
  for (const SweepAxis& axis : axes) {
    if (!keys.insert(axis.key).second)
      throw SceneError("--vary " + axis.key + " is given twice: list all its values in one --vary");
    std::set<std::string> values;
    for (const std::string& value : axis.values)
      if (!values.insert(canonical(value)).second)
        throw SceneError("--vary " + axis.key + ": the value " + value + " is given twice");
  }
  std::set<std::string> labels;
  for (const SweepCase& c : cases) {
    if (!labels.insert(c.label).second)
      throw SceneError("--case " + c.label + " is given twice: each case needs a label of its own");
    std::set<std::string> set_keys;
    for (const std::string& assignment : c.assignments) {
      const std::string key = assignment.substr(0, assignment.find('='));
      if (!set_keys.insert(key).second) throw SceneError("--case " + c.label + ": " + key + " is set twice");
    }
  }
  std::vector<SweepRun> settings;
  // Every assignment is tried on the scene here, so that a bad key fails the sweep before any run.
  const auto applied = [&](const std::vector<std::string>& assignments) {
    nlohmann::json document = scene;
    for (const std::string& assignment : assignments)
      apply_override(document, assignment);
    return document;
  };
  if (one_at_a_time) {
    settings.push_back({"scene", {}, 0});
    for (const SweepAxis& axis : axes) {
      for (const std::string& value : axis.values) {
        const std::string assignment = axis.key + "=" + value;
        if (applied({assignment}) == scene) continue;
        settings.push_back({assignment, {assignment}, 0});
      }
    }
  } else {
    // The grid in odometer order, the last axis fastest.
    std::vector<std::size_t> digit(axes.size(), 0);
    const bool empty_axis =
        std::any_of(axes.begin(), axes.end(), [](const SweepAxis& a) { return a.values.empty(); });
    while (!empty_axis) {
      SweepRun run;
      for (std::size_t a = 0; a < axes.size(); ++a) {
        run.assignments.push_back(axes[a].key + "=" + axes[a].values[digit[a]]);
        run.label += (run.label.empty() ? "" : " ") + run.assignments.back();
      }
      if (run.label.empty()) run.label = "scene";
      applied(run.assignments);
      settings.push_back(std::move(run));
      std::size_t a = axes.size();
      while (a > 0 && ++digit[a - 1] == axes[a - 1].values.size())
        digit[--a] = 0;
      if (a == 0) break;
    }
  }
  for (const SweepCase& c : cases) {
    applied(c.assignments);
    settings.push_back({c.label, c.assignments, 0});
  }
  std::vector<SweepRun> runs;
  for (const SweepRun& setting : settings) {
    for (int r = 0; r < repeats; ++r) {
      runs.push_back(setting);
      runs.back().repeat = r;
    }
  }
  return runs;
}

const std::vector<std::string>& sweep_columns() {
  static const std::vector<std::string> columns = {"status",
                                                   "wall_s",
                                                   "fluid_s",
                                                   "cloth_s",
                                                   "coupling_s",
                                                   "repulsion_s",
                                                   "ccd_s",
                                                   "leak_audit_s",
                                                   "surface_s",
                                                   "wetting_s",
                                                   "steps",
                                                   "particles",
                                                   "contacts",
                                                   "ccd_impacts",
                                                   "leaks",
                                                   "surface_intersections",
                                                   "density_error_mean",
                                                   "density_error_max",
                                                   "energy_drift",
                                                   "mean_contact_slip_mps",
                                                   "max_particle_speed_mps",
                                                   "max_node_speed_mps"};
  return columns;
}

std::vector<std::string> sweep_row(const nlohmann::json* summary, const std::string& failure) {
  if (!summary) {
    std::vector<std::string> row(sweep_columns().size());
    row[0] = failure.empty() ? "failed" : failure;
    return row;
  }
  const nlohmann::json& s = *summary;
  std::string status = s.value("status", std::string("ok"));
  if (!failure.empty()) status = status == "ok" ? failure : status + "; " + failure;
  return {status,
          field(s, {"wall_s"}),
          field(s, {"timings_s", "fluid"}),
          field(s, {"timings_s", "cloth"}),
          field(s, {"timings_s", "coupling"}),
          field(s, {"timings_s", "repulsion"}),
          field(s, {"timings_s", "ccd"}),
          field(s, {"timings_s", "leak_audit"}),
          field(s, {"timings_s", "surface"}),
          field(s, {"timings_s", "wetting"}),
          field(s, {"steps"}),
          field(s, {"particles"}),
          field(s, {"contacts"}),
          field(s, {"ccd_impacts"}),
          field(s, {"leaks"}),
          field(s, {"surface_intersections"}),
          field(s, {"density_error", "mean"}),
          field(s, {"density_error", "max"}),
          field(s, {"energy_drift"}),
          field(s, {"mean_contact_slip_mps"}),
          field(s, {"max_speed_mps", "particle"}),
          field(s, {"max_speed_mps", "node"})};
}

const std::vector<std::string>& reference_columns() {
  static const std::vector<std::string> columns = [] {
    std::vector<std::string> list = observable_names();
    list.push_back("worst_relative_error");
    list.push_back("worst_observable");
    return list;
  }();
  return columns;
}

std::vector<std::string> reference_row(const RunComparison* comparison) {
  std::vector<std::string> row(reference_columns().size());
  if (!comparison) return row;
  const std::vector<std::string>& names = observable_names();
  for (const ObservableError& e : comparison->observables) {
    const std::size_t i =
        static_cast<std::size_t>(std::find(names.begin(), names.end(), e.name) - names.begin());
    if (i < names.size() && std::isfinite(e.largest)) row[i] = number_field(e.largest);
  }
  if (std::isfinite(comparison->worst_relative)) row[names.size()] = number_field(comparison->worst_relative);
  row[names.size() + 1] = comparison->worst;
  return row;
}

double sweep_number(const std::string& text) {
  if (text.empty()) return std::numeric_limits<double>::quiet_NaN();
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  return end && *end == '\0' ? value : std::numeric_limits<double>::quiet_NaN();
}

std::vector<std::size_t> pareto_front(const std::vector<std::pair<double, double>>& time_error) {
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < time_error.size(); ++i)
    if (std::isfinite(time_error[i].first) && std::isfinite(time_error[i].second)) order.push_back(i);
  // By time, ties by error: a point is on the front when its error is below every faster point's.
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return time_error[a] < time_error[b] || (time_error[a] == time_error[b] && a < b);
  });
  std::vector<std::size_t> front;
  double best = std::numeric_limits<double>::infinity();
  for (const std::size_t i : order) {
    if (time_error[i].second < best) {
      front.push_back(i);
      best = time_error[i].second;
    }
  }
  return front;
}

}  // namespace drench
