// The configuration of each BVH structure (bvh-median, bvh-sah, bvh-sweep): one struct per structure whose
// field initializers are its defaults, read once from the parameters (read) and passed typed to the
// structure and its builder, as pbrt-v4's Create() does. What two structures share sits in a base struct, so
// every default is written once.
#pragma once

#include <cstddef>
#include <string>

#include "accel/bvh/node.h"
#include "accel/common/sah.h"
#include "accel/core/params.h"

namespace ab {

/// What every BVH's Config holds: the depth limit and the build's parallelism.
struct BvhTreeConfig {
  int max_depth = 64;                ///< a node at this depth becomes a leaf (parameter max_depth)
  size_t parallel_threshold = 4096;  ///< subtrees at least this large build their children in parallel (not a
                                     ///< parameter: the tree is the same for any value)

  /// Reads max_depth.
  void read_tree(Params& params) { params.read("max_depth", max_depth, 1, kBvhMaxDepth); }
};

/// Reads a node width in place: 2 (the binary tree) or 8 (collapsed into 8-wide nodes).
inline void read_bvh_width(Params& params, int& width) {
  params.read("width", width, 2, 8);
  if (width != 2 && width != 8)
    throw ParamError("parameter 'width': " + std::to_string(width) + " is not 2 or 8");
}

/// How the binary tree is collapsed into the 8-wide one (collapse.h): greedy (Wald, Benthin and Boulos 2008)
/// or SAH-optimal (Ylitie, Karras and Laine 2017).
enum class BvhCollapse { greedy, optimal };

/// Reads the collapse method in place (parameter collapse: greedy or optimal).
inline void read_bvh_collapse(Params& params, BvhCollapse& collapse) {
  params.read("collapse", collapse, {{"greedy", BvhCollapse::greedy}, {"optimal", BvhCollapse::optimal}});
}

/// bvh-median: the object median of the centroids on the longest axis.
struct BvhMedianConfig : BvhTreeConfig {
  int leaf_size = 4;  ///< a node of at most this many primitives becomes a leaf
  int width = 2;      ///< node width, 2 or 8

  /// Reads every field (leaf_size, max_depth, width).
  static BvhMedianConfig read(Params& params) {
    BvhMedianConfig c;
    params.read("leaf_size", c.leaf_size, 1, 1 << 20);
    c.read_tree(params);
    read_bvh_width(params, c.width);
    return c;
  }
};

/// What both SAH builders share: when a node becomes a leaf, and the costs that price every split.
struct BvhSahTreeConfig : BvhTreeConfig {
  int max_leaf_size = 8;  ///< a node above this size is always split
  SahCosts costs;         ///< traversal and intersection costs (1 and 1); block is set by the structure

  /// Reads max_leaf_size, traversal_cost, intersection_cost and max_depth.
  void read_sah_tree(Params& params) {
    params.read("max_leaf_size", max_leaf_size, 1, 1 << 20);
    params.read("traversal_cost", costs.traversal, 0.0, 1e6);
    params.read("intersection_cost", costs.intersection, 1e-6, 1e6);
    read_tree(params);
  }
};

/// bvh-sah: binned SAH (Wald 2007), 8-wide by default.
struct BvhSahConfig : BvhSahTreeConfig {
  int bins = 32;  ///< bins per axis
  int width = 8;  ///< node width, 2 or 8
  /// How width 8 is made from the binary tree: optimal (greedy until issue 12's tenth step, when the optimal
  /// collapse ran straight from the slots and in parallel: as fast to build, traversal +2-3%).
  BvhCollapse collapse = BvhCollapse::optimal;

  /// Reads every field.
  static BvhSahConfig read(Params& params) {
    BvhSahConfig c;
    c.read_sah_tree(params);
    params.read("bins", c.bins, 2, 256);
    read_bvh_width(params, c.width);
    read_bvh_collapse(params, c.collapse);
    return c;
  }
};

/// bvh-sweep: full-sweep SAH (MacDonald and Booth 1990), the quality reference.
struct BvhSweepConfig : BvhSahTreeConfig {
  int width = 2;  ///< node width, 2 or 8

  /// Reads every field.
  static BvhSweepConfig read(Params& params) {
    BvhSweepConfig c;
    c.read_sah_tree(params);
    read_bvh_width(params, c.width);
    return c;
  }
};

}  // namespace ab
