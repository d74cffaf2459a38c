// What a run's report derives from its measured rows: ratios to Embree, the correlation of the SAH's
// predicted cost with the measured cost per ray, and the per-configuration summaries of the terminal table.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace ab {

/// Pearson's correlation coefficient of two equally long series (NaN when undefined).
double pearson(const std::vector<double>& x, const std::vector<double>& y);

/// Sets every result row's ratio_to_embree: its rays/s over the rays/s of the first "embree" configuration
/// on the same scene, ray set, query and thread count (rows without such an Embree row keep null), and
/// cpu_ratio_to_embree, the same by rays per cpu second.
void fill_ratios(nlohmann::json& report);

/// Replaces report["sah_correlation"]: per scene and ray set, Pearson's r between each configuration's
/// SAH-predicted cost and its measured Havran cost per ray (closest hit at `threads`, the suite's first
/// thread count), null below three configurations.
void fill_correlations(nlohmann::json& report, int threads);

/// Geometric mean of the positive values added (NaN when there are none).
struct GeoMean {
  double log_sum = 0.0;  ///< sum of the logarithms
  int n = 0;             ///< values added
  /// Adds v when it is a positive number.
  void add(const nlohmann::json& v);
  /// The mean.
  double value() const;
};

/// One configuration's line of the summary table: geometric means over scenes and ray sets.
struct ConfigSummary {
  GeoMean ratio_one, ratio_all;  ///< ratio_to_embree, closest hit, at 1 thread and at all threads
  GeoMean cpu_ratio_one;         ///< cpu_ratio_to_embree, closest hit, at 1 thread
  GeoMean mrays_one, mrays_all;  ///< Mrays/s, closest hit, at 1 thread and at all threads
  GeoMean build_rate;            ///< million triangles built per second
  GeoMean nodes, prims;          ///< per ray, closest hit at 1 thread
  GeoMean bytes;                 ///< bytes per triangle
  bool verified = true;          ///< every row of the configuration verified
  int rows = 0;                  ///< result rows of the configuration
};

/// The summaries of every configuration label of the report's results; `order` receives the labels in the
/// order they first appear.
std::map<std::string, ConfigSummary> summarize_configs(const nlohmann::json& report,
                                                       std::vector<std::string>& order);

}  // namespace ab
