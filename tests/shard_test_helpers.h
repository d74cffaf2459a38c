// What the sharding tests share: running the binary, reading reports, and the comparison of a merged run with
// an unsharded run of the same suite: the same cases in the same order, the same verification results and
// hit checks, the same deterministic figures (structure statistics, per-ray counters); timings and Embree's
// memory aside.
#pragma once

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "tests/cli_test_helpers.h"

namespace ab::test {

/// A JSON file (null when it cannot be read or parsed).
inline nlohmann::json read_json_file(const std::string& path) {
  return nlohmann::json::parse(read_text(path), nullptr, false);
}

/// `value` without the keys that are measurements of time or of this process (they differ run to run).
inline nlohmann::json without_timings(nlohmann::json value) {
  if (value.is_array())
    for (auto& v : value) v = without_timings(v);
  if (!value.is_object()) return value;
  for (auto it = value.begin(); it != value.end();) {
    const std::string& k = it.key();
    const bool timing = k.find("seconds") != std::string::npos ||
                        k.find("rays_per_second") != std::string::npos || k == "rays_per_cpu_second" ||
                        k.find("ratio_to_embree") != std::string::npos || k == "iterations" || k == "extra" ||
                        k.find("peak_bytes") != std::string::npos;
    if (timing)
      it = value.erase(it);
    else
      ++it;
  }
  for (auto& v : value) v = without_timings(v);
  return value;
}

/// An entry without what varies between runs: timings, and Embree's memory (its allocator's blocks depend on
/// the threads that built it).
inline nlohmann::json deterministic_part(const nlohmann::json& entry) {
  nlohmann::json v = without_timings(entry);
  if (v.is_object() && v.value("accelerator", "") == "embree") {
    v.erase("bytes");
    v.erase("bytes_per_triangle");
    if (v.contains("stats")) v["stats"].erase("bytes"), v["stats"].erase("bytes_per_primitive");
  }
  return v;
}

/// Compares list `key` of two reports item by item (timings aside); appends the differences.
inline void compare_list(const nlohmann::json& merged, const nlohmann::json& single, const char* key,
                         std::vector<std::string>& out) {
  const auto& a = merged.value(key, nlohmann::json::array());
  const auto& b = single.value(key, nlohmann::json::array());
  if (a.size() != b.size())
    out.push_back(std::string(key) + ": " + std::to_string(a.size()) + " entries merged, " +
                  std::to_string(b.size()) + " unsharded");
  for (size_t i = 0; i < std::min(a.size(), b.size()) && out.size() < 20; ++i) {
    const nlohmann::json x = deterministic_part(a[i]), y = deterministic_part(b[i]);
    if (x != y)
      out.push_back(std::string(key) + "[" + std::to_string(i) + "]: merged " + x.dump().substr(0, 300) +
                    " vs unsharded " + y.dump().substr(0, 300));
  }
}

/// The differences between a merged report and an unsharded report of the same suite (empty: they agree case
/// for case): scenes, builds (statistics and per-ray-set verification), result rows (case, verification,
/// hit checks, counters), correlations' inputs, the verdict and the failures.
inline std::vector<std::string> report_differences(const nlohmann::json& merged,
                                                   const nlohmann::json& single) {
  std::vector<std::string> out;
  for (const char* key : {"suite", "suite_hash", "seed", "verified", "schema_version"})
    if (merged.value(key, nlohmann::json()) != single.value(key, nlohmann::json()))
      out.push_back(std::string(key) + ": merged " + merged.value(key, nlohmann::json()).dump() +
                    " vs unsharded " + single.value(key, nlohmann::json()).dump());
  auto sorted = [](nlohmann::json v) {
    std::sort(v.begin(), v.end());
    return v;
  };
  if (sorted(merged.value("failures", nlohmann::json::array())) !=
      sorted(single.value("failures", nlohmann::json::array())))
    out.push_back("failures differ");
  for (const char* key : {"scenes", "builds", "results", "sah_correlation"})
    compare_list(merged, single, key, out);
  return out;
}

}  // namespace ab::test
