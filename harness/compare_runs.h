// Two runs compared case by case (`accelbench compare BASE NEW`): the ratio of medians NEW/BASE of every
// case's throughput and of every build's time, a Mann-Whitney U test over the repetitions (each row keeps
// every repetition's seconds), the changes beyond a threshold that are significant, the cases present in only
// one run, and warnings when the runs come from different machines, compilers or suites.
#pragma once

#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

namespace ab {

/// One run's report: report.json read from a run folder or given directly. Throws InputError naming the
/// file when it is missing, not JSON, or not a report (no "results" array).
nlohmann::json load_run_report(const std::string& path);

/// What `compare` decides about one case.
enum class Change {
  kUnchanged,    ///< within the threshold, or not significant
  kImprovement,  ///< faster beyond the threshold, significant
  kRegression,   ///< slower beyond the threshold, significant
  kUntested,     ///< beyond the threshold, but without the repetitions a test needs
};

/// One case of both runs: a query (scene, configuration, ray set, query, threads) or a build (scene,
/// configuration; query "build").
struct CaseComparison {
  std::string scene, config, rays, query;  ///< the case (rays empty for a build)
  int threads = 0;                         ///< threads asked (0: all; -1 for a build)
  double base_median = 0.0;                ///< seconds per pass (or per build) in BASE
  double new_median = 0.0;                 ///< the same in NEW
  double ratio = 1.0;    ///< NEW/BASE of the medians: rays/s for a query, seconds for a build
  double p_value = 1.0;  ///< Mann-Whitney U over the repetitions (NaN: fewer than one each)
  bool exact = false;    ///< p from the exact distribution
  size_t base_repetitions = 0, new_repetitions = 0;  ///< repetitions of each run
  Change change = Change::kUnchanged;                ///< the verdict
};

/// The whole comparison.
struct RunComparison {
  std::vector<CaseComparison> cases;   ///< cases in both runs, in BASE's order
  std::vector<std::string> only_base;  ///< cases of BASE missing from NEW
  std::vector<std::string> only_new;   ///< cases of NEW missing from BASE
  std::vector<std::string> warnings;   ///< different machines, compilers or suites
  double threshold = 0.05;             ///< the relative change that counts
  double alpha = 0.05;                 ///< the significance level
  bool cpu = false;                    ///< queries compared by cpu seconds instead of wall seconds
  /// True when any case regressed (significant, beyond the threshold).
  bool regressed() const;
};

/// Compares NEW against BASE: a case changes when its ratio is beyond 1 +- threshold (slower: throughput
/// below 1 - threshold, build time above 1 + threshold) and the test gives p < alpha. With `cpu`, queries
/// are compared by the process's cpu seconds per pass (cpu_seconds_median/samples) instead of wall seconds.
RunComparison compare_runs(const nlohmann::json& base, const nlohmann::json& next, double threshold,
                           double alpha, bool cpu = false);

/// The word of a verdict ("unchanged", "improvement", "REGRESSION", "untested").
std::string change_name(Change c);
/// The table as JSON (for --json): settings, warnings, cases and the cases in only one run.
nlohmann::json to_json(const RunComparison& c);
/// The table as CSV (for --csv): one line per case.
std::string to_csv(const RunComparison& c);
/// The table for people.
void print_comparison(std::ostream& out, const RunComparison& c);

}  // namespace ab
