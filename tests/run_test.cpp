// `accelbench run` end to end: suites/quick.json through the accelbench binary (report.json and report.csv
// carry the same numbers, gbench.json is Google Benchmark's), a bad suite exits 2 before any work, a
// test-only broken accelerator makes the run fail loudly, and Ctrl-C keeps the finished cases.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "accel/core/registry.h"
#include "accel/reference/brute.h"
#include "harness/cli.h"
#include "tests/cli_test_helpers.h"

namespace ab {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

/// Brute force that corrupts every hit on an odd triangle by one ulp of u: a mismatch the run must catch.
template <class P>
class BrokenBrute final : public AcceleratorBase<BrokenBrute<P>> {
 public:
  using Prims = P;
  using Config = typename Brute<P>::Config;
  BrokenBrute(std::shared_ptr<const P> prims, const Config& config)
      : brute_(prims, config), prims_(std::move(prims)) {}
  AABB bounds() const override { return prims_->bounds(); }
  template <bool kCount>
  void intersect_ray(const Ray& ray, Hit& best, uint32_t inst, RayCounters& c) const {
    brute_.template intersect_ray<kCount>(ray, best, inst, c);
    if (best.found() && (best.prim & 1u)) best.u = std::nextafter(best.u, 1.0f);
  }
  template <bool kCount>
  bool occluded_ray(const Ray& ray, RayCounters& c) const {
    return brute_.template occluded_ray<kCount>(ray, c);
  }

 protected:
  void do_build() override {}
  void gather_stats(BuildStats& stats) const override { stats.primitives = prims_->size(); }

 private:
  Brute<P> brute_;
  std::shared_ptr<const P> prims_;
};

const Registrar kRegisterBroken{structure_info<BrokenBrute>("test-broken", "test only: corrupts hits", 1000)};

using test::read_text;
using test::shell;

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted && c == '"' && i + 1 < line.size() && line[i + 1] == '"')
      cell += '"', ++i;
    else if (c == '"')
      quoted = !quoted;
    else if (c == ',' && !quoted)
      cells.push_back(cell), cell.clear();
    else
      cell += c;
  }
  cells.push_back(cell);
  return cells;
}

/// A fresh output folder for one run and its companions (DIR.json, DIR.err, DIR.out), all removed when the
/// test ends, however it ends.
struct RunDir {
  explicit RunDir(const std::string& name)
      : path((fs::path(::testing::TempDir()) / ("accelbench_run_" + name + "_" + std::to_string(::getpid())))
                 .string()) {
    remove_files();
  }
  ~RunDir() { remove_files(); }
  void remove_files() const {
    fs::remove_all(path);
    for (const char* ext : {".json", ".err", ".out"}) fs::remove(path + ext);
  }
  const std::string path;
};

/// Every CSV cell equals the JSON value of the same row and column.
void expect_csv_matches_json(const json& report, const std::string& csv_text) {
  std::istringstream lines(csv_text);
  std::string line;
  std::getline(lines, line);
  const std::vector<std::string> header = split_csv_line(line);
  size_t row_index = 0;
  for (; std::getline(lines, line); ++row_index) {
    ASSERT_LT(row_index, report["results"].size());
    const json& row = report["results"][row_index];
    const std::vector<std::string> cells = split_csv_line(line);
    ASSERT_EQ(cells.size(), header.size()) << line;
    for (size_t c = 0; c < header.size(); ++c) {
      const json v = row.value(header[c], json());
      if (v.is_number_float()) {
        EXPECT_EQ(std::strtod(cells[c].c_str(), nullptr), v.get<double>()) << header[c];
      } else if (v.is_string()) {
        EXPECT_EQ(cells[c], v.get<std::string>()) << header[c];
      } else if (v.is_null()) {
        EXPECT_EQ(cells[c], "") << header[c];
      } else if (!v.is_object()) {
        EXPECT_EQ(cells[c], v.dump()) << header[c];
      }
    }
  }
  EXPECT_EQ(row_index, report["results"].size());
}

TEST(Run, QuickSuiteEndToEnd) {
  if (test::accelbench_bin().empty()) GTEST_SKIP() << "ACCELBENCH_BIN is not set (run through ctest)";
  const RunDir run_dir("quick");
  const std::string& dir = run_dir.path;
  const std::string suite = std::string(ACCELBENCH_SOURCE_DIR) + "/suites/quick.json";
  ASSERT_EQ(shell("'" + test::accelbench_bin() + "' run '" + suite + "' -o '" + dir + "' --no-plot > '" +
                  dir + ".out' 2>&1"),
            0)
      << read_text(dir + ".out");
  const json report = json::parse(read_text(dir + "/report.json"));
  EXPECT_EQ(report["schema_version"], 1);
  EXPECT_TRUE(report["verified"].get<bool>());
  EXPECT_FALSE(report["interrupted"].get<bool>());
  for (const char* key : {"machine", "compiler", "source", "libraries", "date", "seed", "suite"})
    EXPECT_TRUE(report.contains(key)) << key;
  EXPECT_FALSE(report["machine"]["cpu_model"].get<std::string>().empty());
  // Every registered structure was built, verified against brute force and timed.
  std::map<std::string, int> rows_per_accel;
  for (const auto& r : report["results"]) {
    ++rows_per_accel[r["accelerator"].get<std::string>()];
    EXPECT_GT(r["rays_per_second"].get<double>(), 0.0);
    EXPECT_TRUE(r["verified"].get<bool>());
    if (r["accelerator"] != "embree") {
      EXPECT_EQ(r["brute_mismatches"], 0);
      EXPECT_EQ(r["brute_rays_checked"], r["ray_count"]);
    }
    EXPECT_TRUE(r["ratio_to_embree"].is_number());
    EXPECT_TRUE(r["cpu_ratio_to_embree"].is_number());
    EXPECT_GT(r["rays_per_cpu_second"].get<double>(), 0.0);
    EXPECT_EQ(r["cpu_seconds_samples"].size(), r["seconds_samples"].size());
  }
  for (const auto& info : accelerators())
    if (info.name.rfind("test-", 0) != 0 && info.name != "cgal" && info.name != "bullet") {
      EXPECT_GT(rows_per_accel[info.name], 0) << info.name;  // "all": the outside peers are left out
    }
  expect_csv_matches_json(report, read_text(dir + "/report.csv"));
  const json gbench = json::parse(read_text(dir + "/gbench.json"));
  EXPECT_GT(gbench["benchmarks"].size(), report["results"].size());
  EXPECT_NE(read_text(dir + ".out").find("ratio@1"), std::string::npos);
}

