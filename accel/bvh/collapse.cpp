#include "accel/bvh/collapse.h"

#include <array>
#include <vector>

namespace ab {

namespace {

/// The binary nodes that become one wide node's children (at most eight, no allocation).
struct Kids {
  std::array<uint32_t, Bvh8Node::kWidth> id;
  size_t n = 0;

  size_t size() const { return n; }
  uint32_t operator[](size_t k) const { return id[k]; }
  /// Puts b at position k, shifting the ones from k on (n < 8).
  void insert(size_t k, uint32_t b) {
    for (size_t j = n++; j > k; --j) id[j] = id[j - 1];
    id[k] = b;
  }
};

/// Recursive collapse of the binary tree into the wide array.
class Bvh8Collapser {
 public:
  Bvh8Collapser(const BvhNodeArray& binary, Bvh8NodeArray& wide) : binary_(binary), wide_(wide) {}

  /// Collapses the whole tree (the binary root becomes the wide root's children, or its only leaf).
  void run() {
    wide_.emplace_back();
    if (binary_[0].is_leaf()) {
      Kids root;
      root.insert(0, 0);
      fill(0, root);
    } else {
      collapse(0, 0);
    }
  }

 private:
  /// Children of binary interior node b: open the interior child of largest area until there are 8.
  Kids children_of(uint32_t b) const {
    Kids kids;
    kids.insert(0, binary_[b].offset);
    kids.insert(1, binary_[b].offset + 1);
    while (kids.size() < size_t(Bvh8Node::kWidth)) {
      int pick = -1;
      float pick_area = -1.0f;
      for (size_t k = 0; k < kids.size(); ++k) {
        const BvhNode& n = binary_[kids[k]];
        if (!n.is_leaf() && n.box().area() > pick_area) pick = int(k), pick_area = n.box().area();
      }
      if (pick < 0) break;
      const uint32_t opened = kids[size_t(pick)];
      kids.id[size_t(pick)] = binary_[opened].offset;
      kids.insert(size_t(pick) + 1, binary_[opened].offset + 1);
    }
    return kids;
  }

  /// Writes the boxes and references of `kids` into wide node w (unused lanes stay empty).
  void fill(uint32_t w, const Kids& kids) {
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
  }

  /// Fills wide node w from binary interior node b; interior children get consecutive new wide nodes.
  void collapse(uint32_t b, uint32_t w) {
    const Kids kids = children_of(b);
    fill(w, kids);
    for (size_t k = 0; k < kids.size(); ++k) {
      if (binary_[kids[k]].is_leaf()) continue;
      const uint32_t child = uint32_t(wide_.size());
      wide_.emplace_back();
      wide_[w].child[k] = child;
      collapse(kids[k], child);
    }
  }

  const BvhNodeArray& binary_;
  Bvh8NodeArray& wide_;
};

}  // namespace

// Collapse after Wald, Benthin and Boulos 2008 (section 3: "pull up" the children of the largest-area
// interior child until the node is full), applied top down to the binary SAH tree.
Bvh8NodeArray collapse_to_bvh8(const BvhNodeArray& binary) {
  Bvh8NodeArray wide;
  if (binary.empty()) return wide;
  wide.reserve(binary.size() / 4 + 1);
  Bvh8Collapser(binary, wide).run();
  return wide;
}

}  // namespace ab
