// Build statistics and per-ray traversal counters, shared by every structure.
#pragma once

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

namespace ab {

/// Per-ray work counters, filled only by the counting pass (never on the timed path).
struct RayCounters {
  uint64_t nodes = 0;          ///< interior nodes, leaves or cells visited
  uint64_t leaves = 0;         ///< leaves or non-empty cells visited
  uint64_t prims = 0;          ///< primitive (triangle or instance) intersection tests
  uint64_t mailbox_skips = 0;  ///< tests skipped because the primitive was already tested for this ray

  /// Adds another ray's counts.
  RayCounters& operator+=(const RayCounters& o) {
    nodes += o.nodes;
    leaves += o.leaves;
    prims += o.prims;
    mailbox_skips += o.mailbox_skips;
    return *this;
  }
};

/// What a build produced. Fields that do not apply to a structure stay zero.
struct BuildStats {
  double build_seconds = 0.0;    ///< wall time of build() alone
  uint64_t primitives = 0;       ///< triangles (or instances) it was built over
  uint64_t nodes = 0;            ///< all nodes (or cells)
  uint64_t leaves = 0;           ///< leaves (or cells)
  uint64_t empty_leaves = 0;     ///< leaves or cells holding no primitive
  uint32_t max_depth = 0;        ///< deepest leaf
  double mean_leaf_depth = 0.0;  ///< mean depth over leaves
  uint64_t references = 0;       ///< primitive references stored in leaves or cells
  uint64_t bytes = 0;            ///< memory of the structure itself (not the input mesh)
  uint64_t peak_bytes = 0;       ///< the build's high-water mark of heap memory above its start (memory.h)
  double sah_cost = 0.0;         ///< SAH cost, costs 1 and 1, normalized by the root's area (0: not computed)
  double epo = -1.0;  ///< end-point overlap (accel/common/epo.h), costs 1 and 1 (< 0: not computed)
  std::map<uint32_t, uint64_t> leaf_size_histogram;  ///< primitives per leaf -> number of leaves
  nlohmann::json extra = nlohmann::json::object();   ///< structure-specific figures (grid resolution, ...)

  /// Primitive references per primitive (1 for structures that never duplicate).
  double references_per_primitive() const {
    return primitives ? double(references) / double(primitives) : 0.0;
  }
  /// Bytes per primitive.
  double bytes_per_primitive() const { return primitives ? double(bytes) / double(primitives) : 0.0; }
  /// Peak build bytes per primitive.
  double peak_bytes_per_primitive() const {
    return primitives ? double(peak_bytes) / double(primitives) : 0.0;
  }
  /// Adds one leaf of `size` primitives at `depth` to the counts (nodes are counted by the caller).
  void add_leaf(uint32_t size, uint32_t depth) {
    ++leaves;
    references += size;
    if (size == 0) ++empty_leaves;
    ++leaf_size_histogram[size];
    if (depth > max_depth) max_depth = depth;
    mean_leaf_depth += (depth - mean_leaf_depth) / double(leaves);
  }
};

/// The statistics as JSON (the harness and trace --stats write this).
nlohmann::json to_json(const BuildStats& s);
/// The counters as JSON, averaged over `rays`.
nlohmann::json to_json(const RayCounters& c, uint64_t rays);

}  // namespace ab
