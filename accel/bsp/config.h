// The BSP tree's configuration: each field's initializer is its default, read once from the parameters.
#pragma once

#include <cstddef>
#include <string>

#include "accel/common/leaf_refs.h"
#include "accel/common/sah.h"
#include "accel/core/params.h"

namespace ab {

/// Configuration of the BSP tree.
struct BspConfig {
  /// The cost model over the cell's surface area. Intersection 1.8 (measured on slivers: fewer triangles per
  /// ray at about the same nodes); a small empty bonus, as many directions offer many corner cuts, each one
  /// more level.
  SahCosts costs{.traversal = 1.0f, .intersection = 1.8f, .empty_bonus = 0.05f};
  int bins = 16;          ///< plane positions per fixed direction: bins - 1
  int autopartition = 8;  ///< triangles whose supporting planes are tried per node
  /// Fixed directions tried by nodes of at most oblique_max primitives: 3, 7, 9 or 13 (bsp_direction_set).
  /// 9, the axes and the face diagonals (13 until issue 11: the 100k sphereflake's build 0.82x of the cpu
  /// with 31.0 triangle tests per ray on 20k `needles` instead of 29.9, about the same on the sphereflake;
  /// 7 tested 32.6 there, docs/structures.md).
  int directions = 9;
  /// Nodes of more primitives than this try only the three axes' binned planes (no diagonals, no
  /// autopartition), so their cells stay boxes (BspBuilder::find_plane; 0: every node tries all). 32 (1024
  /// until issue 11: the 100k sphereflake's build 0.69x of the cpu, the same triangle tests per ray, 7%
  /// more nodes per ray; docs/structures.md).
  size_t oblique_max = 32;
  int max_depth = 0;                           ///< depth limit; 0: auto_depth_limit of the primitive count
  LeafCopies leaf_copies = LeafCopies::kAuto;  ///< copy triangles into leaf order (LeafRefs)
  double ref_budget =
      32.0;  ///< the leaves hold at most this many references per primitive (build_with_budget)
  /// A node of more than 64 primitives whose path holds bad_refines - 1 shaves considers no more
  /// (BspBuilder::is_shave; pbrt-v3's count; 0: shaves always allowed).
  int bad_refines = 3;
  /// A node the cost model makes a leaf splits at its cheapest plane anyway while it holds more than this
  /// many primitives and each child fewer (as kdtree-sah; 0: never).
  size_t max_leaf = 64;
  /// A split below the leaf's cost whose larger child keeps at most this share of the cell's area is no
  /// shave (BspBuilder::is_shave: it shrinks the cell, as at a fan's centre; 0: every such split is one).
  /// 0.75 (20k `fan`: 2.7 triangle tests per primary ray instead of 512; `large` 74 instead of 262; the
  /// ordinary generators' trees unchanged).
  float shave_area = 0.75f;
  /// A node of at most max_leaf primitives splits only when the split lowers the tree's expected cost per
  /// ray by at least min_gain / N, N the tree's primitives (BspBuilder::pays; 0: the SAH alone). 1 (20k
  /// `needles`: 0.6 of the nodes and 0.75 of the build's cpu; the 100k sphereflake 0.36 and 0.5, with a third
  /// more triangle tests per ray and 1% fewer nodes per ray).
  float min_gain = 1.0f;
  /// The budgeted second attempt takes the first attempt's decisions (BspBuilder::memoized_decision; the
  /// same tree either way: off only in tests, not a parameter).
  bool reuse_decisions = true;

  /// Reads every field from params.
  static BspConfig read(Params& params) {
    BspConfig c;
    params.read("traversal_cost", c.costs.traversal, 1e-3, 1e6);
    params.read("intersection_cost", c.costs.intersection, 1e-3, 1e6);
    params.read("empty_bonus", c.costs.empty_bonus, 0.0, 0.99);
    params.read("bins", c.bins, 2, 256);
    params.read("autopartition", c.autopartition, 0, 1024);
    params.read("directions", c.directions, 3, 13);
    if (c.directions != 3 && c.directions != 7 && c.directions != 9 && c.directions != 13)
      throw ParamError("parameter 'directions': " + std::to_string(c.directions) + " is not 3, 7, 9 or 13");
    params.read("oblique_max", c.oblique_max, 0, size_t(1) << 30);
    params.read("max_depth", c.max_depth, 0, 100);
    params.read("leaf_copies", c.leaf_copies, kLeafCopiesWords);
    params.read("ref_budget", c.ref_budget, 1.0, 1e6);
    params.read("bad_refines", c.bad_refines, 0, 1000);
    params.read("max_leaf", c.max_leaf, 0, size_t(1) << 30);
    params.read("shave_area", c.shave_area, 0.0, 1.0);
    params.read("min_gain", c.min_gain, 0.0, 1e6);
    return c;
  }
};

}  // namespace ab
