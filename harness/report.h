// The run's report files: DIR/report.json (everything), DIR/report.csv (one tidy row per scene x accelerator
// configuration x ray set x query x threads, the same numbers), and the table printed at the end.
#pragma once

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

}  // namespace ab
