// The cost of the embree adapter against a plain rtcIntersect1 loop on the same scene and rays
// (issue: the adapter's overhead must stay under 5%). Run: build/accelbench_micro --benchmark_filter=Embree
#include <benchmark/benchmark.h>

#include "accel/core/registry.h"
#include "accel/reference/embree.h"
#include "datasets/generators.h"
#include "datasets/rays.h"
#include "harness/target.h"

namespace ab {
namespace {

struct EmbreeFixture {
  Target target;
  std::unique_ptr<Accelerator> accel;
  std::vector<Ray> rays;

  static EmbreeFixture& get(const std::string& kind) {
    static std::map<std::string, std::unique_ptr<EmbreeFixture>> cache;
    auto& f = cache[kind];
    if (!f) {
      f = std::make_unique<EmbreeFixture>();
      f->target = mesh_target(std::make_shared<const Mesh>(generate_mesh("sphereflake", 100000, 1, Params{})),
                              "sphereflake");
      f->accel = make_target_accelerator(f->target, "embree", Params{});
      f->accel->build();
      f->rays = make_rays(kind, ray_target(f->target), 100000, 1);
    }
    return *f;
  }
};

void BM_EmbreeAdapter(benchmark::State& state, const std::string& kind) {
  EmbreeFixture& f = EmbreeFixture::get(kind);
  std::vector<Hit> hits(f.rays.size());
  for (auto _ : state) {
    f.accel->intersect(f.rays, hits);
    benchmark::DoNotOptimize(hits.data());
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(f.rays.size()));
}

void BM_EmbreePlainLoop(benchmark::State& state, const std::string& kind) {
  EmbreeFixture& f = EmbreeFixture::get(kind);
  const RTCScene scene = static_cast<const EmbreeMesh&>(*f.accel).scene();
  std::vector<Hit> hits(f.rays.size());
  for (auto _ : state) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (size_t i = 0; i < f.rays.size(); ++i) {
      RTCRayHit rh = to_embree(f.rays[i]);
      rtcIntersect1(scene, &context, &rh);
      hits[i].t = rh.ray.tfar;
      hits[i].prim = rh.hit.primID;
    }
    benchmark::DoNotOptimize(hits.data());
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(f.rays.size()));
}

BENCHMARK_CAPTURE(BM_EmbreeAdapter, primary, std::string("primary"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_EmbreePlainLoop, primary, std::string("primary"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_EmbreeAdapter, incoherent, std::string("incoherent"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_EmbreePlainLoop, incoherent, std::string("incoherent"))->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace ab
