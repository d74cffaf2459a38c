// scripts/slurm-run against a real Slurm: a private single-node cluster (munged, slurmctld, slurmd on
// localhost; scripts/slurm-local-up) started by the test and stopped when it ends, suites/quick.json as a
// 3-task job array plus the dependent merge job, and the merged report compared case for case with an
// unsharded run of the same suite (timings aside). Skips, saying why, only where Slurm cannot run at all
// (not root: slurmd must be); a missing package or a cluster that does not come up is a failure.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <thread>

#include "tests/shard_test_helpers.h"

namespace ab {
namespace {

using nlohmann::json;
using test::read_json_file;
using test::read_text;
using test::shell;
namespace fs = std::filesystem;

const std::string kSource = ACCELBENCH_SOURCE_DIR;

/// A local cluster for the lifetime of the object: slurm-local-up in the constructor, slurm-local-down in the
/// destructor (also when an assertion ends the test early). SLURM_CONF points at it meanwhile.
class LocalCluster {
 public:
  explicit LocalCluster(std::string dir) : dir_(std::move(dir)) {
    fs::create_directories(dir_);
    // Its own stdin/stdout: the daemons must not hold the test's pipes open.
    const int code = shell("'" + kSource + "/scripts/slurm-local-up' '" + dir_ + "' < /dev/null > '" + dir_ +
                           "/up.out' 2> '" + dir_ + "/up.err'");
    up_ = code == 0;
    if (up_) {
      std::string conf = read_text(dir_ + "/up.out");
      conf.erase(conf.find_last_not_of("\n") + 1);
      ::setenv("SLURM_CONF", conf.c_str(), 1);
    }
  }
  ~LocalCluster() {
    shell("'" + kSource + "/scripts/slurm-local-down' '" + dir_ + "' < /dev/null > /dev/null 2>&1");
    ::unsetenv("SLURM_CONF");
  }
  LocalCluster(const LocalCluster&) = delete;
  LocalCluster& operator=(const LocalCluster&) = delete;
  /// Whether slurm-local-up succeeded.
  bool up() const { return up_; }
  /// What slurm-local-up said (with the daemons' log tails when it failed).
  std::string log() const { return read_text(dir_ + "/up.err"); }

 private:
  std::string dir_;
  bool up_ = false;
};

/// First line of a command's output.
std::string output_of(const std::string& cmd) {
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (!pipe) return "";
  char buf[4096] = {};
  std::string out = std::fgets(buf, sizeof buf, pipe) ? buf : "";
  ::pclose(pipe);
  out.erase(out.find_last_not_of("\n") + 1);
  return out;
}

/// Polls squeue (every half second) until none of `jobs` is queued or running; false on timeout.
bool wait_for_jobs(const std::string& jobs, int timeout_seconds) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(timeout_seconds);
  while (std::chrono::steady_clock::now() < deadline) {
    if (output_of("squeue -h -j " + jobs + " -o %i 2>/dev/null").empty()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  return false;
}

/// "JobState=... ExitCode=..." of every record of a job (one per array task).
std::string job_states(const std::string& job) {
  return output_of("scontrol -o show job " + job +
                   " | grep -o 'JobState=[A-Z_]* .*ExitCode=[0-9:]*' |"
                   " sed 's/JobState=\\([A-Z_]*\\).*ExitCode=\\([0-9:]*\\)/\\1 \\2/' | paste -sd' '");
}

TEST(Slurm, QuickSuiteAsThreeTaskArrayMergesToTheUnshardedRun) {
  const std::string bin = test::accelbench_bin();
  if (bin.empty()) GTEST_SKIP() << "ACCELBENCH_BIN is not set (run through ctest)";
  if (::geteuid() != 0)
    GTEST_SKIP()
        << "Slurm cannot run here: slurmd must run as root to launch jobs, and this test runs as uid "
        << ::geteuid();
  for (const char* c : {"munged", "mungekey", "slurmctld", "slurmd", "sbatch", "squeue", "scontrol"})
    ASSERT_EQ(shell(std::string("command -v ") + c + " > /dev/null"), 0)
        << c << " is not installed: scripts/setup installs slurmctld slurmd slurm-client munge";
  char tmpl[] = "/tmp/accelbench-slurm-XXXXXX";
  ASSERT_NE(::mkdtemp(tmpl), nullptr);
  const std::string dir = tmpl;
  fs::permissions(dir, fs::perms::others_exec | fs::perms::group_exec, fs::perm_options::add);  // for munged
  {
    LocalCluster cluster(dir + "/cluster");
    ASSERT_TRUE(cluster.up()) << "scripts/slurm-local-up failed:\n" << cluster.log();
    const auto t0 = std::chrono::steady_clock::now();
    // Options a user passes for their cluster go to both jobs: here the local partition and node feature.
    const std::string submit = "ACCELBENCH_OUT='" + dir + "/out' '" + kSource + "/scripts/slurm-run' '" +
                               kSource +
                               "/suites/quick.json' 3 --partition=debug "
                               "--constraint=local --time=20 > '" +
                               dir + "/submit.out' 2>&1";
    ASSERT_EQ(shell(submit), 0) << read_text(dir + "/submit.out");
    const std::string ids = read_text(dir + "/out/slurm/jobs");
    const std::string array = ids.substr(0, ids.find(' '));
    const std::string merge = ids.substr(ids.find(' ') + 1, ids.find('\n') - ids.find(' ') - 1);
    // The unsharded run of the same suite, meanwhile.
    ASSERT_EQ(shell("'" + bin + "' run '" + kSource + "/suites/quick.json' -o '" + dir +
                    "/single' --no-plot > '" + dir + "/single.out' 2>&1"),
              0)
        << read_text(dir + "/single.out");
    ASSERT_TRUE(wait_for_jobs(array + "," + merge, 600)) << "jobs still queued after 10 minutes";
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::cout << "slurm: array and merge done " << seconds << " s after submission\n";
    EXPECT_EQ(job_states(array), "COMPLETED 0:0 COMPLETED 0:0 COMPLETED 0:0")
        << read_text(dir + "/out/slurm/shard-1.out");
    EXPECT_EQ(job_states(merge), "COMPLETED 0:0") << read_text(dir + "/out/slurm/merge.out");
  }
  const json merged = read_json_file(dir + "/out/merged/report.json");
  const json single = read_json_file(dir + "/single/report.json");
  ASSERT_TRUE(merged.is_object()) << "no merged report";
  const auto diffs = test::report_differences(merged, single);
  EXPECT_TRUE(diffs.empty()) << diffs.size() << " differences, first: " << diffs.front();
  EXPECT_TRUE(merged["verified"].get<bool>());
  EXPECT_EQ(merged["machines"].size(), 3u);
  EXPECT_GT(merged["results"].size(), 0u);
  // The merged folder is read like any run's: the merge job drew its plots.
  if (shell("/usr/bin/python3 -c 'import matplotlib' > /dev/null 2>&1") == 0) {
    EXPECT_TRUE(fs::exists(dir + "/out/merged/rays_per_second_vs_embree.png"))
        << read_text(dir + "/out/slurm/merge.out");
  }
  for (int k = 1; k <= 3; ++k)
    EXPECT_EQ(read_json_file(dir + "/out/shard-" + std::to_string(k) + "/report.json")["shard"]["index"], k);
  if (!HasFailure()) fs::remove_all(dir);
}

}  // namespace
}  // namespace ab
