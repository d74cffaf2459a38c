// Suite parsing and validation: grids expand, "all" expands, and every kind of bad input is one
// InputError naming the field; the shipped suites parse and validate.
#include "harness/suite.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <thread>

#include "accel/core/error.h"
#include "accel/core/registry.h"
#include "datasets/generators.h"
#include "harness/analysis.h"
#include "harness/bench.h"
#include "harness/report.h"

namespace ab {
namespace {

using nlohmann::json;

json minimal_suite() {
  return json::parse(R"({
    "scenes": [{"generator": "soup", "triangles": 100}],
    "accelerators": ["brute"],
    "rays": [{"kind": "primary", "count": 16}]
  })");
}

/// The message of the InputError that parsing and validating `j` throws ("" when none).
std::string error_of(const json& j) {
  try {
    validate_suite(parse_suite(j, "s.json", ""));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Suite, MinimalSuiteGetsDefaults) {
  const Suite s = parse_suite(minimal_suite(), "s.json", "");
  EXPECT_NO_THROW(validate_suite(s));
  ASSERT_EQ(s.scenes.size(), 1u);
  EXPECT_EQ(s.scenes[0].label, "soup-100");
  EXPECT_EQ(s.repetitions, 3);
  EXPECT_EQ(s.threads, (std::vector<int>{1, 0}));
  EXPECT_EQ(s.verify.brute_rays, 2000u);
  EXPECT_FALSE(s.rays[0].any_hit);
}

TEST(Suite, ParameterListsExpandToAGrid) {
  json j = minimal_suite();
  j["accelerators"] = json::parse(R"([{"name": "grid", "params": {"lambda": [1, 2, 4, 8]}},
                                      {"name": "bvh-sah", "params": {"bins": [8, 16], "leaf_size": 4}}])");
  const Suite s = parse_suite(j, "s.json", "");
  ASSERT_EQ(s.accelerators.size(), 6u);
  EXPECT_EQ(s.accelerators[0].label, "grid{lambda=1}");
  EXPECT_EQ(s.accelerators[3].params.at("lambda"), "8");
  EXPECT_EQ(s.accelerators[4].label, "bvh-sah{bins=8,leaf_size=4}");
  EXPECT_EQ(s.accelerators[5].params.at("bins"), "16");
  EXPECT_EQ(s.accelerators[5].field, "accelerators[1]");
}

TEST(Suite, SizesAndGeneratorParamsExpand) {
  json j = minimal_suite();
  j["scenes"] =
      json::parse(R"([{"generator": "soup", "triangles": [10, 20], "params": {"size": [0.1, 0.5]}}])");
  const Suite s = parse_suite(j, "s.json", "");
  ASSERT_EQ(s.scenes.size(), 4u);
  EXPECT_EQ(s.scenes[0].label, "soup{size=0.1}-10");
  EXPECT_EQ(s.scenes[1].triangles, 20u);
}

TEST(Suite, AllMeansEveryRegisteredStructureButBruteAndTestOnes) {
  json j = minimal_suite();
  j["accelerators"] = {"brute", "all"};
  const Suite s = parse_suite(j, "s.json", "");
  std::set<std::string> names;
  for (const auto& a : s.accelerators) names.insert(a.name);
  for (const auto& info : accelerators()) {
    const bool left_out = info.name.rfind("test-", 0) == 0 || info.name == "cgal" || info.name == "bullet";
    EXPECT_EQ(names.count(info.name), left_out ? 0u : 1u) << info.name;  // the outside peers are named
  }
  EXPECT_EQ(s.accelerators.size(), names.size());  // brute once
}

TEST(Suite, ShadowRaysAlsoTimeAnyHit) {
  json j = minimal_suite();
  j["rays"] =
      json::parse(R"([{"kind": "shadow", "count": 8}, {"kind": "primary", "count": 8, "any_hit": true}])");
  const Suite s = parse_suite(j, "s.json", "");
  EXPECT_TRUE(s.rays[0].any_hit);
  EXPECT_TRUE(s.rays[1].any_hit);
}

struct BadCase {
  const char* patch;     // JSON merge-patch applied to the minimal suite
  const char* expected;  // the error message must start with this
};

TEST(Suite, BadInputNamesTheField) {
  const BadCase cases[] = {
      {R"({"scens": 1})", "s.json: scens: unknown field"},
      {R"({"scenes": null})", "s.json: missing field 'scenes'"},
      {R"({"scenes": []})", "s.json: scenes: expected a non-empty list"},
      {R"({"scenes": [{"generator": "soup"}]})", "s.json: scenes[0]: missing field 'triangles'"},
      {R"({"scenes": [{"generator": "soup", "triangles": -5}]})",
       "s.json: scenes[0].triangles: -5 is outside [1, "},
      {R"({"scenes": [{"generator": "soup", "triangles": [10, "x"]}]})",
       "s.json: scenes[0].triangles[1]: expected"},
      {R"({"scenes": [{"generator": "nope", "triangles": 10}]})",
       "s.json: scenes[0].generator: unknown generator 'nope'"},
      {R"({"scenes": [{"generator": "soup", "triangles": 10, "params": {"bogus": 1}}]})",
       "s.json: scenes[0].params: "},
      {R"({"scenes": [{"mesh": "/nonexistent/x.obj"}]})",
       "s.json: scenes[0].mesh: /nonexistent/x.obj: no such file"},
      {R"({"scenes": [{"mesh": "a.obj", "generator": "soup"}]})", "s.json: scenes[0]: give exactly one of"},
      {R"({"accelerators": ["brute", "bvh-sah", "foo"]})",
       "s.json: accelerators[2].name: unknown accelerator 'foo'"},
      {R"({"accelerators": [{"name": "foo"}]})", "s.json: accelerators[0].name: unknown accelerator 'foo'"},
      {R"({"accelerators": [{"params": {}}]})", "s.json: accelerators[0].name: expected a non-empty string"},
      {R"({"accelerators": [{"name": "brute", "params": {"x": 1}}]})",
       "s.json: accelerators[0].params: unknown parameter 'x'"},
      {R"({"accelerators": [{"name": "brute", "params": {"x": []}}]})",
       "s.json: accelerators[0].params.x: empty list"},
      {R"({"accelerators": [{"name": "brute", "params": {"x": {"y": 1}}}]})",
       "s.json: accelerators[0].params.x: expected a number"},
      {R"({"accelerators": ["brute", "brute"]})", "s.json: accelerators[1]: duplicate entry 'brute'"},
      {R"({"accelerators": [{"name": "brute", "extra": 1}]})",
       "s.json: accelerators[0].extra: unknown field"},
      {R"({"rays": [{"kind": "sideways", "count": 10}]})",
       "s.json: rays[0].kind: unknown ray kind 'sideways'"},
      {R"({"rays": [{"kind": "primary"}]})", "s.json: rays[0]: missing field 'count'"},
      {R"({"rays": [{"kind": "primary", "count": 0}]})", "s.json: rays[0].count: 0 is outside"},
      {R"({"rays": [{"file": "/nonexistent.rays"}]})",
       "s.json: rays[0].file: /nonexistent.rays: no such file"},
      {R"({"rays": []})", "s.json: rays: no ray sets"},
      {R"({"threads": [1, -2]})", "s.json: threads[1]: -2 is outside [0, 4096]"},
      {R"({"threads": []})", "s.json: threads: expected a non-empty list"},
      {R"({"repetitions": 0})", "s.json: repetitions: 0 is outside"},
      {R"({"min_time": "fast"})", "s.json: min_time: expected a number"},
      {R"({"verify": {"reference": "foo"}})", "s.json: verify.reference: unknown accelerator 'foo'"},
      {R"({"verify": {"brute": 1}})", "s.json: verify.brute: unknown field"},
  };
  for (const BadCase& c : cases) {
    json j = minimal_suite();
    j.merge_patch(json::parse(c.patch));
    const std::string message = error_of(j);
    EXPECT_EQ(message.rfind(c.expected, 0), 0u) << "patch " << c.patch << "\n  got: " << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

TEST(Suite, UnreadableOrInvalidFileIsOneLine) {
  EXPECT_THROW(read_suite("/nonexistent/suite.json"), InputError);
  const std::string path = ::testing::TempDir() + "bad_suite.json";
  std::ofstream(path) << "{\"scenes\": [1, 2,]}";
  try {
    read_suite(path);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(path + ": invalid JSON", 0), 0u) << e.what();
  }
}

/// The message of the InputError that read_suite throws for a file holding `text` ("" when none).
std::string read_error_of(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  try {
    read_suite(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// Fuzzing findings (fuzz/regressions/suite): a number out of double's range aborted the process
// (nlohmann's out_of_range escaped), and out-of-range or fractional counts were converted to integers
// (undefined behaviour) before the range check.
TEST(Suite, FuzzedNumbersAreOneLineErrors) {
  const std::string path = ::testing::TempDir() + "s_1e400.json";
  const std::string huge = read_error_of("s_1e400.json", R"({"seed": 1e400})");
  EXPECT_EQ(huge.rfind(path + ": invalid JSON: ", 0), 0u) << huge;
  EXPECT_NE(huge.find("1e400"), std::string::npos) << huge;
  EXPECT_EQ(huge.find('\n'), std::string::npos) << huge;
  const BadCase cases[] = {
      {R"({"seed": 1e20})", "s.json: seed: expected a non-negative integer, got 1e+20"},
      {R"({"seed": -1.5})", "s.json: seed: expected a non-negative integer, got -1.5"},
      {R"({"repetitions": 2.5})", "s.json: repetitions: expected a non-negative integer"},
      {R"({"repetitions": -1e300})", "s.json: repetitions: expected a non-negative integer"},
      {R"({"scenes": [{"generator": "soup", "triangles": 1.8446744073709552e19}]})",
       "s.json: scenes[0].triangles: expected a non-negative integer"},
      {R"({"threads": [1e19]})", "s.json: threads[0]: 1e+19 is outside [0, 4096]"},
  };
  for (const BadCase& c : cases) {
    json j = minimal_suite();
    j.merge_patch(json::parse(c.patch));
    const std::string message = error_of(j);
    EXPECT_EQ(message.rfind(c.expected, 0), 0u) << "patch " << c.patch << "\n  got: " << message;
  }
  json whole = minimal_suite();
  whole["seed"] = 7.0;
  EXPECT_EQ(parse_suite(whole, "s.json", "").seed, 7u);
}

// A short file must not expand into billions of configurations (memory exhaustion).
TEST(Suite, ParameterGridIsBounded) {
  json j = minimal_suite();
  json params = json::object();
  for (const char* key : {"a", "b", "c", "d", "e", "f", "g", "h"})
    params[key] = json::parse("[1, 2, 3, 4, 5, 6, 7, 8]");
  j["accelerators"] = json::array({{{"name", "brute"}, {"params", params}}});
  const std::string message = error_of(j);
  EXPECT_EQ(message.rfind("s.json: accelerators[0].params.e: the parameter lists give more than 4096", 0), 0u)
      << message;
}

TEST(Suite, RelativePathsResolveAgainstTheSuiteFolder) {
  json j = minimal_suite();
  j["scenes"] = json::parse(R"([{"mesh": "meshes/a.obj"}])");
  const Suite s = parse_suite(j, "dir/s.json", "/base/dir");
  EXPECT_EQ(s.scenes[0].path, "/base/dir/meshes/a.obj");
  EXPECT_EQ(s.scenes[0].label, "a");
}

TEST(Suite, DefaultSuiteIsTheShippedFileAndCoversTheBrief) {
  std::ifstream in(std::string(ACCELBENCH_SOURCE_DIR) + "/suites/default.json");
  std::stringstream file;
  file << in.rdbuf();
  EXPECT_EQ(file.str(), compiled_default_suite_text()) << "update the compiled-in copy in harness/suite.cpp";
  const Suite s = default_suite();
  EXPECT_NO_THROW(validate_suite(s));
  std::map<std::string, std::set<uint64_t>> sizes;
  for (const auto& sc : s.scenes) sizes[sc.generator].insert(sc.triangles);
  EXPECT_GE(sizes.size(), 4u);
  for (const auto& [gen, n] : sizes) EXPECT_GE(n.size(), 2u) << gen;
  std::set<std::string> kinds;
  for (const auto& r : s.rays) kinds.insert(r.kind);
  for (const char* k : {"primary", "shadow", "diffuse", "incoherent"}) EXPECT_EQ(kinds.count(k), 1u) << k;
  std::set<std::string> names;
  for (const auto& a : s.accelerators) names.insert(a.name);
  for (const auto& info : accelerators())
    if (info.name != "brute" && info.name != "cgal" && info.name != "bullet" &&
        info.name.rfind("test-", 0) != 0) {  // "all" leaves out brute and the outside peers
      EXPECT_EQ(names.count(info.name), 1u) << info.name;
    }
  EXPECT_EQ(s.threads, (std::vector<int>{1, 0}));
}

TEST(Suite, ShippedSuitesValidate) {
  for (const char* name : {"quick", "scaling", "default", "million", "hostile", "motion"}) {
    const Suite s = read_suite(std::string(ACCELBENCH_SOURCE_DIR) + "/suites/" + name + ".json");
    EXPECT_NO_THROW(validate_suite(s)) << name;
  }
  const Suite scaling = read_suite(std::string(ACCELBENCH_SOURCE_DIR) + "/suites/scaling.json");
  EXPECT_FALSE(scaling.build_only);  // it also traces: every structure must trace 10M triangles (issue 11)
  EXPECT_FALSE(scaling.rays.empty());
  std::set<uint64_t> n;
  for (const auto& sc : scaling.scenes) n.insert(sc.triangles);
  EXPECT_EQ(*n.begin(), 1000u);
  EXPECT_EQ(*n.rbegin(), 10000000u);
}

TEST(Harness, PearsonAndIterations) {
  EXPECT_NEAR(pearson({1, 2, 3, 4}, {2, 4, 6, 8}), 1.0, 1e-12);
  EXPECT_NEAR(pearson({1, 2, 3, 4}, {8, 6, 4, 2}), -1.0, 1e-12);
  EXPECT_NEAR(pearson({1, 2, 3}, {1, 3, 2}), 0.5, 1e-12);
  EXPECT_TRUE(std::isnan(pearson({1, 1, 1}, {1, 2, 3})));
  EXPECT_EQ(iterations_for(0.5, 0.1), 1);
  EXPECT_EQ(iterations_for(0.001, 0.01), 10);
  EXPECT_EQ(iterations_for(0.001, 0.0), 1);
}

TEST(Suite, PrimaryViewsGetTheirOwnLabel) {
  json j = minimal_suite();
  j["rays"] = json::parse(R"([{"kind": "primary", "count": 16},
                              {"kind": "primary", "count": 16, "views": 4}])");
  const Suite s = parse_suite(j, "s.json", "");
  ASSERT_EQ(s.rays.size(), 2u);
  EXPECT_EQ(s.rays[0].views, 1u);
  EXPECT_EQ(s.rays[1].views, 4u);
  EXPECT_EQ(s.rays[1].label, "primary-views4");
  j["rays"] = json::parse(R"([{"kind": "shadow", "count": 16, "views": 2}])");
  EXPECT_NE(error_of(j).find("rays[0].views"), std::string::npos) << error_of(j);
  j["rays"] = json::parse(R"([{"kind": "primary", "count": 16, "views": 0}])");
  EXPECT_NE(error_of(j).find("rays[0].views"), std::string::npos) << error_of(j);
}

// The correlation analysis gives Pearson's r of the SAH cost and of EPO against the measured cost per ray,
// each over the configurations that report the metric.
TEST(Harness, CorrelatesSahAndEpoWithMeasuredCost) {
  json report = {{"results", json::array()}};
  const double sah[] = {1, 2, 3, 4}, epo[] = {4, 3, 2, 1}, cost[] = {10, 20, 30, 40};
  for (int i = 0; i < 4; ++i)
    report["results"].push_back({{"scene", "s"},
                                 {"rays", "primary"},
                                 {"query", "closest"},
                                 {"threads", 1},
                                 {"config_label", "c" + std::to_string(i)},
                                 {"sah_cost", sah[i]},
                                 {"epo", epo[i]},
                                 {"havran_cost_per_ray", cost[i]}});
  report["results"][0]["epo"] = nullptr;  // a configuration without EPO (not a BVH)
  fill_correlations(report, 1);
  ASSERT_EQ(report["sah_correlation"].size(), 1u);
  const json& g = report["sah_correlation"][0];
  EXPECT_NEAR(g["pearson"].get<double>(), 1.0, 1e-12);
  EXPECT_EQ(g["configurations"], 4);
  EXPECT_NEAR(g["epo_pearson"].get<double>(), -1.0, 1e-12);
  EXPECT_EQ(g["epo_configurations"], 3);
}

TEST(Harness, CsvQuotesAndFlattens) {
  json report = {{"results", json::array()}};
  report["results"].push_back({{"scene", "a,b"},
                               {"config_label", "grid{lambda=2}"},
                               {"params", {{"lambda", "2"}}},
                               {"rays_per_second", 1.5e6},
                               {"ratio_to_embree", nullptr},
                               {"verified", true}});
  const std::string csv = report_csv(report);
  std::istringstream lines(csv);
  std::string header, row;
  std::getline(lines, header);
  std::getline(lines, row);
  EXPECT_EQ(header.rfind("scene,triangles,accelerator,config_label,params,", 0), 0u);
  EXPECT_EQ(row.rfind("\"a,b\",,,grid{lambda=2},lambda=2,", 0), 0u) << row;
  EXPECT_NE(row.find(",1500000.0,"), std::string::npos) << row;
}

TEST(Harness, GoogleBenchmarkTimingReportsMedianMinMax) {
  BenchTimer timer;
  int calls = 0;
  const double times[] = {0.003, 0.001, 0.002};
  const Timing t = timer.time(
      "unit/test", 3, 2, [&] { return times[(calls++) / 2]; }, 100.0);
  EXPECT_EQ(calls, 6);
  EXPECT_DOUBLE_EQ(t.median, 0.002);
  EXPECT_DOUBLE_EQ(t.min, 0.001);
  EXPECT_DOUBLE_EQ(t.max, 0.003);
  EXPECT_EQ(t.iterations, 2);
  const json j = json::parse(timer.json());
  EXPECT_GE(j["benchmarks"].size(), 3u);
  EXPECT_NE(j["benchmarks"][0]["name"].get<std::string>().find("unit/test"), std::string::npos);
}

TEST(Harness, CpuTimeLeavesOutWaiting) {
  // A pass that sleeps takes wall time but almost no cpu; a pass that spins takes both: the cpu figures are
  // the process's work, not the time it spent off the cores.
  BenchTimer timer;
  auto timed = [](auto&& work) {
    return [work] {
      const auto t0 = std::chrono::steady_clock::now();
      work();
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    };
  };
  const Timing sleeping = timer.time(
      "unit/sleep", 3, 1, timed([] { std::this_thread::sleep_for(std::chrono::milliseconds(20)); }));
  EXPECT_GE(sleeping.median, 0.019);
  ASSERT_EQ(sleeping.cpu_samples.size(), 3u);
  EXPECT_LT(sleeping.cpu_median, 0.25 * sleeping.median);
  const Timing spinning =
      timer.time("unit/spin", 3, 1, timed([] {
                   const auto t0 = std::chrono::steady_clock::now();
                   while (std::chrono::steady_clock::now() - t0 < std::chrono::milliseconds(20)) {
                   }
                 }));
  EXPECT_GT(spinning.cpu_median, 0.0);
  EXPECT_LE(spinning.cpu_median, 1.5 * spinning.median);
}

}  // namespace
}  // namespace ab
