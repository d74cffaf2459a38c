// Interleaved timing (docs/suites.md, "interleave"): cases timed together get their repetitions in one
// random order and keep their own figures; an interleaved suite gives the same rows, counts and checks as
// one timed configuration after another.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "harness/bench.h"
#include "harness/run.h"
#include "harness/suite.h"

namespace ab {
namespace {

using nlohmann::json;

TEST(Harness, TimeTogetherInterleavesTheRepetitionsAndKeepsEachCasesOwn) {
  BenchTimer timer;
  std::vector<int> order;  // which case ran, pass by pass
  std::vector<BenchCase> cases;
  for (int k = 0; k < 3; ++k)
    cases.push_back(BenchCase{"unit/together/" + std::to_string(k),
                              2,
                              [&order, k] {
                                order.push_back(k);
                                return 0.001 * (k + 1);
                              },
                              0.0,
                              {}});
  const std::vector<Timing> t = timer.time_together(cases, 10);
  ASSERT_EQ(t.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_DOUBLE_EQ(t[k].median, 0.001 * (k + 1)) << k;
    EXPECT_EQ(t[k].samples.size(), 10u) << k;
    EXPECT_EQ(t[k].iterations, 2) << k;
  }
  ASSERT_EQ(order.size(), 60u);
  // One case after another would switch cases twice; a random order of 30 repetitions of three cases does
  // so that rarely with probability 6 / (30! / 10!^3), about 1e-12.
  int switches = 0;
  for (size_t i = 1; i < order.size(); ++i) switches += order[i] != order[i - 1];
  EXPECT_GT(switches, 2);
}

json run_small_suite(bool interleave) {
  json j = json::parse(R"({
    "repetitions": 2, "warmup": 1, "min_time": 0, "threads": [1, 2],
    "scenes": [{"generator": "sphereflake", "triangles": 3000}, {"generator": "soup", "triangles": 2000}],
    "accelerators": ["embree", "bvh-sah", "kdtree-sah", "grid"],
    "rays": [{"kind": "primary", "count": 512}, {"kind": "shadow", "count": 512}],
    "verify": {"brute_rays": 0, "reference": "bvh-sah", "embree": true}})");
  j["interleave"] = interleave;
  const auto dir = std::filesystem::temp_directory_path() /
                   ("accelbench_interleave_" + std::to_string(::getpid()) + (interleave ? "_i" : "_s"));
  RunOptions options;
  options.out_dir = dir.string();
  json report = run_suite(parse_suite(j, "interleave.json", ""), options);
  std::filesystem::remove_all(dir);
  return report;
}

TEST(Run, InterleavedSuiteGivesTheRowsOfOneConfigurationAfterAnother) {
  const json one_by_one = run_small_suite(false), together = run_small_suite(true);
  ASSERT_TRUE(together["verified"].get<bool>()) << together["failures"].dump();
  ASSERT_TRUE(one_by_one["verified"].get<bool>()) << one_by_one["failures"].dump();
  using Key = std::tuple<std::string, std::string, std::string, std::string, int>;
  auto rows = [](const json& report) {
    std::map<Key, json> by_key;
    for (const json& r : report["results"]) {
      json counts = json::object();
      for (const char* field : {"nodes_per_ray", "prims_per_ray", "brute_mismatches", "thread_mismatches",
                                "any_hit_mismatches", "ray_count", "references_per_triangle"})
        if (r.contains(field)) counts[field] = r[field];
      EXPECT_TRUE(r["ratio_to_embree"].is_number()) << r.dump();
      EXPECT_EQ(r["seconds_samples"].size(), 2u);
      by_key[{r["scene"], r["config_label"], r["rays"], r["query"], r["threads"]}] = counts;
    }
    return by_key;
  };
  const auto a = rows(one_by_one), b = rows(together);
  EXPECT_EQ(a.size(),
            2u * 4u * 2u * 3u);  // scenes x configurations x thread counts x (closest, closest, any)
  EXPECT_EQ(a, b);
  ASSERT_EQ(together["builds"].size(), one_by_one["builds"].size());
  for (size_t i = 0; i < together["builds"].size(); ++i)
    EXPECT_EQ(together["builds"][i]["verification"], one_by_one["builds"][i]["verification"]) << i;
}

}  // namespace
}  // namespace ab
