// Sharding and merging: the partition of a suite's scenes is deterministic, covers every scene once and keeps
// heavy scenes apart; `run --shard` then `merge` give the cases, verification results and hit checks of an
// unsharded run; merge refuses (exit 2, one line, nothing written) shards that do not make one run.
#include "harness/shard.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <numeric>
#include <thread>

#include "accel/core/error.h"
#include "tests/shard_test_helpers.h"

namespace ab {
namespace {

using nlohmann::json;
using test::read_json_file;
using test::read_text;
using test::shell;
namespace fs = std::filesystem;

Suite suite_of(const std::string& text) {
  return parse_suite(json::parse(text), "test.json", "");
}

/// Sizes 1000 .. 64000 and two heavy 500000-triangle scenes, each scene alone in the suite's order.
const char* kMixedSuite = R"({"scenes": [
    {"generator": "soup", "triangles": [1000, 2000, 4000, 8000]},
    {"generator": "sphereflake", "triangles": 500000},
    {"generator": "terrain", "triangles": [16000, 32000, 64000]},
    {"generator": "stadium", "triangles": 500000}],
  "accelerators": ["bvh-sah", "grid"], "rays": [{"kind": "primary", "count": 4096}]})";

TEST(Shard, ParsesKOfN) {
  EXPECT_EQ(parse_shard("1/3").index, 1);
  EXPECT_EQ(parse_shard("3/3").count, 3);
  for (const char* bad : {"0/3", "4/3", "a/b", "3", "1/0", "1/3x", "/3", "1/", "-1/3", "1/3/4", ""}) {
    try {
      parse_shard(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("--shard: ", 0), 0u) << e.what();
    }
  }
}

TEST(Shard, EveryScenePlacedOnceInSuiteOrder) {
  const Suite suite = suite_of(kMixedSuite);
  for (int n = 1; n <= 12; ++n) {  // more shards than scenes leaves some empty
    const auto shards = partition_scenes(suite, n);
    ASSERT_EQ(shards.size(), size_t(n));
    std::vector<size_t> all;
    for (const auto& s : shards) {
      EXPECT_TRUE(std::is_sorted(s.begin(), s.end()));
      all.insert(all.end(), s.begin(), s.end());
    }
    std::sort(all.begin(), all.end());
    std::vector<size_t> expected(suite.scenes.size());
    std::iota(expected.begin(), expected.end(), size_t(0));
    EXPECT_EQ(all, expected) << n << " shards";
  }
}

TEST(Shard, DeterministicAndHeavyScenesApart) {
  const Suite suite = suite_of(kMixedSuite);
  EXPECT_EQ(partition_scenes(suite, 3), partition_scenes(suite_of(kMixedSuite), 3));
  for (int n = 2; n <= 4; ++n) {
    const auto shards = partition_scenes(suite, n);
    for (const auto& s : shards) {
      int heavy = 0;
      for (size_t i : s) heavy += suite.scenes[i].triangles == 500000;
      EXPECT_LE(heavy, 1) << n << " shards";
    }
  }
  // Longest processing time first is within 4/3 of the best makespan; here simply: no shard carries more
  // than the mean load plus the heaviest scene.
  const auto shards = partition_scenes(suite, 3);
  double total = 0, heaviest = 0, worst = 0;
  for (const auto& s : suite.scenes)
    total += scene_cost(suite, s), heaviest = std::max(heaviest, scene_cost(suite, s));
  for (const auto& s : shards) {
    double load = 0;
    for (size_t i : s) load += scene_cost(suite, suite.scenes[i]);
    worst = std::max(worst, load);
  }
  EXPECT_LE(worst, total / 3 + heaviest);
}

TEST(Shard, DefaultSuiteSplitsSizesEvenly) {
  const Suite suite = default_suite();
  for (int n : {2, 4}) {
    for (const auto& s : partition_scenes(suite, n)) {
      int large = 0;
      for (size_t i : s) large += suite.scenes[i].triangles >= 100000;
      EXPECT_EQ(large, 4 / n) << n << " shards";
    }
  }
}

TEST(Shard, ShardJsonRecordsThePartitionAndHashTellsSuitesApart) {
  const Suite suite = suite_of(kMixedSuite);
  const json j = shard_json(suite, {2, 3});
  EXPECT_EQ(j["index"], 2);
  EXPECT_EQ(j["count"], 3);
  EXPECT_EQ(j["partition"].size(), 3u);
  EXPECT_EQ(j["scenes"], j["partition"][1]["scenes"]);
  EXPECT_EQ(j["suite_scenes"].size(), suite.scenes.size());
  EXPECT_EQ(shard_suite(suite, {2, 3}).scenes.size(), j["scenes"].size());
  EXPECT_EQ(suite_hash(suite.json), suite_hash(suite_of(kMixedSuite).json));
  json other = suite.json;
  other["seed"] = 2;
  EXPECT_NE(suite_hash(suite.json), suite_hash(other));
  EXPECT_EQ(suite_hash(suite.json).rfind("fnv1a64:", 0), 0u);
}

