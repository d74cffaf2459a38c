// The CLI's contract, run through the real binary: exit codes, one clear line for bad input, no
// half-written output, byte-identical hit files across thread counts, and trace --stats.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "harness/hitfile.h"
#include "tests/cli_test_helpers.h"

namespace ab {
namespace {

namespace fs = std::filesystem;

struct Result {
  int code = -1;
  std::string out;
  std::string err;
};

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    bin_ = test::accelbench_exe();
    if (!fs::exists(bin_)) GTEST_SKIP() << "accelbench binary not found at " << bin_;
    dir_ = fs::temp_directory_path() / ("accelbench_cli_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  Result run(const std::string& args) {
    const fs::path out = dir_ / "stdout.txt", err = dir_ / "stderr.txt";
    const std::string cmd = bin_ + " " + args + " >" + out.string() + " 2>" + err.string();
    const int code = test::shell(cmd);
    return {code, test::read_text(out), test::read_text(err)};
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  void expect_bad_input(const Result& r, const std::string& names) {
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find(names), std::string::npos) << "stderr does not name '" << names << "': " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "expected one line: " << r.err;
  }

  std::string bin_;
  fs::path dir_;
};

TEST_F(Cli, HelpAndListWork) {
  EXPECT_EQ(run("--help").code, 0);
  EXPECT_EQ(run("trace --help").code, 0);
  const Result r = run("list --json");
  ASSERT_EQ(r.code, 0);
  const auto j = nlohmann::json::parse(r.out);
  std::vector<std::string> names;
  for (const auto& a : j["accelerators"]) {
    names.push_back(a["name"]);
    if (a["name"] == "bvh-sah") {
      EXPECT_EQ(a["params"]["width"], 8);  // parameters with their defaults
    }
    if (a["name"] == "grid") {
      EXPECT_TRUE(a["params"].contains("lambda"));
    }
  }
  EXPECT_NE(std::find(names.begin(), names.end(), "brute"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "embree"), names.end());
  EXPECT_GE(j["generators"].size(), 7u);
  EXPECT_GE(j["ray_kinds"].size(), 5u);
}

TEST_F(Cli, GenerateRaysTraceRoundTripIsDeterministic) {
  ASSERT_EQ(run("generate sphereflake --triangles 2000 --seed 3 -o " + path("a.obj")).code, 0);
  ASSERT_EQ(run("generate sphereflake --triangles 2000 --seed 3 -o " + path("b.obj")).code, 0);
  EXPECT_EQ(test::read_text(path("a.obj")), test::read_text(path("b.obj")));
  ASSERT_EQ(run("rays --mesh " + path("a.obj") + " --kind primary --count 3000 -o " + path("r.rays")).code,
            0);
  EXPECT_EQ(read_rays(path("r.rays")).size(), 3000u);
  const std::string base = "trace --mesh " + path("a.obj") + " --rays " + path("r.rays");
  ASSERT_EQ(run(base + " --accel brute --threads 1 -o " + path("b1.hits")).code, 0);
  ASSERT_EQ(
      run(base + " --accel brute --threads 2 -o " + path("b2.hits") + " --stats " + path("s.json")).code, 0);
  EXPECT_EQ(test::read_text(path("b1.hits")), test::read_text(path("b2.hits")));
  const auto stats = nlohmann::json::parse(test::read_text(path("s.json")));
  for (const char* key :
       {"accelerator", "params", "triangles", "build_seconds", "trace_seconds", "rays_per_second", "per_ray"})
    EXPECT_TRUE(stats.contains(key)) << key;
  EXPECT_EQ(stats["per_ray"]["nodes_per_ray"], 0.0);  // brute visits no nodes
  EXPECT_GT(stats["per_ray"]["prims_per_ray"].get<double>(), 1000.0);
}

TEST_F(Cli, BadInputGivesExitTwoOneLineAndNoOutput) {
  ASSERT_EQ(run("generate soup --triangles 100 -o " + path("m.obj")).code, 0);
  ASSERT_EQ(run("rays --mesh " + path("m.obj") + " --kind incoherent --count 10 -o " + path("r.rays")).code,
            0);
  const std::string good_rays = test::read_text(path("r.rays"));
  auto write = [&](const std::string& name, const std::string& bytes) {
    std::ofstream(path(name), std::ios::binary) << bytes;
  };
  const std::string mesh = " --mesh " + path("m.obj");
  const std::string out = path("out.hits");

  expect_bad_input(
      run("trace --mesh " + path("missing.obj") + " --accel brute --rays " + path("r.rays") + " -o " + out),
      "missing.obj");
  write("magic.rays", "XXRAYS01" + good_rays.substr(8));
  expect_bad_input(run("trace" + mesh + " --accel brute --rays " + path("magic.rays") + " -o " + out),
                   "magic.rays");
  write("short.rays", good_rays.substr(0, good_rays.size() - 5));
  expect_bad_input(run("trace" + mesh + " --accel brute --rays " + path("short.rays") + " -o " + out),
                   "short.rays");
  std::string nan_rays = good_rays;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(nan_rays.data() + 16 + 4, &nan, 4);
  write("nan.rays", nan_rays);
  expect_bad_input(run("trace" + mesh + " --accel brute --rays " + path("nan.rays") + " -o " + out),
                   "nan.rays");
  write("nan.obj", "v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n");
  expect_bad_input(
      run("trace --mesh " + path("nan.obj") + " --accel brute --rays " + path("r.rays") + " -o " + out),
      "nan.obj");
  expect_bad_input(run("trace" + mesh + " --accel no-such-accel --rays " + path("r.rays") + " -o " + out),
                   "no-such-accel");
  expect_bad_input(
      run("trace" + mesh + " --accel brute --param leaf=3 --rays " + path("r.rays") + " -o " + out), "leaf");
  expect_bad_input(run("generate no-such-gen --triangles 10 -o " + path("x.obj")), "no-such-gen");
  expect_bad_input(run("generate soup --triangles 10 -o " + path("x.xyz")), "x.xyz");
  expect_bad_input(run("rays" + mesh + " --kind no-such-kind --count 10 -o " + path("x.rays")),
                   "no-such-kind");
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(path("x.obj")));
  EXPECT_FALSE(fs::exists(path("x.xyz")));
  EXPECT_FALSE(fs::exists(path("x.rays")));
  for (const auto& entry : fs::directory_iterator(dir_))
    EXPECT_EQ(entry.path().string().find(".tmp."), std::string::npos) << "left behind: " << entry.path();
}

