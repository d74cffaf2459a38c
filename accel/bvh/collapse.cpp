#include "accel/bvh/wide.h"

#include "accel/common/sah.h"

#include <algorithm>

namespace ab {

namespace {

/// Recursive collapse of binary node `b` into the already allocated wide node `w`.
class Bvh8Collapser {
 public:
  Bvh8Collapser(const BvhNodeArray& binary, Bvh8NodeArray& wide)
      : binary_(binary), wide_(wide), sah_(binary[0].box().area()) {}

  /// Collapses the whole tree (the binary root becomes the wide root's children, or its only leaf).
  void run() {
    wide_.emplace_back();
    if (binary_[0].is_leaf()) {
      fill(0, {0u});
      add_leaf(0, 1);
    } else {
      sah_.add_interior(binary_[0].box().area());
      collapse(0, 0, 1);
    }
  }
  /// Mean depth of the leaves, deepest leaf and the SAH cost (costs 1 and 1) of the wide tree.
  double mean_depth() const { return leaves_ ? depth_sum_ / double(leaves_) : 0.0; }
  uint32_t max_depth() const { return max_depth_; }
  double sah_cost() const { return sah_.cost(); }
  uint64_t used_lanes() const { return used_lanes_; }

 private:
  /// Children of binary interior node b: open the interior child of largest area until there are 8.
  std::vector<uint32_t> children_of(uint32_t b) const {
    std::vector<uint32_t> kids{binary_[b].offset, binary_[b].offset + 1};
    while (kids.size() < size_t(Bvh8Node::kWidth)) {
      int pick = -1;
      float pick_area = -1.0f;
      for (size_t k = 0; k < kids.size(); ++k) {
        const BvhNode& n = binary_[kids[k]];
        if (!n.is_leaf() && n.box().area() > pick_area) pick = int(k), pick_area = n.box().area();
      }
      if (pick < 0) break;
      const uint32_t opened = kids[size_t(pick)];
      kids[size_t(pick)] = binary_[opened].offset;
      kids.insert(kids.begin() + pick + 1, binary_[opened].offset + 1);
    }
    return kids;
  }

  /// Writes the boxes and references of `kids` into wide node w (unused lanes stay empty).
  void fill(uint32_t w, const std::vector<uint32_t>& kids) {
    Bvh8Node& node = wide_[w];
    for (int k = 0; k < Bvh8Node::kWidth; ++k) {
      const bool used = size_t(k) < kids.size();
      const BvhNode* n = used ? &binary_[kids[size_t(k)]] : nullptr;
      for (int a = 0; a < 3; ++a) {
        node.bounds[a][k] = used ? n->lo[a] : kInf;
        node.bounds[3 + a][k] = used ? n->hi[a] : -kInf;
      }
      node.child[k] = used && n->is_leaf() ? n->offset : 0;
      node.count[k] = used && n->is_leaf() ? n->count : 0;
    }
    used_lanes_ += kids.size();
  }

  void add_leaf(uint32_t b, uint32_t depth) {
    sah_.add_leaf(binary_[b].box().area(), binary_[b].count);
    ++leaves_;
    depth_sum_ += depth;
    max_depth_ = std::max(max_depth_, depth);
  }

  /// Fills wide node w from binary interior node b; interior children get consecutive new wide nodes.
  void collapse(uint32_t b, uint32_t w, uint32_t depth) {
    const std::vector<uint32_t> kids = children_of(b);
    fill(w, kids);
    for (size_t k = 0; k < kids.size(); ++k) {
      if (binary_[kids[k]].is_leaf()) {
        add_leaf(kids[k], depth);
        continue;
      }
      const uint32_t child = uint32_t(wide_.size());
      wide_.emplace_back();
      wide_[w].child[k] = child;
      sah_.add_interior(binary_[kids[k]].box().area());
      collapse(kids[k], child, depth + 1);
    }
  }

  const BvhNodeArray& binary_;
  Bvh8NodeArray& wide_;
  SahTreeCost sah_;
  uint64_t leaves_ = 0, used_lanes_ = 0;
  double depth_sum_ = 0.0;
  uint32_t max_depth_ = 0;
};

}  // namespace

// Collapse after Wald, Benthin and Boulos 2008 (section 3: "pull up" the children of the largest-area
// interior child until the node is full), applied top down to the binary SAH tree.
Bvh8NodeArray collapse_to_bvh8(const BvhNodeArray& binary, BuildStats& stats) {
  Bvh8NodeArray wide;
  if (binary.empty()) return wide;
  wide.reserve(binary.size() / 4 + 1);
  Bvh8Collapser collapser(binary, wide);
  collapser.run();
  stats.extra["binary_nodes"] = stats.nodes;
  stats.extra["binary_max_depth"] = stats.max_depth;
  stats.extra["wide_sah_cost"] = collapser.sah_cost();
  stats.extra["mean_children"] = double(collapser.used_lanes()) / double(wide.size());
  stats.nodes = wide.size() + stats.leaves;
  stats.max_depth = collapser.max_depth();
  stats.mean_leaf_depth = collapser.mean_depth();
  return wide;
}

}  // namespace ab
