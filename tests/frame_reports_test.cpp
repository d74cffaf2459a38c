// Reports of animated suites beyond one run: Embree's refit of a scene agrees with brute frame after frame;
// an animated suite run as shards and merged reads case for case like the unsharded run (the frame is part of
// every case, the frame summary is recomputed over all shards); `compare` matches cases frame by frame.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "accel/core/registry.h"
#include "accel/core/trace.h"
#include "datasets/rays.h"
#include "harness/compare_runs.h"
#include "tests/shard_test_helpers.h"
#include "tracer/scene.h"
#include "tracer/scene_accel.h"
#include "tracer/update_strategy.h"

namespace ab {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

/// Two orbiting sphereflakes and a waving tetrahedron field over time 0..1.
const char* kAnimatedScene =
    "<scene>\n<camera><eye>0 3 12</eye><lookat>0 0 0</lookat></camera>\n"
    "<mesh name='flake' generator='sphereflake' triangles='400' seed='5'/>\n"
    "<mesh name='wave' generator='tetra' triangles='256'><deform type='wave' start='0' end='1'>"
    "<amplitude>0.08</amplitude></deform></mesh>\n"
    "<instance mesh='flake'><keyframe time='0'><translate>-2 0 0</translate><rotate axis='Y'>0</rotate>"
    "</keyframe><keyframe time='1'><translate>2 1 0</translate><rotate axis='Y'>200</rotate></keyframe>"
    "</instance>\n<instance mesh='wave'/>\n"
    "<instance mesh='flake'><translate>0 0 -2</translate></instance>\n</scene>\n";

/// Hits of `accel` on `rays` (one thread).
std::vector<Hit> hits_of(const Accelerator& accel, const std::vector<Ray>& rays) {
  std::vector<Hit> hits(rays.size());
  accel.intersect(rays, hits);
  return hits;
}

TEST(EmbreeSceneRefit, FollowsTheFramesAndAgreesWithBrute) {
  EXPECT_TRUE(FrameUpdater::supports("embree", {}, UpdateStrategy::kRefit));
  EXPECT_FALSE(FrameUpdater::supports("embree", {}, UpdateStrategy::kAdaptive));
  const Scene scene = parse_scene(kAnimatedScene, "anim.xml", ".");
  FrameUpdater updater("embree", {}, UpdateStrategy::kRefit);
  for (uint64_t f = 0; f < 4; ++f) {
    auto frame = std::make_shared<const Scene>(scene_at(scene, frame_time(f, 4)));
    const FrameUpdate u = updater.update(frame);
    EXPECT_EQ(u.rebuilt, f == 0);
    auto brute = make_scene_accelerator(frame, "brute", Params{});
    brute->build();
    const std::vector<Ray> rays = make_rays("primary", RayTarget{frame->world_bounds(), {}, {}}, 3000, f + 1);
    const std::vector<Hit> a = hits_of(*brute, rays), b = hits_of(updater.accelerator(), rays);
    size_t found = 0, agree = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      found += a[i].found();
      agree += a[i].found() == b[i].found() && a[i].prim == b[i].prim && a[i].inst == b[i].inst;
    }
    EXPECT_GT(found, rays.size() / 10) << "frame " << f;
    EXPECT_GE(agree, rays.size() * 99 / 100) << "frame " << f;
    const AABB have = updater.accelerator().bounds(), want = frame->world_bounds();
    EXPECT_TRUE(have.contains(want.lo) && have.contains(want.hi)) << "frame " << f;
  }
}

TEST(EmbreeSceneRefit, RefusesAFrameThatDoesNotMatch) {
  const Scene scene = parse_scene(kAnimatedScene, "anim.xml", ".");
  auto first = std::make_shared<const Scene>(scene_at(scene, 0.0f));
  auto accel = make_scene_accelerator(first, "embree", Params{});
  auto* frames = dynamic_cast<EmbreeSceneFrames*>(accel.get());
  ASSERT_NE(frames, nullptr);
  std::vector<std::shared_ptr<const Mesh>> meshes;
  std::vector<EmbreeInstanceInput> instances;
  embree_scene_inputs(*first, meshes, instances);
  accel->build();
  EXPECT_FALSE(frames->refit_frame(meshes, instances));  // not built for refitting
  frames->build_for_refit();
  accel->build();
  EXPECT_TRUE(frames->refit_frame(meshes, instances));
  instances.pop_back();
  EXPECT_FALSE(frames->refit_frame(meshes, instances));
  embree_scene_inputs(*first, meshes, instances);
  std::swap(instances[0].mesh, instances[1].mesh);
  EXPECT_FALSE(frames->refit_frame(meshes, instances));
}

TEST(RepeatUpdate, LeavesTheStructureAndTheStrategyAsTheUpdateDid) {
  const Scene scene = parse_scene(kAnimatedScene, "anim.xml", ".");
  for (const char* name : {"bvh-sah", "embree"})
    for (UpdateStrategy s : all_update_strategies()) {
      if (!FrameUpdater::supports(name, {}, s)) continue;
      FrameUpdater updater(name, {}, s, 1.05);
      for (uint64_t f = 0; f < 4; ++f) {
        auto frame = std::make_shared<const Scene>(scene_at(scene, frame_time(f, 4)));
        const FrameUpdate u = updater.update(frame);
        const int rebuilds = updater.rebuilds();
        const std::vector<Ray> rays = make_rays("primary", RayTarget{frame->world_bounds(), {}, {}}, 1000, f);
        const std::vector<Hit> before = hits_of(updater.accelerator(), rays);
        for (int r = 0; r < 2; ++r) EXPECT_GE(updater.repeat_update(), 0.0);
        const std::string what = std::string(name) + ":" + strategy_name(s) + " frame " + std::to_string(f);
        EXPECT_EQ(updater.rebuilds(), rebuilds) << what;
        EXPECT_EQ(update_sah_cost(updater.accelerator()), u.sah_cost) << what;
        const std::vector<Hit> after = hits_of(updater.accelerator(), rays);
        EXPECT_EQ(std::memcmp(before.data(), after.data(), before.size() * sizeof(Hit)), 0) << what;
      }
    }
}

