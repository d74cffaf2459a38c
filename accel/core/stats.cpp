#include "accel/core/stats.h"

namespace ab {

nlohmann::json to_json(const BuildStats& s) {
  nlohmann::json hist = nlohmann::json::object();
  for (const auto& [size, count] : s.leaf_size_histogram) hist[std::to_string(size)] = count;
  return {{"build_seconds", s.build_seconds},
          {"primitives", s.primitives},
          {"nodes", s.nodes},
          {"leaves", s.leaves},
          {"empty_leaves", s.empty_leaves},
          {"max_depth", s.max_depth},
          {"mean_leaf_depth", s.mean_leaf_depth},
          {"references", s.references},
          {"references_per_primitive", s.references_per_primitive()},
          {"bytes", s.bytes},
          {"bytes_per_primitive", s.bytes_per_primitive()},
          {"peak_bytes", s.peak_bytes},
          {"peak_bytes_per_primitive", s.peak_bytes_per_primitive()},
          {"sah_cost", s.sah_cost},
          {"epo", s.epo >= 0 ? nlohmann::json(s.epo) : nlohmann::json()},
          {"leaf_size_histogram", hist},
          {"extra", s.extra}};
}

nlohmann::json to_json(const RayCounters& c, uint64_t rays) {
  const double n = rays ? double(rays) : 1.0;
  return {{"nodes_per_ray", double(c.nodes) / n},
          {"leaves_per_ray", double(c.leaves) / n},
          {"prims_per_ray", double(c.prims) / n},
          {"mailbox_skips_per_ray", double(c.mailbox_skips) / n}};
}

}  // namespace ab
