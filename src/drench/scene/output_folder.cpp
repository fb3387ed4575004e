#include <drench/scene/output_folder.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <system_error>

#include <drench/common/error.hpp>
#include <drench/io/atomic_file.hpp>

namespace drench {

namespace {

namespace fs = std::filesystem;

std::vector<std::string> split_path(const std::string& path) {
  std::vector<std::string> parts;
  std::string::size_type begin = 0;
  while (true) {
    const std::string::size_type slash = path.find('/', begin);
    parts.push_back(path.substr(begin, slash == std::string::npos ? std::string::npos : slash - begin));
    if (slash == std::string::npos) return parts;
    begin = slash + 1;
  }
}

/// Glob match of one name: `*` matches any run of characters, everything else itself.
bool name_matches(const std::string& pattern, const std::string& name) {
  std::size_t p = 0, n = 0, star = std::string::npos, resume = 0;
  while (n < name.size()) {
    if (p < pattern.size() && pattern[p] == '*') {
      star = p++;
      resume = n;
    } else if (p < pattern.size() && pattern[p] == name[n]) {
      ++p;
      ++n;
    } else if (star != std::string::npos) {
      p = star + 1;
      n = ++resume;
    } else {
      return false;
    }
  }
  while (p < pattern.size() && pattern[p] == '*')
    ++p;
  return p == pattern.size();
}

/// Whether the first `count` names of `parts` match the pattern's first `count` names.
bool prefix_matches(const std::vector<std::string>& pattern, const std::vector<std::string>& parts,
                    std::size_t count) {
  if (pattern.size() < count || parts.size() < count) return false;
  for (std::size_t i = 0; i < count; ++i)
    if (!name_matches(pattern[i], parts[i])) return false;
  return true;
}

/// `name` without a trailing `.tmp-DIGITS`, or `name` itself.
std::string without_temporary_suffix(const std::string& name) {
  const std::string::size_type tmp = name.rfind(".tmp-");
  if (tmp == std::string::npos || tmp + 5 == name.size()) return name;
  if (name.find_first_not_of("0123456789", tmp + 5) != std::string::npos) return name;
  return name.substr(0, tmp);
}

/// A folder some pattern writes into, e.g. "frames" for "frames/fluid_*.ply".
bool folder_covered(const std::vector<std::string>& patterns, const std::string& relative) {
  const std::vector<std::string> parts = split_path(relative);
  return std::any_of(patterns.begin(), patterns.end(), [&](const std::string& pattern) {
    const std::vector<std::string> names = split_path(pattern);
    return names.size() > parts.size() && prefix_matches(names, parts, parts.size());
  });
}

bool file_covered(const std::vector<std::string>& patterns, const std::string& relative) {
  return std::any_of(patterns.begin(), patterns.end(),
                     [&](const std::string& pattern) { return output_pattern_covers(pattern, relative); });
}

/// An output folder's entries, '/'-separated relative to it, in name order; symbolic links are entries and
/// are not followed.
struct FolderEntries {
  std::vector<std::string> files;    ///< everything that is not a folder
  std::vector<std::string> folders;  ///< real folders (not links to one)
};

/// The first of `entries`, folders then files, in name order, that `patterns` do not cover; "" when all are.
std::string first_not_covered(const FolderEntries& entries, const std::vector<std::string>& patterns) {
  for (const std::string& folder : entries.folders)
    if (!folder_covered(patterns, folder)) return folder;
  for (const std::string& file : entries.files)
    if (!file_covered(patterns, file)) return file;
  return "";
}

FolderEntries list_entries(const fs::path& dir, const std::string& flag) {
  FolderEntries entries;
  std::error_code ec;
  fs::recursive_directory_iterator it(dir, fs::directory_options::none, ec), end;
  for (; !ec && it != end; it.increment(ec)) {
    const std::string relative = it->path().lexically_relative(dir).generic_string();
    std::error_code status_error;
    if (it->symlink_status(status_error).type() == fs::file_type::directory) {
      entries.folders.push_back(relative);
    } else {
      entries.files.push_back(relative);
    }
  }
  if (ec) throw IoError(flag + " " + dir.string() + ": cannot list the folder: " + ec.message());
  std::sort(entries.files.begin(), entries.files.end());
  std::sort(entries.folders.begin(), entries.folders.end());
  return entries;
}

/// The patterns of the manifest an earlier output of `command` left in `dir`. @throws IoError when it is
/// missing, unreadable or another command's
std::vector<std::string> read_manifest(const fs::path& dir, const std::string& flag,
                                       const std::string& command, const std::string& found) {
  const fs::path manifest = dir / kOutputManifest;
  const std::string refusal = flag + " " + dir.string() + " --overwrite: ";
  std::error_code ec;
  if (!fs::is_regular_file(fs::symlink_status(manifest, ec))) {
    throw IoError(refusal + "the folder holds " + (dir / found).string() + " but no " + kOutputManifest +
                  ", so nothing in it is known to be drench's; nothing deleted: empty it or choose another "
                  "folder");
  }
  std::vector<std::string> patterns;
  std::string written_by;
  try {
    std::ifstream in(manifest);
    const nlohmann::json document = nlohmann::json::parse(in);
    written_by = document.at("command").get<std::string>();
    for (const nlohmann::json& pattern : document.at("files"))
      patterns.push_back(pattern.get<std::string>());
  } catch (const nlohmann::json::exception& e) {
    throw IoError(refusal + manifest.string() + " is not a drench manifest (" + e.what() +
                  "); nothing deleted: empty the folder or choose another");
  }
  if (written_by != command) {
    throw IoError(refusal + manifest.string() + " says the folder holds the output of drench " + written_by +
                  ", not of drench " + command + "; nothing deleted: choose another folder");
  }
  return patterns;
}

/// What prepare_output_folder removes: the files and folders an earlier manifest covers.
FolderEntries check_folder(const fs::path& dir, const std::string& flag, const std::string& command,
                           const std::vector<std::string>& patterns, bool overwrite) {
  check_output_path(dir.string(), flag);
  std::error_code ec;
  if (!fs::exists(dir, ec)) return {};
  if (!overwrite) {
    // The first entry in name order is a top-level one: listing only that level keeps a refusal of a
    // folder such as $HOME instant instead of a walk of the whole tree.
    std::string found;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
      const std::string name = it->path().filename().generic_string();
      if (found.empty() || name < found) found = name;
    }
    if (ec) throw IoError(flag + " " + dir.string() + ": cannot list the folder: " + ec.message());
    if (found.empty()) return {};
    const bool earlier_run = fs::is_regular_file(fs::symlink_status(dir / kOutputManifest, ec));
    throw IoError(flag + " " + dir.string() + ": the folder is not empty (it holds " +
                  (dir / found).string() +
                  "); drench writes only into a new or empty folder, so that no earlier file is lost or " +
                  "mixed with this run's: choose another folder" +
                  (earlier_run ? ", or add --overwrite to replace the earlier drench run there" : ""));
  }
  FolderEntries entries = list_entries(dir, flag);
  if (entries.files.empty() && entries.folders.empty()) return {};
  const std::string& found = entries.files.empty() ? entries.folders.front() : entries.files.front();
  const std::vector<std::string> listed = read_manifest(dir, flag, command, found);
  // Covered by the manifest and by the command's own names both: the manifest alone may be forged.
  for (const auto& [covering, why] : {std::pair{&listed, std::string(kOutputManifest) + " does not list it"},
                                      std::pair{&patterns, "drench " + command + " writes no such file"}}) {
    const std::string entry = first_not_covered(entries, *covering);
    if (!entry.empty()) {
      throw IoError(flag + " " + dir.string() + " --overwrite: " + (dir / entry).string() +
                    " was not written by drench (" + why + "); nothing deleted");
    }
  }
  return entries;
}

}  // namespace