/// Runs the animated suite unsharded and as two shards, merges them: the tests below read the folders.
class AnimatedShards : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (test::accelbench_bin().empty()) return;
    dir_ = (fs::temp_directory_path() / ("ab_frame_reports_" + std::to_string(getpid()))).string();
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    std::ofstream(dir_ + "/a.xml") << kAnimatedScene;
    std::ofstream(dir_ + "/b.xml") << kAnimatedScene;
    std::ofstream(dir_ + "/anim.json") << R"({"name": "anim", "repetitions": 3, "warmup": 0,
      "min_time": 0, "threads": [1], "seed": 3,
      "scenes": [{"scene": "a.xml", "frames": 3, "strategies": ["rebuild", "refit"]},
                 {"scene": "b.xml", "frames": 3, "strategies": ["rebuild", "refit", "top-level"]}],
      "accelerators": ["bvh-sah", "embree"], "rays": [{"kind": "primary", "count": 256}],
      "verify": {"brute_rays": 64}})";
    ok_ = run("", "single") && run("1/2", "s1") && run("2/2", "s2") &&
          test::shell(cmd("merge '" + dir_ + "/s2' '" + dir_ + "/s1' -o '" + dir_ + "/merged' --no-plot",
                          "merge")) == 0;
  }
  static void TearDownTestSuite() {
    if (!dir_.empty()) fs::remove_all(dir_);
  }
  void SetUp() override {
    if (test::accelbench_bin().empty()) GTEST_SKIP() << "ACCELBENCH_BIN is not set (run through ctest)";
    ASSERT_TRUE(ok_) << test::read_text(dir_ + "/log.txt");
  }
  static std::string cmd(const std::string& args, const std::string& what) {
    std::ostringstream c;  // (a stream: GCC 12 warns falsely on a chain of string additions here)
    c << "'" << test::accelbench_bin() << "' " << args << " >> '" << dir_ << "/log.txt' 2>&1 || { echo '"
      << what << " failed' >> '" << dir_ << "/log.txt'; exit 1; }";
    return c.str();
  }
  static bool run(const std::string& shard, const std::string& out) {
    const std::string args = "run '" + dir_ + "/anim.json' " + (shard.empty() ? "" : "--shard " + shard) +
                             " -o '" + dir_ + "/" + out + "' --no-plot";
    return test::shell(cmd(args, out)) == 0;
  }
  static json report(const std::string& name) {
    return test::read_json_file(dir_ + "/" + name + "/report.json");
  }
  static std::string dir_;
  static bool ok_;
};

std::string AnimatedShards::dir_;
bool AnimatedShards::ok_ = false;

/// The frame summary without its timings (the frame at which refit stops paying is one of them).
json summary_identity(json summary) {
  summary = test::without_timings(summary);
  for (json& s : summary) s.erase("refit_stops_paying_frame");
  return summary;
}

TEST_F(AnimatedShards, MergedRunReadsLikeTheUnshardedOne) {
  const json merged = report("merged"), single = report("single");
  const auto diffs = test::report_differences(merged, single);
  EXPECT_TRUE(diffs.empty()) << diffs.size() << " differences, first: " << diffs.front();
  EXPECT_TRUE(merged["verified"].get<bool>()) << merged["failures"].dump();
  std::set<std::string> frames_seen, labels;
  for (const json& r : merged["results"]) {
    ASSERT_TRUE(r.contains("frame"));
    frames_seen.insert(r["scene"].get<std::string>() + "/" + r["frame"].dump());
    labels.insert(r["config_label"].get<std::string>());
  }
  EXPECT_EQ(frames_seen.size(), 6u);  // two scenes, three frames each
  for (const char* l :
       {"bvh-sah:rebuild", "bvh-sah:refit", "bvh-sah:top-level", "embree:rebuild", "embree:refit"})
    EXPECT_TRUE(labels.count(l)) << l;
  // The summary covers both shards' scenes (shard 1's report alone holds only its own).
  ASSERT_TRUE(merged.contains("frame_summary"));
  EXPECT_EQ(summary_identity(merged["frame_summary"]), summary_identity(single["frame_summary"]));
  EXPECT_GT(merged["frame_summary"].size(), report("s1")["frame_summary"].size());
}

TEST_F(AnimatedShards, CompareMatchesEveryCaseFrameByFrame) {
  const RunComparison c = compare_runs(report("single"), report("merged"), 0.05, 0.05);
  EXPECT_TRUE(c.only_base.empty()) << c.only_base.front();
  EXPECT_TRUE(c.only_new.empty()) << c.only_new.front();
  size_t queries = 0;
  std::set<std::string> scenes;
  for (const CaseComparison& k : c.cases) {
    scenes.insert(k.scene);
    EXPECT_NE(k.scene.find(" frame "), std::string::npos) << k.scene;
    if (k.query != "build") ++queries;
  }
  EXPECT_EQ(scenes.size(), 6u);
  EXPECT_EQ(queries, report("single")["results"].size());
}

}  // namespace
}  // namespace ab
