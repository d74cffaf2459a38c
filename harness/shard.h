// Sharding a suite (`accelbench run SUITE --shard K/N`): the suite's scenes are split into N parts that run
// anywhere, each in its own process. The unit is the scene with all its configurations, ray sets, thread
// counts and its Embree timing, so every ratio to Embree is still measured in one process on one machine.
// The partition is a pure function of the suite (and of the sizes of its mesh and scene files): every shard
// computes the same one, and `accelbench merge` (harness/merge.h) checks that it did.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "harness/suite.h"

namespace ab {

/// Shard K of N (1 <= K <= N).
struct ShardSpec {
  int index = 1;  ///< K, 1-based
  int count = 1;  ///< N
};

/// Parses "K/N" (the value of --shard); throws InputError "--shard: ..." when malformed or K is outside 1..N.
ShardSpec parse_shard(const std::string& text);

/// The estimated work of one scene of the suite, in triangle-ray steps: every configuration's builds
/// (triangles x build repetitions) and traversals (rays x passes x log2 of the triangles), the brute-force
/// reference (checked rays x triangles) and brute force where the suite times it (rays x passes x
/// triangles). Generated scenes count their requested triangles; mesh and scene files are estimated from
/// their size in bytes (about 50 bytes a triangle).
double scene_cost(const Suite& suite, const SceneSpec& scene);

/// The scenes of every shard (indices into suite.scenes, each list in suite order): longest processing time
/// first (Graham 1969) over scene_cost, the heaviest scene first (ties: the earlier scene), each to the
/// least loaded shard (ties: the lower shard). So the N heaviest scenes land in N different shards.
std::vector<std::vector<size_t>> partition_scenes(const Suite& suite, int count);

/// The suite restricted to the scenes of one shard (everything else unchanged, the suite's JSON included).
Suite shard_suite(const Suite& suite, const ShardSpec& shard);

/// What a shard's report records under "shard": index, count, its scenes and estimated cost, and the whole
/// partition (every shard's scene labels and costs) that merge checks the shards agree on.
nlohmann::json shard_json(const Suite& suite, const ShardSpec& shard);

/// A stable hash of the suite as given ("fnv1a64:" and 16 hex digits of its canonical JSON), recorded in
/// every report so that merge can tell the shards of one suite from those of another.
std::string suite_hash(const nlohmann::json& suite_json);

}  // namespace ab
