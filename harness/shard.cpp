#include "harness/shard.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numeric>

#include "accel/core/error.h"
#include "harness/hitfile.h"

namespace ab {

namespace {

using nlohmann::json;

/// A whole decimal number in [1, 1000000], or 0 when `s` is not one.
int parse_positive(const std::string& s) {
  int v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size() || v < 1 || v > 1000000) return 0;
  return v;
}

/// Bytes of a file, 0 when it cannot be read.
double file_bytes(const std::string& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  return ec ? 0.0 : double(size);
}

double scene_triangles(const SceneSpec& scene) {
  if (scene.source == SceneSpec::Source::kGenerator) return double(scene.triangles);
  return std::max(1.0, file_bytes(scene.path) / 50.0);  // OBJ/PLY text: about 50 bytes a triangle
}

double ray_count(const RaySpec& rays) {
  if (rays.path.empty()) return double(rays.count);
  return std::max(1.0, (file_bytes(rays.path) - 16.0) / double(ray_record_bytes(rays.path)));
}

}  // namespace

ShardSpec parse_shard(const std::string& text) {
  const auto slash = text.find('/');
  const int k = slash == std::string::npos ? 0 : parse_positive(text.substr(0, slash));
  const int n = slash == std::string::npos ? 0 : parse_positive(text.substr(slash + 1));
  if (k == 0 || n == 0)
    throw InputError("--shard: expected K/N with whole numbers 1 <= K <= N, got '" + text + "'");
  if (k > n) throw InputError("--shard: K must be at most N, got '" + text + "'");
  return {k, n};
}

double scene_cost(const Suite& suite, const SceneSpec& scene) {
  const double tri = scene_triangles(scene);
  const double depth = std::log2(tri + 2.0);
  double cost = 0.0;
  for (const AccelSpec& a : suite.accelerators) {
    cost += double(suite.build_repetitions) * tri * depth;
    for (const RaySpec& r : suite.rays) {
      const double timed = double(1 + suite.warmup + suite.repetitions) * double(suite.threads.size()) *
                           (r.any_hit ? 2.0 : 1.0);
      const double passes = 1.0 + timed;  // the counting pass and the timed ones
      cost += ray_count(r) * passes * (a.name == "brute" ? tri : depth);
    }
  }
  for (const RaySpec& r : suite.rays) {  // the references: brute force on the checked rays, Embree on all
    const double checked =
        suite.verify.brute_rays == 0 ? ray_count(r) : std::min(ray_count(r), double(suite.verify.brute_rays));
    cost += checked * tri + 2.0 * ray_count(r) * depth;
  }
  return cost;
}

std::vector<std::vector<size_t>> partition_scenes(const Suite& suite, int count) {
  if (count < 1) throw InputError("--shard: N must be at least 1");
  std::vector<double> cost(suite.scenes.size());
  for (size_t i = 0; i < cost.size(); ++i) cost[i] = scene_cost(suite, suite.scenes[i]);
  std::vector<size_t> order(cost.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return cost[a] > cost[b]; });
  std::vector<std::vector<size_t>> shards(static_cast<size_t>(count));
  std::vector<double> load(static_cast<size_t>(count), 0.0);
  for (size_t scene : order) {
    const size_t lightest = size_t(std::min_element(load.begin(), load.end()) - load.begin());
    shards[lightest].push_back(scene);
    load[lightest] += cost[scene];
  }
  for (auto& s : shards) std::sort(s.begin(), s.end());
  return shards;
}

Suite shard_suite(const Suite& suite, const ShardSpec& shard) {
  const auto shards = partition_scenes(suite, shard.count);
  Suite part = suite;
  part.scenes.clear();
  for (size_t i : shards[size_t(shard.index - 1)]) part.scenes.push_back(suite.scenes[i]);
  return part;
}

json shard_json(const Suite& suite, const ShardSpec& shard) {
  const auto shards = partition_scenes(suite, shard.count);
  json partition = json::array();
  for (const auto& s : shards) {
    json entry = {{"scenes", json::array()}, {"estimated_cost", 0.0}};
    for (size_t i : s) {
      entry["scenes"].push_back(suite.scenes[i].label);
      entry["estimated_cost"] = entry["estimated_cost"].get<double>() + scene_cost(suite, suite.scenes[i]);
    }
    partition.push_back(entry);
  }
  json suite_scenes = json::array();
  for (const SceneSpec& s : suite.scenes) suite_scenes.push_back(s.label);
  const json& own = partition[size_t(shard.index - 1)];
  return {{"index", shard.index},         {"count", shard.count},
          {"scenes", own["scenes"]},      {"estimated_cost", own["estimated_cost"]},
          {"suite_scenes", suite_scenes}, {"partition", partition}};
}

// Fowler-Noll-Vo FNV-1a, 64 bits: stable across machines and compilers, which std::hash is not.
std::string suite_hash(const nlohmann::json& suite_json) {
  uint64_t h = 14695981039346656037ull;
  for (const unsigned char c : suite_json.dump()) {
    h ^= c;
    h *= 1099511628211ull;
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, "fnv1a64:%016llx", static_cast<unsigned long long>(h));
  return buf;
}

}  // namespace ab
