// The timing of a suite's builds and queries through Google Benchmark (harness/bench.h): builds repeated and
// each timed alone, queries after untimed warm-up passes with enough iterations per repetition to last the
// suite's min_time, and the timing fields of the report's rows.
#pragma once

#include <chrono>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "harness/bench.h"
#include "harness/suite.h"

namespace ab {

/// Wall seconds since t0.
double seconds_since(std::chrono::steady_clock::time_point t0);

/// Times a suite's cases with its repetitions, warm-up and minimum time; keeps every run for gbench.json.
class SuiteTimer {
 public:
  /// With the suite's timing settings (the suite must outlive the timer).
  explicit SuiteTimer(const Suite& suite) : suite_(suite) {}

  /// Runs `build` (which builds once and returns the seconds of that build alone) build_repetitions times.
  Timing time_build(const std::string& name, double triangles, const std::function<double()>& build);
  /// Times `work` (one pass over `rays` rays): warm-up passes first (untimed), then repetitions of enough
  /// passes to last min_time, the count estimated from the fastest warm-up pass.
  Timing time_query(const std::string& name, size_t rays, const std::function<void()>& work);
  /// One query case of a batch (time_queries).
  struct Query {
    std::string name;            ///< the case's name
    size_t rays = 0;             ///< rays per pass
    std::function<void()> work;  ///< one pass
  };
  /// Times several queries as time_query times one (each its own warm-up and pass count), their
  /// repetitions interleaved in one run (BenchTimer::time_together); one Timing per query, in order.
  std::vector<Timing> time_queries(const std::vector<Query>& queries);
  /// Google Benchmark's JSON of every case timed so far.
  std::string gbench_json() const { return timer_.json(); }

 private:
  const Suite& suite_;
  BenchTimer timer_;
};

/// A Timing as the report's JSON (median, min, max, mean, stddev, repetitions, iterations).
nlohmann::json timing_json(const Timing& t);

/// The timing fields of a query's result row: threads (asked and used), repetitions, iterations, seconds
/// (median, min, max, mean, stddev) and rays per second (median, min, max) over `rays` rays, and the
/// process's cpu seconds per pass (median, samples) with rays per cpu second.
nlohmann::json query_timing_fields(const Timing& t, int threads, double rays);

}  // namespace ab