const std::vector<std::string>& run_output_patterns() {
  static const std::vector<std::string> patterns = {
      kOutputManifest,
      "scene.json",
      "summary.json",
      // drench reference: the settings the reference was made with, beside the run's files.
      "reference.json",
      "obstacles.ply",
      "frames/fluid_*.ply",
      "frames/cloth_*.ply",
      "frames/surface_*.ply",
      // drench reconstruct: its surfaces are made in reconstruct.tmp-PID/ and moved into frames/.
      "reconstruct.json",
      "reconstruct.tmp-*/surface_*.ply",
      // drench render without --out.
      "render/frame_*.png",
      "render/video.mp4",
  };
  return patterns;
}

const std::vector<std::string>& sweep_output_patterns() {
  static const std::vector<std::string> patterns = [] {
    std::vector<std::string> list = {kOutputManifest, "sweep.csv", "report.md", "pareto.png", "pareto.gp",
                                     "pareto_all.dat", "pareto_front.dat", "pareto_apart.dat",
                                     // pareto_leaked.dat: an older sweep's, cleared by --overwrite.
                                     "pareto_leaked.dat", "runs/*.log", "runs/*.comparison.json"};
    for (const std::string& pattern : run_output_patterns())
      list.push_back("runs/*/" + pattern);
    return list;
  }();
  return patterns;
}

