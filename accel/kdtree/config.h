// The configurations of the two k-d trees: each field's initializer is its default, read once from the
// parameters (Params::read) and passed typed to the builder.
#pragma once

#include <cstddef>

#include "accel/common/leaf_refs.h"
#include "accel/common/sah.h"
#include "accel/core/params.h"

namespace ab {

/// How the median builder picks a node's split axis.
enum class KdAxisRule { kLongest, kCycle };

/// Configuration of kdtree-median.
struct KdMedianConfig {
  size_t leaf_size = 4;                    ///< a node with at most this many primitives is a leaf
  KdAxisRule axis = KdAxisRule::kLongest;  ///< longest axis of the node box, or x, y, z in turn
  double straddle_limit =
      0.75;           ///< a node whose split would put more than this share on both sides is a leaf
  int max_depth = 0;  ///< depth limit; 0: auto_depth_limit of the primitive count
  LeafCopies leaf_copies = LeafCopies::kAuto;  ///< copy triangles into leaf order (LeafRefs)
  int bad_refines = 3;  ///< a node whose split is the bad_refines-th bad one on its path is a leaf (pbrt-v3)
  /// pbrt-v3's cost model of the bad-refine rule (KdTreeAccel: traversalCost 1, isectCost 80).
  SahCosts costs{.traversal = 1.0f, .intersection = 80.0f, .empty_bonus = 0.0f};
  double ref_budget =
      32.0;  ///< the leaves hold at most this many references per primitive (build_with_budget)

  /// Reads every field from params.
  static KdMedianConfig read(Params& params) {
    KdMedianConfig c;
    params.read("leaf_size", c.leaf_size, 1, 1 << 20);
    params.read("axis", c.axis, {{"longest", KdAxisRule::kLongest}, {"cycle", KdAxisRule::kCycle}});
    params.read("straddle_limit", c.straddle_limit, 0.0, 1.0);
    params.read("max_depth", c.max_depth, 0, 100);
    params.read("leaf_copies", c.leaf_copies, kLeafCopiesWords);
    params.read("bad_refines", c.bad_refines, 0, 1000);
    params.read("traversal_cost", c.costs.traversal, 1e-3, 1e6);
    params.read("intersection_cost", c.costs.intersection, 1e-3, 1e6);
    params.read("ref_budget", c.ref_budget, 1.0, 1e6);
    return c;
  }
};

/// Configuration of kdtree-sah.
struct KdSahConfig {
  /// Wald and Havran 2006's cost model: Ct, Ci and the empty-space bonus (1 - lambda).
  SahCosts costs{.traversal = 1.0f, .intersection = 1.5f, .empty_bonus = 0.2f};
  int max_depth = 0;                           ///< depth limit; 0: auto_depth_limit of the primitive count
  LeafCopies leaf_copies = LeafCopies::kAuto;  ///< copy triangles into leaf order (LeafRefs)
  /// A node the cost model makes a leaf splits at its cheapest plane anyway while it holds more than this
  /// many primitives and each child fewer (KdSahBuilder; 0: never).
  size_t max_leaf = 64;
  double ref_budget =
      32.0;  ///< the leaves hold at most this many references per primitive (build_with_budget)
  /// Nodes holding more primitives than this choose their plane from bins (sah_bins.h), the others by the
  /// exact event sweep (sah_sweep.h).
  size_t exact_max = 8192;

  /// Reads every field from params.
  static KdSahConfig read(Params& params) {
    KdSahConfig c;
    params.read("traversal_cost", c.costs.traversal, 1e-3, 1e6);
    params.read("intersection_cost", c.costs.intersection, 1e-3, 1e6);
    params.read("empty_bonus", c.costs.empty_bonus, 0.0, 0.99);
    params.read("max_depth", c.max_depth, 0, 100);
    params.read("leaf_copies", c.leaf_copies, kLeafCopiesWords);
    params.read("max_leaf", c.max_leaf, 0, size_t(1) << 30);
    params.read("ref_budget", c.ref_budget, 1.0, 1e6);
    params.read("exact_max", c.exact_max, 0, size_t(1) << 32);
    return c;
  }
};

}  // namespace ab
