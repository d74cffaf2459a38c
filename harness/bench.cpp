#include "harness/bench.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <mutex>
#include <sstream>

namespace ab {

namespace {

/// Google Benchmark reads its flags once; everything is set per case but the random interleaving of the
/// repetitions of cases timed together (which leaves a batch of one case as it was).
void initialize_benchmark_library() {
  static std::once_flag once;
  std::call_once(once, [] {
    static char name[] = "accelbench-run";
    static char interleave[] = "--benchmark_enable_random_interleaving=true";
    static char* argv[] = {name, interleave, nullptr};
    int argc = 2;
    benchmark::Initialize(&argc, argv);
  });
}

double stat_min(const std::vector<double>& v) {
  return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end());
}
double stat_max(const std::vector<double>& v) {
  return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end());
}

/// Seconds per pass of a run (iteration or aggregate).
double seconds_per_pass(const benchmark::BenchmarkReporter::Run& r) {
  return r.iterations > 0 ? r.real_accumulated_time / double(r.iterations) : r.real_accumulated_time;
}

/// Cpu seconds (of the process, all threads) per pass of an iteration run.
double cpu_seconds_per_pass(const benchmark::BenchmarkReporter::Run& r) {
  return r.iterations > 0 ? r.cpu_accumulated_time / double(r.iterations) : r.cpu_accumulated_time;
}

}  // namespace

int64_t iterations_for(double pass_seconds, double min_time) {
  if (min_time <= 0.0 || pass_seconds >= min_time) return 1;
  const double n = std::ceil(min_time / std::max(pass_seconds, 1e-7));
  return int64_t(std::min(n, 1e6));
}

/// Keeps every batch of runs the library reports (display reporter of each RunSpecifiedBenchmarks call).
class BenchTimer::Collector : public benchmark::BenchmarkReporter {
 public:
  bool ReportContext(const Context&) override { return true; }
  void ReportRuns(const std::vector<Run>& runs) override {
    batches.push_back(runs);
    // The statistics pointer refers to the registered case, which is cleared after the run.
    for (Run& r : batches.back()) r.statistics = nullptr;
    for (const Run& r : runs) current.push_back(r);
  }

  std::vector<std::vector<Run>> batches;  ///< everything, for gbench.json
  std::vector<Run> current;               ///< runs of the case being timed
};

BenchTimer::BenchTimer() : collector_(new Collector) {
  initialize_benchmark_library();
}

BenchTimer::~BenchTimer() {
  delete collector_;
}

namespace {

Timing summarize(const std::vector<benchmark::BenchmarkReporter::Run>& runs, int repetitions,
                 int64_t iterations) {
  Timing t;
  t.repetitions = repetitions;
  t.iterations = iterations;
  std::vector<double> per_rep;
  for (const auto& r : runs) {
    if (r.run_type == benchmark::BenchmarkReporter::Run::RT_Iteration) {
      per_rep.push_back(seconds_per_pass(r));
      t.cpu_samples.push_back(cpu_seconds_per_pass(r));
      continue;
    }
    const double s = seconds_per_pass(r);
    if (r.aggregate_name == "median")
      t.median = s, t.cpu_median = cpu_seconds_per_pass(r);
    else if (r.aggregate_name == "mean")
      t.mean = s;
    else if (r.aggregate_name == "stddev")
      t.stddev = s;
    else if (r.aggregate_name == "min")
      t.min = s;
    else if (r.aggregate_name == "max")
      t.max = s;
  }
  if (per_rep.size() == 1) {  // no aggregates for one run
    t.median = t.mean = t.min = t.max = per_rep.front();
    t.cpu_median = t.cpu_samples.front();
  }
  t.samples = std::move(per_rep);
  return t;
}

}  // namespace

Timing BenchTimer::time(const std::string& name, int repetitions, int64_t iterations,
                        const std::function<double()>& pass, double items,
                        const std::map<std::string, double>& counters) {
  return time_together({BenchCase{name, iterations, pass, items, counters}}, repetitions).front();
}

std::vector<Timing> BenchTimer::time_together(const std::vector<BenchCase>& cases, int repetitions) {
  std::exception_ptr error;
  for (const BenchCase& c : cases) {
    auto body = [&error, &c](benchmark::State& state) {
      try {
        for (auto _ : state) state.SetIterationTime(c.pass());
      } catch (...) {
        if (!error) error = std::current_exception();
        state.SkipWithError("exception in the timed pass");
        return;
      }
      if (c.items > 0) state.SetItemsProcessed(int64_t(c.items * double(state.iterations())));
      for (const auto& [key, value] : c.counters) state.counters[key] = value;
    };
    benchmark::RegisterBenchmark(c.name.c_str(), body)
        ->UseManualTime()
        ->MeasureProcessCPUTime()
        ->Iterations(std::max<int64_t>(1, c.iterations))
        ->Repetitions(std::max(1, repetitions))
        ->ComputeStatistics("min", stat_min)
        ->ComputeStatistics("max", stat_max)
        ->Unit(benchmark::kMillisecond);
  }
  collector_->current.clear();
  benchmark::RunSpecifiedBenchmarks(collector_);
  benchmark::ClearRegisteredBenchmarks();
  if (error) std::rethrow_exception(error);
  std::vector<Timing> timings;
  for (const BenchCase& c : cases) {
    std::vector<benchmark::BenchmarkReporter::Run> runs;  // this case's, from the interleaved batch
    for (const auto& r : collector_->current)
      if (r.run_name.function_name == c.name) runs.push_back(r);
    timings.push_back(summarize(runs, repetitions, c.iterations));
  }
  return timings;
}

std::string BenchTimer::json() const {
  std::ostringstream out;
  benchmark::JSONReporter reporter;
  reporter.SetOutputStream(&out);
  reporter.SetErrorStream(&out);
  benchmark::BenchmarkReporter::Context context;
  reporter.ReportContext(context);
  for (const auto& batch : collector_->batches) reporter.ReportRuns(batch);
  reporter.Finalize();
  return out.str();
}

}  // namespace ab