// Every input fuzzing found (fuzz/regressions/) through the real binary: a valid file loads (exit 0), a
// bad one gets exit 2 and one line naming it; never a crash, an abort or a hang, and no output left.
TEST_F(Cli, FuzzedInputsExitZeroOrTwoWithOneLine) {
  ASSERT_EQ(run("generate soup --triangles 50 -o " + path("m.obj")).code, 0);
  ASSERT_EQ(run("rays --mesh " + path("m.obj") + " --kind incoherent --count 8 -o " + path("r.rays")).code,
            0);
  const fs::path regressions = fs::path(ACCELBENCH_SOURCE_DIR) / "fuzz" / "regressions";
  size_t files = 0;
  for (const char* format : {"obj", "ply", "off", "stl", "suite"}) {
    if (!fs::is_directory(regressions / format)) continue;
    for (const auto& entry : fs::directory_iterator(regressions / format)) {
      const std::string file = entry.path().string();
      SCOPED_TRACE(file);
      ++files;
      const std::string out = path("out");
      const Result r =
          std::string(format) == "suite"
              ? run("run " + file + " -o " + out)
              : run("trace --mesh " + file + " --accel brute --rays " + path("r.rays") + " -o " + out);
      if (std::string(format) == "suite" || r.code != 0)
        expect_bad_input(r, entry.path().filename().string());
      if (r.code != 0) {
        EXPECT_FALSE(fs::exists(out));
      }
      fs::remove_all(out);
    }
  }
  EXPECT_GE(files, 20u);
}

TEST_F(Cli, VerifyAgreesWithEmbree) {
  ASSERT_EQ(run("generate terrain --triangles 5000 -o " + path("t.obj")).code, 0);
  const Result r = run("verify --mesh " + path("t.obj") + " --kind primary --count 4000");
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("brute"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace ab
