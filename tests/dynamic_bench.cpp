// The refit target of issue 13 (docs/dynamic.md): a 1M-triangle deforming mesh (a sphereflake under the wave
// deformer), the same four frames in turn for every case: bvh-sah rebuilt from scratch, bvh-sah refitted
// (accel/bvh/refit.h; 8-wide and binary), Embree refitted (RTC_BUILD_QUALITY_REFIT on a dynamic scene) and
// Embree rebuilt in its dynamic scene (low and medium quality); bvh-sah refitted from a TrianglePrims made
// inside the timing (FromMesh) and straight from the mesh (RefitMesh, the harness's path). Wall time of the
// update alone (manual time: build_seconds, not the statistics walk that follows), all threads. Run:
// build/accelbench_micro --benchmark_filter=Dynamic
#include <benchmark/benchmark.h>

#include <chrono>

#include "accel/core/registry.h"
#include "accel/reference/embree.h"
#include "datasets/generators.h"
#include "tracer/deform.h"

namespace ab {
namespace {

/// The frames of the deforming mesh, made once.
const std::vector<std::shared_ptr<const Mesh>>& meshes() {
  static const std::vector<std::shared_ptr<const Mesh>> out = [] {
    const Mesh base = generate_mesh("sphereflake", 1000000, 1, Params{});
    Deformer wave;
    wave.kind = Deformer::Kind::kWave;
    wave.amplitude = 0.02f;
    std::vector<std::shared_ptr<const Mesh>> m;
    for (float p : {0.25f, 0.5f, 0.75f, 1.0f}) m.push_back(std::make_shared<Mesh>(wave.apply(base, p)));
    return m;
  }();
  return out;
}

/// The frames as triangle sets (made once, outside the timing).
const std::vector<std::shared_ptr<const TrianglePrims>>& frames() {
  static const std::vector<std::shared_ptr<const TrianglePrims>> out = [] {
    std::vector<std::shared_ptr<const TrianglePrims>> f;
    for (const auto& m : meshes()) f.push_back(std::make_shared<TrianglePrims>(m));
    return f;
  }();
  return out;
}

void BM_DynamicBvhRebuild(benchmark::State& state, const std::string& width) {
  size_t i = 0;
  for (auto _ : state) {
    auto accel = make_accelerator("bvh-sah", frames()[i++ % frames().size()], Params({{"width", width}}));
    accel->build();
    state.SetIterationTime(accel->stats().build_seconds);  // the build alone, as the harness times it
  }
}

/// Refits bvh-sah (built over frame 0) to each of `frames` in turn (TrianglePrims made outside the timing,
/// or meshes: the whole update), timing the refit alone (not the statistics walk that follows).
template <class Frames>
void refit_each(benchmark::State& state, const std::string& width, const Frames& frames) {
  auto accel = make_accelerator("bvh-sah", ab::frames()[0], Params({{"width", width}}));
  accel->build();
  size_t i = 1;
  for (auto _ : state) {
    if (!accel->refit(frames[i++ % frames.size()])) state.SkipWithError("refit unsupported");
    state.SetIterationTime(accel->stats().build_seconds);
  }
}

void BM_DynamicBvhRefit(benchmark::State& state, const std::string& width) {
  refit_each(state, width, frames());
}

// The same with the frame's TrianglePrims (the triangles copied out of the indexed mesh) made inside the
// timed loop: the like-for-like figure before refit(mesh) (Embree's update reads the indexed vertex buffer
// itself), kept for comparison.
void BM_DynamicBvhRefitFromMesh(benchmark::State& state, const std::string& width) {
  auto accel = make_accelerator("bvh-sah", frames()[0], Params({{"width", width}}));
  accel->build();
  size_t i = 1;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    auto prims = std::make_shared<TrianglePrims>(meshes()[i++ % meshes().size()]);
    const double copy = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!accel->refit(std::move(prims))) state.SkipWithError("refit unsupported");
    state.SetIterationTime(copy + accel->stats().build_seconds);
  }
}

// Straight from the frame's indexed mesh (Accelerator::refit(mesh): the leaves gather their triangles from
// it, no TrianglePrims copy is made): the like-for-like figure of the refit path the harness takes.
void BM_DynamicBvhRefitMesh(benchmark::State& state, const std::string& width) {
  refit_each(state, width, meshes());
}

void BM_DynamicEmbree(benchmark::State& state, RTCBuildQuality quality) {
  EmbreeMesh embree(frames()[0], EmbreeConfig{});
  embree.commit_frame(frames()[0], quality);
  size_t i = 1;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    embree.commit_frame(frames()[i++ % frames().size()], quality);
    state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
}

BENCHMARK_CAPTURE(BM_DynamicBvhRebuild, bvh_sah_width8, "8")->Unit(benchmark::kMillisecond)->UseManualTime();
BENCHMARK_CAPTURE(BM_DynamicBvhRebuild, bvh_sah_width2, "2")->Unit(benchmark::kMillisecond)->UseManualTime();
BENCHMARK_CAPTURE(BM_DynamicBvhRefit, bvh_sah_width8, "8")->Unit(benchmark::kMillisecond)->UseManualTime();
BENCHMARK_CAPTURE(BM_DynamicBvhRefit, bvh_sah_width2, "2")->Unit(benchmark::kMillisecond)->UseManualTime();
BENCHMARK_CAPTURE(BM_DynamicBvhRefitFromMesh, bvh_sah_width8, "8")
    ->Unit(benchmark::kMillisecond)
    ->UseManualTime();
BENCHMARK_CAPTURE(BM_DynamicBvhRefitFromMesh, bvh_sah_width2, "2")
    ->Unit(benchmark::kMillisecond)
    ->UseManualTime();
BENCHMARK_CAPTURE(BM_DynamicBvhRefitMesh, bvh_sah_width8, "8")
    ->Unit(benchmark::kMillisecond)
    ->UseManualTime();
BENCHMARK_CAPTURE(BM_DynamicBvhRefitMesh, bvh_sah_width2, "2")
    ->Unit(benchmark::kMillisecond)
    ->UseManualTime();
BENCHMARK_CAPTURE(BM_DynamicEmbree, embree_refit, RTC_BUILD_QUALITY_REFIT)
    ->Unit(benchmark::kMillisecond)
    ->UseManualTime();
BENCHMARK_CAPTURE(BM_DynamicEmbree, embree_rebuild_low, RTC_BUILD_QUALITY_LOW)
    ->Unit(benchmark::kMillisecond)
    ->UseManualTime();
BENCHMARK_CAPTURE(BM_DynamicEmbree, embree_rebuild_medium, RTC_BUILD_QUALITY_MEDIUM)
    ->Unit(benchmark::kMillisecond)
    ->UseManualTime();

}  // namespace
}  // namespace ab
