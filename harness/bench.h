// Timing through Google Benchmark: each case is registered at run time, timed manually (only the part
// the caller measures, for example the traversal loop), repeated, and summarized by the library's own
// statistics (median, mean, stddev, plus min and max). Every run is kept for DIR/gbench.json, which the
// library's tools (compare.py) read.
#pragma once

#include <benchmark/benchmark.h>

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace ab {

/// Seconds per pass over the repetitions of one case.
struct Timing {
  double median = 0.0;          ///< median over the repetitions
  double min = 0.0;             ///< fastest repetition
  double max = 0.0;             ///< slowest repetition
  double mean = 0.0;            ///< mean over the repetitions
  double stddev = 0.0;          ///< standard deviation over the repetitions
  int repetitions = 0;          ///< repetitions timed
  int64_t iterations = 0;       ///< passes per repetition
  std::vector<double> samples;  ///< seconds per pass of each repetition, in order (for `compare`)
  /// Cpu seconds of the whole process (every thread) per pass: the median over the repetitions and each
  /// repetition's, in order. Time the process spent waiting for a core on a loaded machine is not in it.
  double cpu_median = 0.0;
  std::vector<double> cpu_samples;  ///< cpu seconds per pass of each repetition
};

/// Passes per repetition so that a repetition lasts at least `min_time` seconds, given one pass's time.
int64_t iterations_for(double pass_seconds, double min_time);

/// One case of a batch timed together (BenchTimer::time_together).
struct BenchCase {
  std::string name;                        ///< the case's name in gbench.json (unique within the batch)
  int64_t iterations = 1;                  ///< passes per repetition
  std::function<double()> pass;            ///< one pass; returns the seconds to count (manual timing)
  double items = 0.0;                      ///< rays or triangles per pass (items_per_second)
  std::map<std::string, double> counters;  ///< attached to the case in gbench.json
};

/// Runs cases through Google Benchmark, one at a time or a batch together, and keeps every reported run.
class BenchTimer {
 public:
  /// Initializes Google Benchmark (once per process) and an empty collection of runs.
  BenchTimer();
  ~BenchTimer();
  BenchTimer(const BenchTimer&) = delete;
  BenchTimer& operator=(const BenchTimer&) = delete;

  /// Times `pass`, which does one unit of work and returns the seconds of the part to count (manual
  /// timing), `iterations` times per repetition. `items` (rays, triangles) per pass gives the
  /// library's items_per_second; `counters` are attached to the case in gbench.json. Exceptions thrown
  /// by `pass` are rethrown after the library has finished the case.
  Timing time(const std::string& name, int repetitions, int64_t iterations,
              const std::function<double()>& pass, double items = 0.0,
              const std::map<std::string, double>& counters = {});

  /// Times every case of `cases` in one run of the library, `repetitions` times each, the repetitions of
  /// all cases in a random order (the library's random interleaving), so that a change of the machine's
  /// load falls on every case alike; one Timing per case, in order. With one case, the same as time().
  std::vector<Timing> time_together(const std::vector<BenchCase>& cases, int repetitions);

  /// Google Benchmark's JSON (context and every run so far), as its JSONReporter writes it.
  std::string json() const;

 private:
  class Collector;
  Collector* collector_;
};

}  // namespace ab