const std::vector<std::string>& render_output_patterns() {
  static const std::vector<std::string> patterns = {kOutputManifest, "frame_*.png", "video.mp4"};
  return patterns;
}

void check_folder_holds_only(const std::string& dir, const std::string& command,
                             const std::vector<std::string>& patterns) {
  std::error_code ec;
  if (!fs::exists(dir, ec)) return;
  const std::string entry = first_not_covered(list_entries(dir, "drench " + command), patterns);
  if (!entry.empty()) {
    throw IoError((fs::path(dir) / entry).string() + " was not written by drench " + command +
                  ", which writes only " + nlohmann::json(patterns).dump() +
                  " there; nothing written: move it away or choose another folder");
  }
}

bool output_pattern_covers(const std::string& pattern, const std::string& relative) {
  const std::vector<std::string> names = split_path(pattern);
  std::vector<std::string> parts = split_path(relative);
  if (names.size() != parts.size()) return false;
  if (prefix_matches(names, parts, parts.size())) return true;
  parts.back() = without_temporary_suffix(parts.back());
  return prefix_matches(names, parts, parts.size());
}

void check_output_path(const std::string& dir, const std::string& flag) {
  if (dir.empty()) {
    throw IoError(flag +
                  " '': must name a folder (an empty path would write into the working directory), e.g. " +
                  flag + " out/run1");
  }
  std::error_code ec;
  const fs::file_status status = fs::status(dir, ec);
  if (fs::exists(status) && !fs::is_directory(status))
    throw IoError(flag + " " + dir + ": exists and is not a folder; " + flag + " must name a folder");
  // A link to nothing: creating the folder failed with a bare "File exists" once the scene had been read.
  if (!fs::exists(status) && fs::is_symlink(fs::symlink_status(dir, ec)))
    throw IoError(flag + " " + dir + ": a symbolic link to " + fs::read_symlink(dir, ec).string() +
                  ", which does not exist; " + flag + " must name a folder");
}

void check_output_folder(const std::string& dir, const std::string& flag, const std::string& command,
                         const std::vector<std::string>& patterns, bool overwrite) {
  (void)check_folder(dir, flag, command, patterns, overwrite);
}

void prepare_output_folder(const std::string& dir, const std::string& flag, const std::string& command,
                           const std::vector<std::string>& patterns, bool overwrite) {
  const fs::path root(dir);
  const FolderEntries old = check_folder(root, flag, command, patterns, overwrite);
  std::error_code ec;
  // The old manifest goes last, so that whatever an interruption leaves is still covered by it.
  for (const std::string& file : old.files) {
    if (file == kOutputManifest) continue;
    if (!fs::remove(root / file, ec) && ec)
      throw IoError(flag + " " + dir + " --overwrite: cannot remove " + (root / file).string() + ": " +
                    ec.message());
  }
  // Deepest first: a folder is removed once its files are.
  for (auto it = old.folders.rbegin(); it != old.folders.rend(); ++it) {
    if (!fs::remove(root / *it, ec) && ec)
      throw IoError(flag + " " + dir + " --overwrite: cannot remove " + (root / *it).string() + ": " +
                    ec.message());
  }
  fs::create_directories(root, ec);
  if (ec) throw IoError(flag + " " + dir + ": cannot create the folder: " + ec.message());
  const nlohmann::json manifest = {
      {"drench_version", DRENCH_VERSION}, {"command", command}, {"files", patterns}};
  write_file_atomic((root / kOutputManifest).string(), manifest.dump(2) + "\n");
}

}  // namespace drench