/// A folder with a tiny suite (and a variant of it) whose shards the merge tests run (a second or two).
class Merge : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (test::accelbench_bin().empty()) return;
    dir_ = (fs::path(::testing::TempDir()) / ("accelbench_merge_" + std::to_string(::getpid()))).string();
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    const char* suite = R"({"name": "tiny", "seed": 3, "repetitions": 1, "warmup": 0, "min_time": 0,
      "threads": [1], "scenes": [{"generator": "soup", "triangles": [300, 600, 900, 1200]}],
      "accelerators": ["bvh-sah", "grid", "embree"],
      "rays": [{"kind": "primary", "count": 256}, {"kind": "shadow", "count": 256}],
      "verify": {"brute_rays": 0}})";
    std::ofstream(dir_ + "/tiny.json") << suite;
    json other = json::parse(suite);
    other["seed"] = 4;
    std::ofstream(dir_ + "/other.json") << other.dump();
  }
  /// The runs the merge tests read: the tiny suite unsharded and as 3 shards, and shard 2/3 of another suite.
  static void run_shards() {
    run_ok("tiny.json", "", "single");
    for (int k = 1; k <= 3; ++k) run_ok("tiny.json", std::to_string(k) + "/3", "shard-" + std::to_string(k));
    run_ok("other.json", "2/3", "other-2");
  }
  static void TearDownTestSuite() {
    if (!dir_.empty()) fs::remove_all(dir_);
  }
  static void run_ok(const std::string& suite, const std::string& shard, const std::string& out) {
    const std::string bin = test::accelbench_bin();
    const std::string cmd = "'" + bin + "' run '" + dir_ + "/" + suite + "' " +
                            (shard.empty() ? "" : "--shard " + shard) + " -o '" + dir_ + "/" + out +
                            "' --no-plot > '" + dir_ + "/" + out + ".log' 2>&1";
    ASSERT_EQ(shell(cmd), 0) << read_text(dir_ + "/" + out + ".log");
  }
  void SetUp() override {
    if (test::accelbench_bin().empty()) GTEST_SKIP() << "ACCELBENCH_BIN is not set (run through ctest)";
  }
  /// Runs merge over the given folders (relative to the test's folder) into `out`; returns the exit code, the
  /// stderr text in `err`.
  static int merge(const std::vector<std::string>& dirs, const std::string& out, std::string& err) {
    const std::string bin = test::accelbench_bin();
    std::string cmd = "'" + bin + "' merge";
    for (const auto& d : dirs) cmd += " '" + dir_ + "/" + d + "'";
    cmd += " -o '" + dir_ + "/" + out + "' --no-plot > '" + dir_ + "/merge.out' 2> '" + dir_ + "/merge.err'";
    const int code = shell(cmd);
    err = read_text(dir_ + "/merge.err");
    return code;
  }
  /// A copy of shard folder `from` as `to`, its report changed by `edit`.
  static void tampered_copy(const std::string& from, const std::string& to,
                            const std::function<void(json&)>& edit) {
    fs::remove_all(dir_ + "/" + to);
    fs::copy(dir_ + "/" + from, dir_ + "/" + to, fs::copy_options::recursive);
    json r = read_json_file(dir_ + "/" + to + "/report.json");
    edit(r);
    std::ofstream(dir_ + "/" + to + "/report.json") << r.dump(1);
  }
  /// Merge refuses: exit 2, one line on stderr containing `what`, no output folder.
  static void expect_refused(const std::vector<std::string>& dirs, const std::string& what) {
    std::string err;
    fs::remove_all(dir_ + "/refused");
    EXPECT_EQ(merge(dirs, "refused", err), 2) << err;
    EXPECT_NE(err.find(what), std::string::npos) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_FALSE(fs::exists(dir_ + "/refused")) << "merge wrote output for a refused input";
  }
  static std::string dir_;
};

std::string Merge::dir_;

TEST_F(Merge, ShardsInAnyOrderGiveTheUnshardedRun) {
  ASSERT_NO_FATAL_FAILURE(run_shards());
  std::string err;
  ASSERT_EQ(merge({"shard-3", "shard-1", "shard-2"}, "merged", err), 0) << err;
  const json merged = read_json_file(dir_ + "/merged/report.json");
  const json single = read_json_file(dir_ + "/single/report.json");
  const auto diffs = test::report_differences(merged, single);
  EXPECT_TRUE(diffs.empty()) << diffs.size() << " differences, first: " << diffs.front();
  EXPECT_EQ(merged["machines"].size(), 3u);
  EXPECT_FALSE(merged.contains("shard"));
  EXPECT_EQ(merged["merged"]["shards"], 3);
  for (const auto& r : merged["results"]) {
    EXPECT_TRUE(r["ratio_to_embree"].is_number()) << r["config_label"];
  }
  const auto lines = [](const std::string& t) { return std::count(t.begin(), t.end(), '\n'); };
  EXPECT_EQ(lines(read_text(dir_ + "/merged/report.csv")), lines(read_text(dir_ + "/single/report.csv")));
  EXPECT_EQ(read_json_file(dir_ + "/merged/gbench.json")["benchmarks"].size(),
            read_json_file(dir_ + "/single/gbench.json")["benchmarks"].size());
}

