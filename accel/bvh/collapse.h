// The collapse of the binary BVH into the 8-wide one (collapse.cpp).
#pragma once

#include "accel/bvh/config.h"
#include "accel/bvh/node.h"
#include "accel/bvh/node8.h"
#include "accel/bvh/slots.h"

namespace ab {

/// Collapses a binary BVH (build_bvh's layout, not empty) into an 8-wide one. Greedy: each wide node takes a
/// binary node's two children and keeps opening the interior child of largest surface area until it has
/// eight children or only leaves. Optimal: the children minimize the SAH cost of the wide tree (with the
/// leaves fixed, the summed area of the wide nodes) over every way of opening the binary tree (dynamic
/// programming). Leaves keep their primitive ranges. Node 0 is the root; when the binary root is a leaf, the
/// wide root holds it as its only lane.
Bvh8NodeArray collapse_to_bvh8(const BvhNodeArray& binary, BvhCollapse method = BvhCollapse::greedy);

/// The same collapse of a binary tree still in its builder's slots (slots.h; root at slot 0), without
/// flattening it first: the same wide tree as flattening and then collapsing.
Bvh8NodeArray collapse_to_bvh8(const BvhSlots& slots, BvhCollapse method = BvhCollapse::greedy);

}  // namespace ab
