#include <drench/ccd/ccd_query_file.hpp>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <string_view>
#include <system_error>

#include <drench/common/error.hpp>
#include <drench/common/file_text.hpp>

namespace drench::ccd {
namespace {

constexpr int kFieldCount = 50;        // qid, truth, r1..r24, d1..d24
constexpr int kFirstDoubleField = 26;  // 0-based index of d1

/// The vertices in the files' order, so that d(3v + k) fills coordinate k of kVertices[v].
constexpr Vec3 VertexFaceQuery::*kVertices[8] = {
    &VertexFaceQuery::p_t0, &VertexFaceQuery::a_t0, &VertexFaceQuery::b_t0, &VertexFaceQuery::c_t0,
    &VertexFaceQuery::p_t1, &VertexFaceQuery::a_t1, &VertexFaceQuery::b_t1, &VertexFaceQuery::c_t1};
constexpr const char* kVertexNames[8] = {"p_t0", "a_t0", "b_t0", "c_t0", "p_t1", "a_t1", "b_t1", "c_t1"};

/// The whole file in one string (one read is several times faster than a stream extraction per token), of at
/// most kMaxCcdQueryFileBytes: the benchmark's largest file is 17 MB.
std::string read_whole_file(const std::string& path) {
  try {
    return read_file_text(path, kMaxCcdQueryFileBytes,
                          "1 GiB (" + std::to_string(kMaxCcdQueryFileBytes) + " bytes) a CCD query file");
  } catch (const FileTextError& e) {
    throw IoError(path + ": cannot read CCD query file: " + e.reason());
  }
}

/// A field as it appears in an error message; cut short because a corrupt line can be megabytes long.
std::string shown(std::string_view value) {
  constexpr std::size_t kMax = 64;
  if (value.size() <= kMax) return std::string(value);
  return std::string(value.substr(0, kMax)) + "...";
}

/// `d5 (a_t0.y, field 30)`: the column as the README names it, the member it fills, and where to count to.
std::string double_column_name(int k) {
  return "d" + std::to_string(k + 1) + " (" + kVertexNames[k / 3] + "." + "xyz"[k % 3] + ", field " +
         std::to_string(kFirstDoubleField + k + 1) + ")";
}

bool is_blank(char c) {
  return c == ' ' || c == '\t';
}

/// Parses one query line. `where` is `<file>:<line>` for error messages.
CcdBenchmarkQuery parse_query_line(std::string_view line, const std::string& where) {
  // Splitting on runs of blanks rather than single spaces costs nothing and forgives hand-edited files;
  // the field count still catches any missing or extra value.
  std::array<std::string_view, kFieldCount> fields;
  int count = 0;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_blank(line[i]))
      ++i;
    if (i == line.size()) break;
    const std::size_t start = i;
    while (i < line.size() && !is_blank(line[i]))
      ++i;
    if (count < kFieldCount) fields[static_cast<std::size_t>(count)] = line.substr(start, i - start);
    ++count;
  }
  if (count != kFieldCount) {
    throw IoError(where + ": expected " + std::to_string(kFieldCount) +
                  " fields (qid, truth, r1..r24, d1..d24), got " + std::to_string(count));
  }

  CcdBenchmarkQuery result;
  result.id = std::string(fields[0]);
  if (fields[1] != "0" && fields[1] != "1") {
    throw IoError(where + ": truth (field 2) must be 0 or 1, got " + shown(fields[1]));
  }
  result.collides = fields[1] == "1";

  for (int k = 0; k < 24; ++k) {
    const std::string_view text = fields[static_cast<std::size_t>(kFirstDoubleField + k)];
    double value = 0.0;
    // from_chars rounds correctly (the files' repr strings give back the exact doubles) and ignores the
    // locale, which strtod would not.
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (error == std::errc::result_out_of_range) {
      throw IoError(where + ": " + double_column_name(k) + " is out of the double range, got " + shown(text));
    }
    if (error != std::errc() || end != text.data() + text.size()) {
      throw IoError(where + ": " + double_column_name(k) + " is not a number, got " + shown(text));
    }
    if (!std::isfinite(value)) {
      throw IoError(where + ": " + double_column_name(k) + " is not finite, got " + shown(text));
    }
    (result.query.*kVertices[k / 3])[k % 3] = value;
  }
  return result;
}

}  // namespace

std::vector<CcdBenchmarkQuery> read_ccd_query_file(const std::string& path) {
  const std::string text = read_whole_file(path);
  std::vector<CcdBenchmarkQuery> queries;
  queries.reserve(static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')));

  std::size_t line_number = 0;
  std::size_t begin = 0;
  while (begin < text.size()) {
    std::size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    std::string_view line(text.data() + begin, end - begin);
    begin = end + 1;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (std::all_of(line.begin(), line.end(), is_blank) || line.front() == '#') continue;
    queries.push_back(parse_query_line(line, path + ":" + std::to_string(line_number)));
  }
  return queries;
}

std::vector<std::string> list_ccd_query_files(const std::string& path) {
  namespace fs = std::filesystem;
  // error_code overloads throughout: an IoError that names the argument reads better than a filesystem_error.
  std::error_code error;
  const fs::file_status status = fs::status(path, error);
  if (error || !fs::exists(status)) {
    throw IoError(path + ": cannot read CCD query files: " +
                  (error ? error.message() : std::string("no such file or directory")));
  }
  if (!fs::is_directory(status)) return {path};

  std::vector<std::string> files;
  fs::recursive_directory_iterator it(path, error);
  for (; !error && it != fs::recursive_directory_iterator(); it.increment(error)) {
    const std::string name = it->path().filename().string();
    constexpr std::string_view kSuffix = ".vf.txt";
    std::error_code type_error;
    if (name.size() > kSuffix.size() &&
        name.compare(name.size() - kSuffix.size(), kSuffix.size(), kSuffix) == 0 &&
        it->is_regular_file(type_error)) {
      files.push_back(it->path().string());
    }
  }
  if (error) throw IoError(path + ": cannot list CCD query files: " + error.message());
  if (files.empty()) throw IoError(path + ": holds no *.vf.txt file");
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace drench::ccd
