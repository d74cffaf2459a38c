// `accelbench compare`: cases matched by scene, configuration, ray set, query and threads; the ratio of
// medians; a regression only when beyond the threshold and significant; cases in one run only; warnings;
// exit codes through the binary.
#include "harness/compare_runs.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "tests/cli_test_helpers.h"

namespace ab {
namespace {

using nlohmann::json;

json row(const std::string& config, int threads, std::vector<double> seconds) {
  std::vector<double> sorted = seconds;
  std::sort(sorted.begin(), sorted.end());
  return {{"scene", "flake-1000"},
          {"config_label", config},
          {"accelerator", config},
          {"rays", "primary-1024"},
          {"query", "closest"},
          {"threads", threads},
          {"seconds_median", sorted[sorted.size() / 2]},
          {"seconds_samples", seconds}};
}

json report(std::vector<json> rows, std::vector<double> build_seconds, const std::string& host = "a") {
  std::vector<double> sorted = build_seconds;
  std::sort(sorted.begin(), sorted.end());
  return {{"suite_name", "t"},
          {"suite", {{"name", "t"}}},
          {"machine", {{"cpu_model", "x"}, {"logical_cores", 2}, {"hostname", host}}},
          {"compiler", {{"compiler", "gcc"}, {"version", "12"}, {"flags", "-O3"}}},
          {"results", rows},
          {"builds",
           {{{"scene", "flake-1000"},
             {"config_label", "bvh-sah"},
             {"build_seconds", {{"median", sorted[sorted.size() / 2]}, {"samples", build_seconds}}}}}}};
}

const std::vector<double> kBase{1.00, 1.01, 0.99, 1.02, 0.98};
const std::vector<double> kSlower{1.20, 1.21, 1.19, 1.22, 1.18};   // 20% more seconds: throughput / 1.2
const std::vector<double> kNoise{1.01, 0.99, 1.00, 1.03, 0.97};    // within noise
const std::vector<double> kOverlap{0.90, 1.30, 0.95, 1.25, 1.00};  // median +0%, no clear order

TEST(CompareRuns, FindsASignificantRegressionBeyondTheThreshold) {
  const json base = report({row("bvh-sah", 1, kBase), row("bvh-sah", 0, kBase)}, kBase);
  const json next = report({row("bvh-sah", 1, kSlower), row("bvh-sah", 0, kNoise)}, kNoise);
  const RunComparison c = compare_runs(base, next, 0.05, 0.05);
  ASSERT_EQ(c.cases.size(), 3u);  // two queries and the build
  EXPECT_EQ(c.cases[0].change, Change::kRegression);
  EXPECT_NEAR(c.cases[0].ratio, 1.0 / 1.2, 1e-9);  // rays/s NEW/BASE
  EXPECT_NEAR(c.cases[0].p_value, 2.0 / 252.0, 1e-12);
  EXPECT_EQ(c.cases[1].change, Change::kUnchanged);
  EXPECT_EQ(c.cases[2].query, "build");
  EXPECT_EQ(c.cases[2].change, Change::kUnchanged);
  EXPECT_TRUE(c.regressed());
  EXPECT_TRUE(c.warnings.empty());
}

TEST(CompareRuns, CpuComparesTheCpuSeconds) {
  // The wall clock says 20% slower (a loaded machine), the cpu seconds say unchanged: --cpu judges by these.
  auto with_cpu = [](json r, const std::vector<double>& cpu) {
    std::vector<double> sorted = cpu;
    std::sort(sorted.begin(), sorted.end());
    r["cpu_seconds_median"] = sorted[sorted.size() / 2];
    r["cpu_seconds_samples"] = cpu;
    return r;
  };
  const json base = report({with_cpu(row("bvh-sah", 1, kBase), kBase)}, kBase);
  const json next = report({with_cpu(row("bvh-sah", 1, kSlower), kNoise)}, kBase);
  EXPECT_TRUE(compare_runs(base, next, 0.05, 0.05).regressed());
  const RunComparison c = compare_runs(base, next, 0.05, 0.05, true);
  EXPECT_FALSE(c.regressed());
  EXPECT_TRUE(c.warnings.empty());
  EXPECT_NEAR(c.cases[0].ratio, 1.0, 0.02);
  // A report without cpu times is named, not silently judged equal.
  const RunComparison old = compare_runs(report({row("bvh-sah", 1, kBase)}, kBase), next, 0.05, 0.05, true);
  ASSERT_EQ(old.warnings.size(), 1u);
  EXPECT_NE(old.warnings[0].find("BASE has no cpu times"), std::string::npos);
}

TEST(CompareRuns, ImprovementsAndBuildRegressions) {
  const json base = report({row("bvh-sah", 1, kSlower)}, kBase);
  const json next = report({row("bvh-sah", 1, kBase)}, kSlower);
  const RunComparison c = compare_runs(base, next, 0.05, 0.05);
  ASSERT_EQ(c.cases.size(), 2u);
  EXPECT_EQ(c.cases[0].change, Change::kImprovement);
  EXPECT_EQ(c.cases[1].change, Change::kRegression);  // the build takes 20% longer
  EXPECT_NEAR(c.cases[1].ratio, 1.2, 1e-9);
}

TEST(CompareRuns, NotSignificantOrWithinTheThresholdIsNoRegression) {
  const json base = report({row("bvh-sah", 1, kBase)}, kBase);
  EXPECT_FALSE(compare_runs(base, report({row("bvh-sah", 1, kOverlap)}, kBase), 0.05, 0.05).regressed());
  EXPECT_FALSE(compare_runs(base, report({row("bvh-sah", 1, kSlower)}, kBase), 0.25, 0.05).regressed());
  EXPECT_FALSE(compare_runs(base, report({row("bvh-sah", 1, kSlower)}, kBase), 0.05, 0.005).regressed());
  // Two repetitions can never reach p < 0.05 (the smallest exact p is 1/3).
  const json two = report({row("bvh-sah", 1, {1.0, 1.01})}, kBase);
  const RunComparison c = compare_runs(two, report({row("bvh-sah", 1, {2.0, 2.01})}, kBase), 0.05, 0.05);
  EXPECT_EQ(c.cases[0].change, Change::kUnchanged);
  EXPECT_NEAR(c.cases[0].p_value, 1.0 / 3.0, 1e-12);
}

TEST(CompareRuns, CasesInOneRunAndWarnings) {
  const json base = report({row("bvh-sah", 1, kBase), row("grid", 1, kBase)}, kBase, "a");
  json next = report({row("bvh-sah", 1, kBase), row("kdtree-sah", 1, kBase)}, kBase, "b");
  next["suite_name"] = "other";
  const RunComparison c = compare_runs(base, next, 0.05, 0.05);
  EXPECT_EQ(c.cases.size(), 2u);
  ASSERT_EQ(c.only_base.size(), 1u);
  EXPECT_NE(c.only_base[0].find("grid"), std::string::npos);
  ASSERT_EQ(c.only_new.size(), 1u);
  EXPECT_NE(c.only_new[0].find("kdtree-sah"), std::string::npos);
  ASSERT_EQ(c.warnings.size(), 2u);  // machines (hostname) and suites
  EXPECT_NE(c.warnings[0].find("machines"), std::string::npos);
  EXPECT_NE(c.warnings[1].find("suites"), std::string::npos);
}

TEST(CompareRuns, WithoutRepetitionsAChangeIsUntested) {
  json base = report({row("bvh-sah", 1, kBase)}, kBase), next = report({row("bvh-sah", 1, kSlower)}, kBase);
  base["results"][0].erase("seconds_samples");
  const RunComparison c = compare_runs(base, next, 0.05, 0.05);
  EXPECT_EQ(c.cases[0].change, Change::kUntested);
  EXPECT_FALSE(c.regressed());
  EXPECT_TRUE(to_json(c)["cases"][0]["p_value"].is_null());
  EXPECT_NE(to_csv(c).find("untested"), std::string::npos);
}

/// The CLI: exit 1 on a regression, 0 without, 2 on bad input; --json and --csv written.
TEST(CompareRuns, CommandExitCodesAndOutputs) {
  const std::string bin = test::accelbench_exe();
  if (!std::filesystem::exists(bin)) GTEST_SKIP() << "accelbench binary not found at " << bin;
  const auto dir =
      std::filesystem::temp_directory_path() / ("accelbench_compare_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "base");
  auto write = [&](const std::filesystem::path& p, const json& j) { std::ofstream(p) << j.dump(); };
  write(dir / "base" / "report.json", report({row("bvh-sah", 1, kBase)}, kBase));
  write(dir / "slower.json", report({row("bvh-sah", 1, kSlower)}, kBase));
  write(dir / "same.json", report({row("bvh-sah", 1, kNoise)}, kBase));
  std::ofstream(dir / "bad.json") << "{ not json";
  auto run = [&](const std::string& args) { return test::run_accelbench("compare " + args, dir).first; };
  const std::string base = (dir / "base").string();
  EXPECT_EQ(run(base + " " + (dir / "slower.json").string() + " --json " + (dir / "t.json").string() +
                " --csv " + (dir / "t.csv").string()),
            1);
  EXPECT_EQ(json::parse(std::ifstream(dir / "t.json"))["regressed"], true);
  EXPECT_TRUE(std::filesystem::exists(dir / "t.csv"));
  EXPECT_EQ(run(base + " " + (dir / "same.json").string()), 0);
  EXPECT_EQ(run(base + " " + (dir / "slower.json").string() + " --threshold 30"), 0);
  EXPECT_EQ(run(base + " " + (dir / "bad.json").string()), 2);
  EXPECT_EQ(run(base + " " + (dir / "missing").string()), 2);
  EXPECT_EQ(run(base + " " + (dir / "same.json").string() + " --alpha 2"), 2);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace ab