TEST_F(Merge, RefusesShardsThatDoNotMakeOneRun) {
  ASSERT_NO_FATAL_FAILURE(run_shards());
  expect_refused({"shard-1", "shard-2"}, "shard 3/3 is missing");
  expect_refused({"shard-1", "shard-2", "shard-2", "shard-3"}, "shard 2/3 given twice");
  expect_refused({"shard-1", "other-2", "shard-3"}, "suite (hash)");
  expect_refused({"shard-1", "single", "shard-3"}, "not a shard");
  expect_refused({"shard-1", "missing-folder"}, "missing-folder");
  tampered_copy("shard-2", "commit-2", [](json& r) { r["source"]["git_commit"] = "0123abcd"; });
  expect_refused({"shard-1", "commit-2", "shard-3"}, "commit 0123abcd differs");
  tampered_copy("shard-2", "stopped-2", [](json& r) { r["interrupted"] = true; });
  expect_refused({"shard-1", "stopped-2", "shard-3"}, "shard 2/3 was interrupted");
  tampered_copy("shard-2", "killed-2", [](json& r) { r["complete"] = false; });  // saved mid-run, then killed
  expect_refused({"shard-1", "killed-2", "shard-3"}, "shard 2/3 was interrupted");
  tampered_copy("shard-2", "short-2", [](json& r) { r["scenes"].erase(r["scenes"].begin()); });
  expect_refused({"shard-1", "short-2", "shard-3"}, "has no entry for its scene");
  tampered_copy("shard-2", "broken-2", [](json& r) { r["shard"]["index"] = "two"; });
  expect_refused({"shard-1", "broken-2", "shard-3"}, "malformed shard report");
  fs::create_directories(dir_ + "/garbage");
  std::ofstream(dir_ + "/garbage/report.json") << "{not json";
  expect_refused({"shard-1", "garbage", "shard-3"}, "invalid JSON");
  std::string err;
  EXPECT_EQ(merge({"shard-1", "shard-2", "shard-3"}, "shard-1", err), 2);
  EXPECT_NE(err.find("is one of the shard folders"), std::string::npos) << err;
}

TEST_F(Merge, ShardStoppedBySigtermIsRefused) {
  // A scheduler's time limit or scancel sends SIGTERM: the shard stops after its current case, keeps what it
  // finished, exits 130 and says so in its report, which merge then refuses.
  const std::string suite = dir_ + "/slow.json";
  std::ofstream(suite) << R"({"repetitions": 3, "threads": [1], "min_time": 0.05,
    "scenes": [{"generator": "soup", "triangles": [300, 301, 302, 303, 304, 305, 306, 307]}],
    "accelerators": ["bvh-sah", "embree"], "rays": [{"kind": "incoherent", "count": 4096}]})";
  const std::string out = dir_ + "/slow-1";
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const std::string b = test::accelbench_bin();
    if (!::freopen("/dev/null", "w", stdout)) ::_exit(127);
    ::execl(b.c_str(), b.c_str(), "run", suite.c_str(), "--shard", "1/2", "-o", out.c_str(), "--no-plot",
            (char*)nullptr);
    ::_exit(127);
  }
  const auto start = std::chrono::steady_clock::now();
  while (!fs::exists(out + "/report.json") &&
         std::chrono::steady_clock::now() - start < std::chrono::seconds(60))
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ::kill(pid, SIGTERM);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  const json report = read_json_file(out + "/report.json");
  EXPECT_TRUE(report["interrupted"].get<bool>());
  EXPECT_FALSE(report["complete"].get<bool>());
  EXPECT_EQ(report["shard"]["index"], 1);
  expect_refused({"slow-1"}, "shard 1/2 was interrupted");
}

TEST_F(Merge, BadShardValueExitsTwo) {
  const std::string bin = test::accelbench_bin();
  for (const char* bad : {"4/3", "0/3", "x"}) {
    const std::string err_file = dir_ + "/bad-shard.err";
    EXPECT_EQ(shell("'" + bin + "' run '" + dir_ + "/tiny.json' --shard '" + bad + "' -o '" + dir_ +
                    "/bad-shard' 2> '" + err_file + "'"),
              2);
    const std::string err = read_text(err_file);
    EXPECT_EQ(err.rfind("accelbench: --shard: ", 0), 0u) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_FALSE(fs::exists(dir_ + "/bad-shard"));
  }
}

}  // namespace
}  // namespace ab
