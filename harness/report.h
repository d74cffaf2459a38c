// The run's report: DIR/report.json (everything), DIR/report.csv (one tidy row per scene x accelerator
// configuration x ray set x query x threads, the same numbers), the terminal table and the progress bar.
#pragma once

#include <chrono>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

namespace ab {

/// Version of the report.json layout (bumped on incompatible changes).
inline constexpr int kReportSchemaVersion = 1;

/// The columns of report.csv, in order; each is a key of a row in report.json's "results".
const std::vector<std::string>& csv_columns();
/// report.csv's text for a report (header line, then one line per result row).
std::string report_csv(const nlohmann::json& report);
/// Writes DIR/report.json and DIR/report.csv, each whole or not at all.
void write_report(const nlohmann::json& report, const std::string& dir);

/// The short table printed at the end: one line per accelerator configuration with its geometric-mean
/// ratio to Embree at 1 thread and at all threads, Mrays/s, build time, bytes per triangle, per-ray
/// costs and the verification verdict. `color` adds ANSI colors (red for failures).
void print_summary_table(std::ostream& out, const nlohmann::json& report, bool color);

/// A progress bar with ETA on stderr, drawn only when stderr is a terminal.
class Progress {
 public:
  /// `total` units of work; `enabled` false draws nothing.
  Progress(size_t total, bool enabled);
  /// One more unit done; `what` says what is running now.
  void step(const std::string& what);
  /// Clears the bar.
  void finish();

 private:
  void draw(const std::string& what);
  size_t total_;
  size_t done_ = 0;
  bool enabled_;
  std::chrono::steady_clock::time_point start_;
};

/// True when stderr is a terminal (progress bar and colors).
bool stderr_is_terminal();
/// True when stdout is a terminal.
bool stdout_is_terminal();

}  // namespace ab
