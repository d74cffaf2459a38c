#include "accel/bvh/slots.h"

namespace ab {

// Root at 0, padding at 1, then sibling pairs allocated in depth-first order: a node's children pair is
// allocated when the node is reached, so a subtree's pairs are contiguous and the left child's subtree
// follows its parent's pair.
BvhBuildResult flatten_bvh_slots(const BvhSlots& slots, std::vector<uint32_t> order) {
  BvhBuildResult out;
  out.order = std::move(order);
  if (slots.size == 0) return out;
  struct Item {
    uint32_t slot, index;
  };
  const BvhNode* in = slots.slots.get();
  out.nodes.reserve(slots.size + 1);
  out.nodes.resize(2);
  out.nodes[1] = BvhNode{{kInf, kInf, kInf}, 0, {-kInf, -kInf, -kInf}, 1};  // padding, never visited
  std::vector<Item> stack{{0, 0}};
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    BvhNode node = in[it.slot];
    if (!node.is_leaf()) {
      const uint32_t pair = uint32_t(out.nodes.size());
      out.nodes.resize(pair + 2);
      stack.push_back({node.offset, pair + 1});
      stack.push_back({it.slot + 1, pair});
      node.offset = pair;
    }
    out.nodes[it.index] = node;
  }
  return out;
}

}  // namespace ab
