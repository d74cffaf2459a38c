// Google Benchmark microbenchmarks of the hot kernels (ray/box, ray/triangle), of one traversal per
// structure and generator (single thread, closest hit), and of the builds (2 threads).
// Sizes from the environment: ACCELBENCH_MICRO_TRIANGLES (default 100000), ACCELBENCH_MICRO_RAYS (100000).
// Filter with --benchmark_filter, e.g. 'Trace/sphereflake/.*/(bvh-sah|embree)'.
#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

#include <cstdlib>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <vector>

#include "accel/bvh/walk2.h"
#include "accel/bvh/walk8.h"
#include "accel/core/box_test.h"
#include "accel/core/registry.h"
#include "accel/core/triangle.h"
#include "accel/core/triangle4.h"
#include "datasets/generators.h"
#include "datasets/rays.h"
#include "harness/target.h"

namespace ab {
namespace {

uint64_t env_count(const char* name, uint64_t def) {
  const char* s = std::getenv(name);
  return s ? std::strtoull(s, nullptr, 10) : def;
}

float uniform(std::mt19937& rng, float lo, float hi) {
  return lo + (hi - lo) * float(rng() >> 8) * 0x1p-24f;
}

std::vector<Ray> random_rays(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<Ray> rays(n);
  for (Ray& r : rays) {
    r.org = {uniform(rng, -1, 2), uniform(rng, -1, 2), uniform(rng, -1, 2)};
    r.dir = {uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)};
  }
  return rays;
}

Triangle random_triangle(std::mt19937& rng) {
  auto corner = [&] { return vec3(uniform(rng, 0, 1), uniform(rng, 0, 1), uniform(rng, 0, 1)); };
  const vec3 a = corner(), b = corner(), c = corner();
  return {a, b, c};
}

void BM_SlabTest(benchmark::State& state) {
  const auto rays = random_rays(1024, 1);
  std::vector<RayBoxData> data;
  for (const Ray& r : rays) data.emplace_back(r);
  const AABB box{{0, 0, 0}, {1, 1, 1}};
  size_t i = 0, hits = 0;
  for (auto _ : state) {
    float t0 = 0.0f, t1 = kInf;
    hits += slab_test(box, data[i++ & 1023], t0, t1);
    benchmark::DoNotOptimize(t0);
  }
  benchmark::DoNotOptimize(hits);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_SlabTest);

void BM_BvhPairTest(benchmark::State& state) {
  const auto rays = random_rays(1024, 2);
  std::vector<BvhPairTest> tests;
  for (const Ray& r : rays) tests.emplace_back(r);
  alignas(64) const BvhNode pair[2] = {{{0, 0, 0}, 0, {1, 1, 1}, 0}, {{0.5f, 0, 0}, 0, {1.5f, 1, 1}, 0}};
  size_t i = 0;
  for (auto _ : state) {
    float tl, tr;
    tests[i++ & 1023].entries(pair, kInf, tl, tr);
    benchmark::DoNotOptimize(tl);
    benchmark::DoNotOptimize(tr);
  }
  state.SetItemsProcessed(state.iterations() * 2);  // boxes
}
BENCHMARK(BM_BvhPairTest);

void BM_RayTriangle(benchmark::State& state) {
  const auto rays = random_rays(1024, 3);
  std::mt19937 rng(4);
  std::vector<Triangle> tris(1024);
  for (Triangle& t : tris) t = random_triangle(rng);
  size_t i = 0;
  Hit best;
  for (auto _ : state) {
    intersect_and_update(rays[i & 1023], tris[(i * 7) & 1023], uint32_t(i & 1023), kInvalidId, best);
    ++i;
    benchmark::DoNotOptimize(best);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RayTriangle);

void BM_Bvh8BoxTest(benchmark::State& state) {
  const auto rays = random_rays(1024, 5);
  std::vector<Bvh8RayTest> tests;
  for (const Ray& r : rays) tests.emplace_back(r);
  Bvh8Node node;
  for (int k = 0; k < 8; ++k) {
    for (int a = 0; a < 3; ++a)
      node.bounds[a][k] = 0.25f * float(k) * (a == 0),
      node.bounds[3 + a][k] = 1.0f + 0.25f * float(k) * (a == 0);
    node.child[k] = node.count[k] = 0;
  }
  alignas(32) float t[8];
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(tests[i++ & 1023].entries(node, kInf, t));
    benchmark::DoNotOptimize(t);
  }
  state.SetItemsProcessed(state.iterations() * 8);  // boxes
}
BENCHMARK(BM_Bvh8BoxTest);

void BM_RayTriangle4(benchmark::State& state) {
  const auto rays = random_rays(1024, 3);
  std::mt19937 rng(4);
  std::vector<Triangle4> quads(256);
  for (Triangle4& q : quads) {
    Triangle tris[4];
    for (Triangle& t : tris) t = random_triangle(rng);
    q = Triangle4::pack(tris);
  }
  std::vector<RayBoxData> boxes(rays.begin(), rays.end());
  std::vector<Ray4> ray4;
  for (size_t r = 0; r < rays.size(); ++r) ray4.emplace_back(rays[r], boxes[r]);
  alignas(16) float t[4], u[4], v[4];
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(intersect_triangle4(ray4[i & 1023], quads[(i * 7) & 255], t, u, v));
    ++i;
  }
  state.SetItemsProcessed(state.iterations() * 4);  // triangles
}
BENCHMARK(BM_RayTriangle4);

