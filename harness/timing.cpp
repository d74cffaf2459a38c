#include "harness/timing.h"

#include <oneapi/tbb/info.h>

#include <algorithm>

namespace ab {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

Timing SuiteTimer::time_build(const std::string& name, double triangles,
                              const std::function<double()>& build) {
  return timer_.time(name, suite_.build_repetitions, 1, build, triangles);
}

Timing SuiteTimer::time_query(const std::string& name, size_t rays, const std::function<void()>& work) {
  return time_queries({Query{name, rays, work}}).front();
}

std::vector<Timing> SuiteTimer::time_queries(const std::vector<Query>& queries) {
  std::vector<BenchCase> cases;
  for (const Query& q : queries) {
    auto pass = [work = q.work] {
      const auto t0 = std::chrono::steady_clock::now();
      work();
      return seconds_since(t0);
    };
    double estimate = 0.0;  // the fastest warm-up pass (the least disturbed by other processes)
    for (int i = 0; i < suite_.warmup; ++i) {
      const double s = pass();
      estimate = i == 0 ? s : std::min(estimate, s);
    }
    const int64_t iterations = estimate > 0 ? iterations_for(estimate, suite_.min_time) : 1;
    cases.push_back(BenchCase{q.name, iterations, pass, double(q.rays), {}});
  }
  return timer_.time_together(cases, suite_.repetitions);
}

nlohmann::json timing_json(const Timing& t) {
  return {{"median", t.median},
          {"min", t.min},
          {"max", t.max},
          {"mean", t.mean},
          {"stddev", t.stddev},
          {"repetitions", t.repetitions},
          {"iterations", t.iterations},
          {"samples", t.samples}};
}

nlohmann::json query_timing_fields(const Timing& t, int threads, double rays) {
  return {{"threads", threads},
          {"threads_used", threads > 0 ? threads : tbb::info::default_concurrency()},
          {"repetitions", t.repetitions},
          {"iterations", t.iterations},
          {"seconds_median", t.median},
          {"seconds_min", t.min},
          {"seconds_max", t.max},
          {"seconds_mean", t.mean},
          {"seconds_stddev", t.stddev},
          {"seconds_samples", t.samples},
          {"rays_per_second", t.median > 0 ? rays / t.median : 0.0},
          {"rays_per_second_min", t.max > 0 ? rays / t.max : 0.0},
          {"rays_per_second_max", t.min > 0 ? rays / t.min : 0.0},
          {"cpu_seconds_median", t.cpu_median},
          {"cpu_seconds_samples", t.cpu_samples},
          {"rays_per_cpu_second", t.cpu_median > 0 ? rays / t.cpu_median : 0.0}};
}

}  // namespace ab
