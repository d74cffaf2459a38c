// Merging the shards of a suite (`accelbench merge DIR... -o DIR`) into one run folder that reads like a
// single run: every scene's entries, builds and result rows in the suite's scene order, verification results
// and failures combined, the ratios to Embree and SAH correlations as each shard measured them (both are per
// scene), and each shard's machine, compiler, source and date kept under "machines".
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace ab {

/// A merged run: the contents of its report.json and gbench.json, and notes for the user.
struct MergedRun {
  nlohmann::json report;           ///< report.json: one run of the whole suite
  nlohmann::json gbench;           ///< gbench.json: shard 1's context, every shard's benchmarks
  std::vector<std::string> notes;  ///< lines worth printing (for example: shards ran on different CPUs)
};

/// Reads DIR/report.json and DIR/gbench.json of every shard folder and merges them. Refuses (InputError, one
/// line naming the folder) a folder that is not a finished shard of `accelbench run --shard`, shards of
/// different suites, commits or shard counts, a missing or duplicated shard, an interrupted shard, a shard
/// whose report lacks part of its scenes, and a case that appears twice.
MergedRun merge_shards(const std::vector<std::string>& dirs);

/// Writes DIR/report.json, DIR/report.csv and DIR/gbench.json of a merged run, each whole or not at all.
void write_merged(const MergedRun& run, const std::string& dir);

}  // namespace ab
