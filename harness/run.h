// Running a suite: scenes are made one at a time, every accelerator configuration is built (timed over
// the repetitions), verified against brute force, the verified reference structure and Embree
// (harness/verification.h), and timed through Google Benchmark at each thread count (harness/timing.h);
// counters come from a separate counting pass; ratios and correlations follow (harness/analysis.h).
#pragma once

#include <atomic>
#include <nlohmann/json.hpp>
#include <string>

#include "harness/suite.h"

namespace ab {

/// How to run a suite.
struct RunOptions {
  std::string out_dir;                             ///< where report.json, report.csv and gbench.json go
  bool progress = false;                           ///< draw the progress bar on stderr
  bool color = false;                              ///< red failure lines on stderr
  const std::atomic<bool>* interrupted = nullptr;  ///< set by SIGINT: stop after the current case
  /// When the suite is one shard of a larger one: what the report records under "shard" (harness/shard.h).
  nlohmann::json shard;
};

/// Runs the suite and returns the report (also written to out_dir after every scene and at the end,
/// with gbench.json beside it). report["verified"] is false when any check failed; report["interrupted"]
/// is true when the run stopped early (finished cases are kept); report["complete"] is true only in the final
/// save of a run that was not interrupted (a report saved between scenes, then killed, says false).
nlohmann::json run_suite(const Suite& suite, const RunOptions& options);

}  // namespace ab