TEST(Run, BadSuiteExitsTwoBeforeAnyWork) {
  if (test::accelbench_bin().empty()) GTEST_SKIP() << "ACCELBENCH_BIN is not set (run through ctest)";
  const RunDir run_dir("bad");
  const std::string& dir = run_dir.path;
  const std::string suite = dir + ".json";
  std::ofstream(suite) << R"({"scenes": [{"generator": "soup", "triangles": 100}],
    "accelerators": ["brute", "bvh-sah", "foo"], "rays": [{"kind": "primary", "count": 8}]})";
  ASSERT_EQ(
      shell("'" + test::accelbench_bin() + "' run '" + suite + "' -o '" + dir + "' 2> '" + dir + ".err'"), 2);
  const std::string err = read_text(dir + ".err");
  EXPECT_NE(err.find(suite + ": accelerators[2].name: unknown accelerator 'foo'"), std::string::npos) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_FALSE(fs::exists(dir)) << "work started before the suite was validated";
}

TEST(Run, BrokenAcceleratorFailsTheRunLoudly) {
  const RunDir run_dir("broken");
  const std::string& dir = run_dir.path;
  const std::string suite = dir + ".json";
  std::ofstream(suite) << R"({"repetitions": 1, "warmup": 0, "threads": [1],
    "scenes": [{"generator": "sphereflake", "triangles": 500}],
    "accelerators": ["test-broken", "brute"],
    "rays": [{"kind": "primary", "count": 512}, {"kind": "shadow", "count": 256}],
    "verify": {"reference": "brute", "brute_rays": 100}})";
  std::vector<std::string> args{"accelbench", "run", suite, "-o", dir, "--no-plot"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  testing::internal::CaptureStderr();
  const int code = run_cli(int(argv.size()), argv.data());
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, 1);
  EXPECT_NE(err.find("VERIFICATION FAILED: sphereflake-500 / test-broken / primary:"), std::string::npos)
      << err;
  const json report = json::parse(read_text(dir + "/report.json"));
  EXPECT_FALSE(report["verified"].get<bool>());
  EXPECT_FALSE(report["failures"].empty());
  for (const auto& r : report["results"]) {
    const bool broken = r["accelerator"] == "test-broken";
    if (!broken) {
      EXPECT_TRUE(r["verified"].get<bool>()) << r["rays"];
    }
    if (broken && r["rays"] == "primary") {
      EXPECT_FALSE(r["verified"].get<bool>());
      EXPECT_GT(r["brute_mismatches"].get<int>() + r["reference_mismatches"].get<int>(), 0);
    }
  }
}

TEST(Run, InterruptKeepsFinishedCases) {
  if (test::accelbench_bin().empty()) GTEST_SKIP() << "ACCELBENCH_BIN is not set (run through ctest)";
  const RunDir run_dir("interrupt");
  const std::string& dir = run_dir.path;
  const std::string suite = dir + ".json";
  std::ofstream(suite) << R"({"repetitions": 3, "threads": [1], "min_time": 0.05,
    "scenes": [{"generator": "soup", "triangles": [300, 301, 302, 303, 304, 305, 306, 307]}],
    "accelerators": ["bvh-sah", "embree"], "rays": [{"kind": "incoherent", "count": 4096}]})";
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const std::string b = test::accelbench_bin();
    ::freopen("/dev/null", "w", stdout);
    ::execl(b.c_str(), b.c_str(), "run", suite.c_str(), "-o", dir.c_str(), "--no-plot", (char*)nullptr);
    ::_exit(127);
  }
  // Wait for the first scene's report, then press Ctrl-C.
  const auto start = std::chrono::steady_clock::now();
  while (!fs::exists(dir + "/report.json") &&
         std::chrono::steady_clock::now() - start < std::chrono::seconds(60))
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ::kill(pid, SIGINT);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  const json report = json::parse(read_text(dir + "/report.json"));
  EXPECT_TRUE(report["interrupted"].get<bool>());
  EXPECT_FALSE(report["results"].empty());
  EXPECT_LT(report["scenes"].size(), 8u);
  EXPECT_TRUE(fs::exists(dir + "/report.csv"));
  EXPECT_TRUE(fs::exists(dir + "/gbench.json"));
}

}  // namespace
}  // namespace ab
