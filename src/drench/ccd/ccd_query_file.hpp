#pragma once
/// Reader of the vertex-face CCD query files (`*.vf.txt`) that hold an outside ground truth: the samples of
/// Wang et al. 2021 and Belgrod et al. 2023 converted in ../shared/data/ccd-vertex-face (README.md there
/// describes the format). The `drench ccd` command, the CCD tests and bench/bench_ccd.cpp read them.

#include <cstdint>
#include <string>
#include <vector>

#include <drench/ccd/point_triangle_ccd.hpp>

namespace drench::ccd {

/// Largest query file read (unit: bytes): 1 GiB, some 2.5 million queries (the benchmark's largest file is
/// 17 MB).
inline constexpr std::uint64_t kMaxCcdQueryFileBytes = std::uint64_t{1} << 30;

/// One query of a `*.vf.txt` file with its ground-truth label.
struct CcdBenchmarkQuery {
  /// `<source file>#<index in that file>`, e.g. `erleben-spikes/vertex-face/data_0_0.csv#35`; no spaces.
  std::string id;
  /// Ground truth: the point lies in the closed triangle at some t in [0, 1] (touching counts).
  bool collides = false;
  /// The coordinates d1..d24 of the file: p_t0 f0_t0 f1_t0 f2_t0 p_t1 f0_t1 f1_t1 f2_t1 (x y z each), with
  /// f0, f1, f2 stored as a, b, c. Exact: every value in the files is a double and is parsed with correct
  /// rounding, so the label applies to these doubles.
  VertexFaceQuery query;
};

/// Reads every query of one `*.vf.txt` file, in file order.
/// Lines starting with `#` (the 3-line header) and empty lines are skipped; `\r\n` line ends are accepted.
/// Every other line must hold exactly 50 fields separated by spaces: `<qid> <truth> <r1..r24> <d1..d24>`.
/// The rational columns r1..r24 are not read (the doubles are the same values, exactly).
/// @param path  file to read (any length unit; the shared data are dimensionless)
/// @return the queries, possibly none (a file of comments only)
/// @throws IoError when the file cannot be read (`<file>: cannot read CCD query file: <reason>`), before it
///         is opened when it is not a regular file (a folder, FIFO or device such as /dev/zero) or is larger
///         than kMaxCcdQueryFileBytes; and for bad
///         content as `<file>:<line>: <problem>, got <value>`: a field count other than 50, a truth other
///         than `0` or `1`, a double column that is not a number, out of the double range, NaN or infinite.
std::vector<CcdBenchmarkQuery> read_ccd_query_file(const std::string& path);

/// The query files a command-line argument names.
/// @param path  a file, returned as is whatever its name; or a directory, searched recursively for files
/// named
///        `*.vf.txt` (symbolic links to directories are not followed)
/// @return paths sorted by their full name, so every run visits files in the same order
/// @throws IoError when `path` does not exist, cannot be listed, or is a directory without any `*.vf.txt`
std::vector<std::string> list_ccd_query_files(const std::string& path);

}  // namespace drench::ccd
