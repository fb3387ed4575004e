#include <drench/ccd/ccd_query_file.hpp>

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <drench/common/error.hpp>
#include "../assertions.hpp"
#include "../temp_dir.hpp"
#include "ccd_test_data.hpp"

namespace drench::ccd {
namespace {

using drench::test::throws_containing;

namespace fs = std::filesystem;

constexpr const char* kHeader =
    "# source: hand-written for test_ccd_query_file.cpp\n"
    "# fields: qid truth(0/1) then 24 rationals num/den then 24 doubles (repr, round-trip exact)\n"
    "# order: p_t0 f0_t0 f1_t0 f2_t0 p_t1 f0_t1 f1_t1 f2_t1 (x y z each)\n";

/// A query line with the given double columns; the rational columns are placeholders (the reader skips them).
std::string query_line(const std::string& id, const std::string& truth,
                       const std::vector<std::string>& doubles) {
  std::string line = id + " " + truth;
  for (int k = 0; k < 24; ++k)
    line += " 0/1";
  for (const std::string& d : doubles)
    line += " " + d;
  return line + "\n";
}

/// d1..d24 = 1.5, 2.5, ..., 24.5: every coordinate distinct, so a swapped vertex or axis shows.
std::vector<std::string> distinct_doubles() {
  std::vector<std::string> doubles;
  for (int k = 0; k < 24; ++k)
    doubles.push_back(std::to_string(k + 1) + ".5");
  return doubles;
}

/// distinct_doubles() with column d`column` (1-based) replaced by `text`.
std::vector<std::string> doubles_with(int column, const std::string& text) {
  std::vector<std::string> doubles = distinct_doubles();
  doubles[static_cast<std::size_t>(column - 1)] = text;
  return doubles;
}

TEST(CcdQueryFile, ReadsQueriesInFileOrderWithCoordinatesInVertexOrder) {
  const drench::test::TempDir dir;
  const std::string path = dir.write(
      "two.vf.txt", std::string(kHeader) +
                        query_line("scene/vertex-face/data_0_0.csv#0", "1", distinct_doubles()) +
                        query_line("scene/vertex-face/data_0_0.csv#1", "0", doubles_with(1, "-0.0")));
  const std::vector<CcdBenchmarkQuery> queries = read_ccd_query_file(path);
  ASSERT_EQ(queries.size(), 2u);

  EXPECT_EQ(queries[0].id, "scene/vertex-face/data_0_0.csv#0");
  EXPECT_TRUE(queries[0].collides);
  const VertexFaceQuery& q = queries[0].query;
  const Vec3* in_file_order[8] = {&q.p_t0, &q.a_t0, &q.b_t0, &q.c_t0, &q.p_t1, &q.a_t1, &q.b_t1, &q.c_t1};
  for (int k = 0; k < 24; ++k)
    EXPECT_EQ((*in_file_order[k / 3])[k % 3], k + 1.5) << "d" << k + 1;

  EXPECT_EQ(queries[1].id, "scene/vertex-face/data_0_0.csv#1");
  EXPECT_FALSE(queries[1].collides);
  EXPECT_EQ(queries[1].query.p_t0.x(), 0.0);
  EXPECT_TRUE(std::signbit(queries[1].query.p_t0.x()));
}

TEST(CcdQueryFile, ParsesShortestRoundTripDoublesExactly) {
  // Python repr forms as the files hold them: the reader must return these exact doubles, subnormals
  // included.
  const std::vector<std::string> texts = {"0.1",   "-1.1920928955078125e-07",  "5e-324",
                                          "1e+16", "-1.7976931348623157e+308", "2.220446049250313e-16"};
  const std::vector<double> values = {0.1,   -1.1920928955078125e-07,  5e-324,
                                      1e+16, -1.7976931348623157e+308, 2.220446049250313e-16};
  std::vector<std::string> doubles = distinct_doubles();
  for (std::size_t i = 0; i < texts.size(); ++i)
    doubles[i] = texts[i];
  const drench::test::TempDir dir;
  const std::vector<CcdBenchmarkQuery> queries =
      read_ccd_query_file(dir.write("exact.vf.txt", std::string(kHeader) + query_line("q#0", "0", doubles)));
  ASSERT_EQ(queries.size(), 1u);
  const double read[6] = {queries[0].query.p_t0.x(), queries[0].query.p_t0.y(), queries[0].query.p_t0.z(),
                          queries[0].query.a_t0.x(), queries[0].query.a_t0.y(), queries[0].query.a_t0.z()};
  for (std::size_t i = 0; i < values.size(); ++i)
    EXPECT_EQ(read[i], values[i]) << texts[i];
}

TEST(CcdQueryFile, AcceptsCrlfLineEndsBlankLinesAndNoFinalNewline) {
  std::string line = query_line("q#0", "1", distinct_doubles());
  line.pop_back();  // no final newline
  const drench::test::TempDir dir;
  const std::string path = dir.write("crlf.vf.txt", "# one\r\n# two\r\n\r\n" + line);
  const std::vector<CcdBenchmarkQuery> queries = read_ccd_query_file(path);
  ASSERT_EQ(queries.size(), 1u);
  EXPECT_EQ(queries[0].query.c_t1.z(), 24.5);

  std::string crlf = query_line("q#1", "0", distinct_doubles());
  crlf.insert(crlf.size() - 1, "\r");
  const std::vector<CcdBenchmarkQuery> with_crlf = read_ccd_query_file(dir.write("crlf2.vf.txt", crlf));
  ASSERT_EQ(with_crlf.size(), 1u);
  EXPECT_EQ(with_crlf[0].query.c_t1.z(), 24.5);
}

TEST(CcdQueryFile, ReturnsNoQueriesForAHeaderOnlyFile) {
  const drench::test::TempDir dir;
  EXPECT_TRUE(read_ccd_query_file(dir.write("empty.vf.txt", kHeader)).empty());
}

TEST(CcdQueryFile, ReportsAFileThatCannotBeOpened) {
  const drench::test::TempDir dir;
  const std::string missing = (dir.path() / "missing.vf.txt").string();
  EXPECT_TRUE(throws_containing<IoError>([&] { read_ccd_query_file(missing); },
                                         {missing + ": cannot read CCD query file", "No such file"}));
  EXPECT_TRUE(
      throws_containing<IoError>([&] { read_ccd_query_file(dir.path().string()); },
                                 {dir.path().string() + ": cannot read CCD query file: it is a folder"}));
}

/// Writes the header, one good query and then `bad_line`, and checks that reading names line 5 and the
/// culprit.
testing::AssertionResult bad_line_error(const std::string& bad_line,
                                        const std::vector<std::string>& expected) {
  const drench::test::TempDir dir;
  const std::string path =
      dir.write("bad.vf.txt", std::string(kHeader) + query_line("q#0", "1", distinct_doubles()) + bad_line);
  std::vector<std::string> parts = {path + ":5: "};
  parts.insert(parts.end(), expected.begin(), expected.end());
  return throws_containing<IoError>([&] { read_ccd_query_file(path); }, parts);
}

TEST(CcdQueryFile, ReportsAWrongFieldCountWithFileAndLine) {
  std::vector<std::string> short_doubles = distinct_doubles();
  short_doubles.pop_back();
  EXPECT_TRUE(bad_line_error(query_line("q#1", "1", short_doubles), {"expected 50 fields", "got 49"}));
  std::vector<std::string> long_doubles = distinct_doubles();
  long_doubles.push_back("25.5");
  EXPECT_TRUE(bad_line_error(query_line("q#1", "1", long_doubles), {"expected 50 fields", "got 51"}));
  EXPECT_TRUE(bad_line_error("q#1\n", {"expected 50 fields", "got 1"}));
}

TEST(CcdQueryFile, ReportsATruthOtherThanZeroOrOne) {
  EXPECT_TRUE(
      bad_line_error(query_line("q#1", "2", distinct_doubles()), {"truth (field 2) must be 0 or 1, got 2"}));
  EXPECT_TRUE(bad_line_error(query_line("q#1", "true", distinct_doubles()),
                             {"truth (field 2) must be 0 or 1, got true"}));
  EXPECT_TRUE(bad_line_error(query_line("q#1", "01", distinct_doubles()), {"must be 0 or 1, got 01"}));
}

TEST(CcdQueryFile, ReportsADoubleThatDoesNotParse) {
  EXPECT_TRUE(bad_line_error(query_line("q#1", "0", doubles_with(1, "abc")),
                             {"d1 (p_t0.x, field 27) is not a number, got abc"}));
  EXPECT_TRUE(bad_line_error(query_line("q#1", "0", doubles_with(5, "1.0x")),
                             {"d5 (a_t0.y, field 31) is not a number, got 1.0x"}));
  EXPECT_TRUE(bad_line_error(query_line("q#1", "0", doubles_with(24, "1/2")),
                             {"d24 (c_t1.z, field 50) is not a number, got 1/2"}));
  EXPECT_TRUE(bad_line_error(query_line("q#1", "0", doubles_with(12, "1e999")),
                             {"d12 (c_t0.z, field 38) is out of the double range, got 1e999"}));
}

TEST(CcdQueryFile, ReportsANonFiniteDouble) {
  EXPECT_TRUE(bad_line_error(query_line("q#1", "0", doubles_with(13, "inf")),
                             {"d13 (p_t1.x, field 39) is not finite, got inf"}));
  EXPECT_TRUE(bad_line_error(query_line("q#1", "0", doubles_with(20, "-inf")), {"is not finite, got -inf"}));
  EXPECT_TRUE(bad_line_error(query_line("q#1", "0", doubles_with(2, "nan")), {"is not finite, got nan"}));
}

TEST(CcdQueryFile, CutsALongBadValueInTheMessage) {
  const std::string long_value(1000, 'x');
  const drench::test::TempDir dir;
  const std::string path = dir.write("long.vf.txt", query_line("q#0", "0", doubles_with(3, long_value)));
  try {
    read_ccd_query_file(path);
    FAIL() << "did not throw";
  } catch (const IoError& e) {
    EXPECT_LT(std::string(e.what()).size(), 300u) << e.what();
    EXPECT_NE(std::string(e.what()).find(path + ":1: d3 (p_t0.z, field 29) is not a number, got xxx"),
              std::string::npos)
        << e.what();
  }
}

TEST(CcdQueryFile, ListsAFileAsItself) {
  const drench::test::TempDir dir;
  const std::string path = dir.write("any-name.txt", kHeader);
  EXPECT_EQ(list_ccd_query_files(path), std::vector<std::string>{path});
}

TEST(CcdQueryFile, ListsQueryFilesOfADirectoryRecursivelyAndSorted) {
  const drench::test::TempDir dir;
  const std::string b = dir.write("b/two.vf.txt", kHeader);
  const std::string a2 = dir.write("a/z.vf.txt", kHeader);
  const std::string a1 = dir.write("a/deeper/y.vf.txt", kHeader);
  const std::string top = dir.write("top.vf.txt", kHeader);
  dir.write("a/readme.txt", "not a query file");
  dir.write("a/counts.tsv", "not a query file");
  dir.write("b/vf.txt", "not a query file either: the name must end in .vf.txt");
  EXPECT_EQ(list_ccd_query_files(dir.path().string()), (std::vector<std::string>{a1, a2, b, top}));
}

TEST(CcdQueryFile, ReportsAMissingPathOrADirectoryWithoutQueryFiles) {
  const drench::test::TempDir dir;
  const std::string missing = dir.path().string() + "/missing";
  EXPECT_TRUE(throws_containing<IoError>([&] { list_ccd_query_files(missing); },
                                         {missing + ": cannot read CCD query files", "No such file"}));
  dir.write("sub/readme.txt", "no queries here");
  EXPECT_TRUE(throws_containing<IoError>([&] { list_ccd_query_files(dir.path().string()); },
                                         {dir.path().string() + ": holds no *.vf.txt file"}));
}

/// One row of the data folder's counts.tsv.
struct ExpectedCounts {
  std::int64_t queries = 0, positives = 0, negatives = 0;
};

TEST(CcdQueryFile, ReadsEverySharedDataFileWithTheCountsOfCountsTsv) {
  DRENCH_REQUIRE_CCD_DATA(dir);
  std::ifstream tsv(dir + "/counts.tsv");
  ASSERT_TRUE(tsv) << "cannot read " << dir << "/counts.tsv";
  std::map<std::string, ExpectedCounts> expected;  // by path relative to dir
  std::string line;
  std::getline(tsv, line);
  ASSERT_EQ(line.rfind("category\tfile\tqueries\tpositives\tnegatives", 0), 0u) << "header: " << line;
  while (std::getline(tsv, line)) {
    if (line.empty()) continue;
    std::istringstream fields(line);
    std::string category, file;
    ExpectedCounts counts;
    ASSERT_TRUE(fields >> category >> file >> counts.queries >> counts.positives >> counts.negatives) << line;
    expected[category + "/" + file + ".vf.txt"] = counts;
  }
  // The README's totals, so that a truncated counts.tsv cannot pass.
  ExpectedCounts total;
  for (const auto& [name, counts] : expected) {
    total.queries += counts.queries;
    total.positives += counts.positives;
    total.negatives += counts.negatives;
  }
  EXPECT_EQ(total.queries, 37124);
  EXPECT_EQ(total.positives, 248 + 33933);
  EXPECT_EQ(total.negatives, 2837 + 106);

  std::set<std::string> listed;
  for (const std::string& path : list_ccd_query_files(dir)) {
    const std::string name = fs::path(path).lexically_relative(dir).generic_string();
    listed.insert(name);
    const auto row = expected.find(name);
    if (row == expected.end()) {
      ADD_FAILURE() << name << " is in " << dir << " but not in counts.tsv";
      continue;
    }
    const std::vector<CcdBenchmarkQuery> queries = read_ccd_query_file(path);
    std::int64_t positives = 0;
    std::set<std::string> ids;
    for (const CcdBenchmarkQuery& q : queries) {
      positives += q.collides ? 1 : 0;
      ids.insert(q.id);
    }
    const auto n = static_cast<std::int64_t>(queries.size());
    EXPECT_EQ(n, row->second.queries) << name;
    EXPECT_EQ(positives, row->second.positives) << name;
    EXPECT_EQ(n - positives, row->second.negatives) << name;
    EXPECT_EQ(static_cast<std::int64_t>(ids.size()), n) << name << ": query ids are not unique";
  }
  for (const auto& [name, counts] : expected)
    EXPECT_EQ(listed.count(name), 1u) << name << " is missing";
}

}  // namespace
}  // namespace drench::ccd
