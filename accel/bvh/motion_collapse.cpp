// The collapse of the binary motion BVH into 8-wide motion nodes (motion_node8.h).
#include <array>

#include "accel/bvh/motion_node8.h"

namespace ab {

namespace {

/// The binary nodes that become one wide node's lanes.
struct MotionKids {
  std::array<uint32_t, MotionBvh8Node::kWidth> id{};
  int n = 0;
};

/// Greedy choice of a wide node's lanes (Wald, Benthin and Boulos 2008, section 3): the two children of b,
/// then the interior lane of largest hull area opened into its two children until there are eight.
MotionKids greedy_lanes(const std::vector<MotionBvhNode>& binary, uint32_t b) {
  MotionKids kids;
  kids.id[0] = binary[b].offset, kids.id[1] = binary[b].offset + 1, kids.n = 2;
  while (kids.n < MotionBvh8Node::kWidth) {
    int pick = -1;
    float pick_area = -1.0f;
    for (int k = 0; k < kids.n; ++k) {
      const MotionBvhNode& n = binary[kids.id[size_t(k)]];
      if (!n.is_leaf() && n.hull().area() > pick_area) pick = k, pick_area = n.hull().area();
    }
    if (pick < 0) break;
    const uint32_t opened = kids.id[size_t(pick)];
    for (int j = kids.n++; j > pick + 1; --j) kids.id[size_t(j)] = kids.id[size_t(j - 1)];
    kids.id[size_t(pick)] = binary[opened].offset;
    kids.id[size_t(pick + 1)] = binary[opened].offset + 1;
  }
  return kids;
}

/// Fills wide node w from binary interior node b; interior lanes get consecutive new wide nodes.
void collapse_node(const std::vector<MotionBvhNode>& binary, uint32_t b, uint32_t w,
                   MotionBvh8NodeArray& wide) {
  const MotionKids kids = greedy_lanes(binary, b);
  for (int k = 0; k < kids.n; ++k) wide[w].set(k, binary[kids.id[size_t(k)]]);
  for (int k = 0; k < kids.n; ++k) {
    if (binary[kids.id[size_t(k)]].is_leaf()) continue;
    const auto child = uint32_t(wide.size());
    wide.emplace_back();
    wide[w].child[k] = child;
    collapse_node(binary, kids.id[size_t(k)], child, wide);
  }
}

}  // namespace

MotionBvh8NodeArray collapse_motion_bvh(const std::vector<MotionBvhNode>& binary) {
  MotionBvh8NodeArray wide;
  wide.reserve(binary.size() / 4 + 1);
  wide.emplace_back();
  if (binary[0].is_leaf())
    wide[0].set(0, binary[0]);  // the root leaf as the wide root's only lane
  else
    collapse_node(binary, 0, 0, wide);
  return wide;
}

}  // namespace ab
