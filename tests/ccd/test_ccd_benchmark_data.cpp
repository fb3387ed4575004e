// The outside benchmark (../shared/data/ccd-vertex-face, Wang et al. 2021 and Belgrod et al. 2023): the fast
// solver misses no collision and reports few false positives; the exact reference reproduces the labels.

#include <gtest/gtest.h>

#include <map>
#include <string>

#include <drench/ccd/ccd_exact_reference.hpp>
#include <drench/ccd/ccd_query_file.hpp>
#include <drench/ccd/point_triangle_ccd.hpp>
#include "ccd_test_data.hpp"

namespace drench::ccd {
namespace {

struct PartCounts {
  int queries = 0;
  int false_negatives = 0;
  int false_positives = 0;
};

/// Runs the default solver (what the coupler uses) over every file under `dir/part`.
PartCounts run_part(const std::string& dir, const std::string& part) {
  PartCounts counts;
  for (const std::string& file : list_ccd_query_files(dir + "/" + part)) {
    for (const CcdBenchmarkQuery& q : read_ccd_query_file(file)) {
      const bool hit = point_triangle_ccd(q.query).hit;
      ++counts.queries;
      if (q.collides && !hit) {
        ++counts.false_negatives;
        ADD_FAILURE() << "missed collision " << q.id << " (" << file << ")";
      }
      counts.false_positives += !q.collides && hit;
    }
  }
  return counts;
}

TEST(CcdBenchmarkData, MissesNoCollisionOfTheHandcraftedPart) {
  DRENCH_REQUIRE_CCD_DATA(dir);
  const PartCounts counts = run_part(dir, "handcrafted");
  EXPECT_EQ(counts.queries, 3085);
  EXPECT_EQ(counts.false_negatives, 0);
  // Tight-Inclusion reports 85 here at its tolerance 1e-6; the issue asks for at most 40.
  EXPECT_LE(counts.false_positives, 40);
  RecordProperty("false_positives", counts.false_positives);
}

TEST(CcdBenchmarkData, MissesNoCollisionOfTheSimulationPart) {
  DRENCH_REQUIRE_CCD_DATA(dir);
  const PartCounts counts = run_part(dir, "simulation-belgrod2023");
  EXPECT_EQ(counts.queries, 34039);
  EXPECT_EQ(counts.false_negatives, 0);
  // Every one of the 106 negatives is a near contact; Tight-Inclusion reports all of them. At most 10 here.
  EXPECT_LE(counts.false_positives, 10);
  RecordProperty("false_positives", counts.false_positives);
}

TEST(CcdBenchmarkData, ExactReferenceReproducesTheLabelsOfTheDegenerateFiles) {
  DRENCH_REQUIRE_CCD_DATA(dir);
  // The handcrafted part and the two simulation files full of degenerate contacts (vertices crossing exactly
  // on edges in cloth-funnel, near-parallel motion in rod-twist). The rest of the simulation part is left to
  // the fast solver test above: the reference is ~100 microseconds per query.
  std::vector<std::string> files = list_ccd_query_files(dir + "/handcrafted");
  files.push_back(dir + "/simulation-belgrod2023/cloth-funnel-227.vf.txt");
  files.push_back(dir + "/simulation-belgrod2023/rod-twist-3036.vf.txt");
  int queries = 0;
  for (const std::string& file : files) {
    for (const CcdBenchmarkQuery& q : read_ccd_query_file(file)) {
      ++queries;
      EXPECT_EQ(point_triangle_ccd_exact(q.query).hit, q.collides) << q.id;
    }
  }
  EXPECT_EQ(queries, 3085 + 92 + 801);
}

}  // namespace
}  // namespace drench::ccd