/// Generated meshes and their ray sets, made once per process.
struct Workload {
  std::shared_ptr<const Mesh> mesh;
  Target target;
  std::map<std::string, std::vector<Ray>> rays;
};

Workload& workload(const std::string& generator) {
  static std::mutex mutex;
  static std::map<std::string, std::unique_ptr<Workload>> cache;
  std::lock_guard lock(mutex);
  auto& w = cache[generator];
  if (!w) {
    w = std::make_unique<Workload>();
    w->mesh = std::make_shared<const Mesh>(
        generate_mesh(generator, env_count("ACCELBENCH_MICRO_TRIANGLES", 100000), 1, Params()));
    w->target = mesh_target(w->mesh, generator);
  }
  return *w;
}

const std::vector<Ray>& rays_of(Workload& w, const std::string& kind) {
  auto& r = w.rays[kind];
  if (r.empty()) r = make_rays(kind, ray_target(w.target), env_count("ACCELBENCH_MICRO_RAYS", 100000), 7);
  return r;
}

/// One thread through the batch entry points: closest hit, or any hit for shadow rays (what the harness
/// traces them with).
void BM_Trace(benchmark::State& state, std::string generator, std::string kind, std::string accel,
              std::string param) {
  Workload& w = workload(generator);
  const auto& rays = rays_of(w, kind);
  Params params;
  if (!param.empty()) params.add(param);
  auto structure = make_target_accelerator(w.target, accel, params);
  structure->build();
  const bool any_hit = kind == "shadow";
  std::vector<Hit> hits(any_hit ? 0 : rays.size());
  std::vector<uint8_t> occluded(any_hit ? rays.size() : 0);
  for (auto _ : state) {
    if (any_hit) {
      structure->occluded(rays, occluded);
      benchmark::DoNotOptimize(occluded.data());
    } else {
      structure->intersect(rays, hits);
      benchmark::DoNotOptimize(hits.data());
    }
  }
  state.SetItemsProcessed(int64_t(state.iterations() * rays.size()));
  state.counters["Mrays/s"] =
      benchmark::Counter(double(rays.size()) * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
}

void BM_Build(benchmark::State& state, std::string generator, std::string accel, std::string param) {
  Workload& w = workload(generator);
  tbb::task_arena arena(2);
  Params params;
  if (!param.empty()) params.add(param);
  BuildStats stats;
  for (auto _ : state) {
    auto structure = make_target_accelerator(w.target, accel, params);
    arena.execute([&] { structure->build(); });
    stats = structure->stats();
    state.SetIterationTime(stats.build_seconds);
  }
  state.counters["Mtris/s"] =
      benchmark::Counter(double(w.mesh->size()) * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["sah"] = stats.sah_cost;
  state.counters["bytes/tri"] = stats.bytes_per_primitive();
  state.counters["refs/tri"] = stats.references_per_primitive();
}

const bool kRegistered = [] {
  const char* generators[] = {"sphereflake", "terrain", "soup"};
  for (const char* g : generators) {
    for (const char* kind : {"primary", "incoherent"})
      for (const char* accel : {"bvh-sah", "bvh-sweep", "bvh-median", "grid", "embree"})
        benchmark::RegisterBenchmark((std::string("BM_Trace/") + g + "/" + kind + "/" + accel).c_str(),
                                     BM_Trace, g, kind, accel, "")
            ->Unit(benchmark::kMillisecond)
            ->MinWarmUpTime(0.2);
    for (const char* accel : {"bvh-sah", "embree"})  // any hit
      benchmark::RegisterBenchmark((std::string("BM_Trace/") + g + "/shadow/" + accel).c_str(), BM_Trace, g,
                                   "shadow", accel, "")
          ->Unit(benchmark::kMillisecond)
          ->MinWarmUpTime(0.2);
    for (const char* kind : {"primary", "incoherent"})
      for (const char* cost : {"0.5", "2", "3"})
        benchmark::RegisterBenchmark(
            (std::string("BM_Trace/") + g + "/" + kind + "/bvh-sah/traversal_cost=" + cost).c_str(), BM_Trace,
            g, kind, "bvh-sah", std::string("traversal_cost=") + cost)
            ->Unit(benchmark::kMillisecond);
    for (const char* kind : {"primary", "incoherent"})
      for (const char* lambda : {"0.5", "0.75", "1", "1.5", "2", "3"})
        benchmark::RegisterBenchmark(
            (std::string("BM_Trace/") + g + "/" + kind + "/grid/lambda=" + lambda).c_str(), BM_Trace, g, kind,
            "grid", std::string("lambda=") + lambda)
            ->Unit(benchmark::kMillisecond);
    for (const char* accel : {"bvh-sah", "bvh-sweep", "bvh-median", "grid", "embree"})
      benchmark::RegisterBenchmark((std::string("BM_Build/") + g + "/" + accel).c_str(), BM_Build, g, accel,
                                   "")
          ->Unit(benchmark::kMillisecond)
          ->UseManualTime();
    for (const char* lambda : {"0.5", "0.75", "1", "1.5", "2", "3"})
      benchmark::RegisterBenchmark((std::string("BM_Build/") + g + "/grid/lambda=" + lambda).c_str(),
                                   BM_Build, g, "grid", std::string("lambda=") + lambda)
          ->Unit(benchmark::kMillisecond)
          ->UseManualTime();
  }
  return true;
}();

}  // namespace
}  // namespace ab
