#include "accel/bvh/collapse.h"

#include <tbb/parallel_invoke.h>

#include <array>
#include <memory>
#include <vector>

namespace ab {

namespace {

/// A binary tree in build_bvh's layout: the children of interior node i are the pair offset, offset + 1.
struct PairedTree {
  const BvhNode* nodes;  ///< the node array

  const BvhNode& operator[](uint32_t i) const { return nodes[i]; }
  uint32_t left(uint32_t i) const { return nodes[i].offset; }
  uint32_t right(uint32_t i) const { return nodes[i].offset + 1; }
};

/// A binary tree in the builders' slots (slots.h): the children of interior slot i are i + 1 and offset.
struct SlotTree {
  const BvhNode* nodes;  ///< the slots

  const BvhNode& operator[](uint32_t i) const { return nodes[i]; }
  uint32_t left(uint32_t i) const { return i + 1; }
  uint32_t right(uint32_t i) const { return nodes[i].offset; }
};

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

/// The greedy choice of a wide node's children (Wald, Benthin and Boulos 2008, section 3): open the interior
/// child of largest area until there are eight.
template <class Tree>
class GreedyChildren {
 public:
  explicit GreedyChildren(const Tree& binary) : binary_(binary) {}

  /// Children of binary interior node b. Each child's area is computed once, when it becomes a child (a leaf
  /// counts as area -1, never opened).
  Kids children_of(uint32_t b) const {
    Kids kids;
    std::array<float, Bvh8Node::kWidth> area{};
    auto area_of = [&](uint32_t id) { return binary_[id].is_leaf() ? -1.0f : binary_[id].box().area(); };
    auto put = [&](size_t k, uint32_t id) {
      for (size_t j = kids.size(); j > k; --j) area[j] = area[j - 1];
      kids.insert(k, id);
      area[k] = area_of(id);
    };
    put(0, binary_.left(b));
    put(1, binary_.right(b));
    while (kids.size() < size_t(Bvh8Node::kWidth)) {
      int pick = -1;
      float pick_area = -1.0f;
      for (size_t k = 0; k < kids.size(); ++k)
        if (area[k] > pick_area) pick = int(k), pick_area = area[k];
      if (pick < 0) break;
      const uint32_t opened = kids[size_t(pick)];
      kids.id[size_t(pick)] = binary_.left(opened);
      area[size_t(pick)] = area_of(binary_.left(opened));
      put(size_t(pick) + 1, binary_.right(opened));
    }
    return kids;
  }

 private:
  const Tree& binary_;
};

// The SAH-optimal choice by dynamic programming over the binary tree (Ylitie, Karras and Laine 2017,
// "Efficient incoherent ray traversal on GPUs through compressed wide BVHs", section 3.1), with the binary
// tree's leaves kept as they are, so the leaves' costs are the same whatever the choice and the SAH cost to
// minimize is the traversal cost times the summed area of the wide nodes: F(n, i) is the least summed area
// of the wide nodes made from the binary subtree n as a forest of at most i lanes. For a leaf F(n, i) = 0;
// for an interior node with children l, r, D(n, j) = min over 0 < k < j of F(l, k) + F(r, j - k),
// F(n, 1) = A(n) + D(n, 8) (n becomes a wide node) and F(n, i) = min(F(n, 1), D(n, i)). F is evaluated
// bottom up by a recursion whose top levels run their two subtrees in parallel, each node's F handed to its
// parent (only the choices are kept, 9 bytes a node); the choices are replayed from the root. Over
// PairedTree or SlotTree (straight from the builder's slots, whose unused slots are never read).
template <class Tree>
class OptimalChildren {
 public:
  /// The choices over binary tree `binary` of `size` nodes or slots.
  OptimalChildren(const Tree& binary, size_t size)
      : binary_(binary),
        split_(std::make_unique_for_overwrite<Lanes<uint8_t>[]>(size)),
        open_(std::make_unique_for_overwrite<uint8_t[]>(size)) {
    evaluate(0, 0);
  }

  /// Children of binary interior node b: its subtree as the cheapest forest of at most eight lanes.
  Kids children_of(uint32_t b) const {
    Kids kids;
    forest(binary_.left(b), open_[b], kids);
    forest(binary_.right(b), kW - open_[b], kids);
    return kids;
  }

 private:
  static constexpr int kW = Bvh8Node::kWidth;
  /// Nodes this shallow evaluate their two subtrees in parallel.
  static constexpr int kParallelDepth = 10;
  /// One value per lane count i = 1..8 (at i - 1).
  template <class T>
  using Lanes = std::array<T, kW>;

  /// F(n, i) for i = 1..8 (zero for a leaf); records n's choices.
  Lanes<float> evaluate(uint32_t n, int depth) {
    if (binary_[n].is_leaf()) return Lanes<float>{};
    Lanes<float> fl, fr;
    const uint32_t l = binary_.left(n), r = binary_.right(n);
    if (depth < kParallelDepth) {
      tbb::parallel_invoke([&] { fl = evaluate(l, depth + 1); }, [&] { fr = evaluate(r, depth + 1); });
    } else {
      fl = evaluate(l, depth + 1);
      fr = evaluate(r, depth + 1);
    }
    float best[kW + 1];
    uint8_t best_k[kW + 1];
    for (int j = 2; j <= kW; ++j) {
      best[j] = kInf;
      best_k[j] = 1;  // a valid choice when every cost is infinite (areas overflow beyond about 1e19)
      for (int k = 1; k < j; ++k) {
        const float c = fl[size_t(k - 1)] + fr[size_t(j - k - 1)];
        if (c < best[j]) best[j] = c, best_k[j] = uint8_t(k);
      }
    }
    const float as_node = binary_[n].box().area() + best[kW];
    open_[n] = best_k[kW];
    Lanes<float> f;
    f[0] = as_node;
    split_[n][0] = 0;
    for (int i = 2; i <= kW; ++i) {
      const bool open = best[i] < as_node;
      f[size_t(i - 1)] = open ? best[i] : as_node;
      split_[n][size_t(i - 1)] = open ? best_k[i] : 0;
    }
    return f;
  }
  /// Appends the forest chosen for F(n, i).
  void forest(uint32_t n, int i, Kids& kids) const {
    const int k = binary_[n].is_leaf() ? 0 : split_[n][size_t(i - 1)];
    if (k == 0) return kids.insert(kids.size(), n);
    forest(binary_.left(n), k, kids);
    forest(binary_.right(n), i - k, kids);
  }

  const Tree& binary_;
  std::unique_ptr<Lanes<uint8_t>[]> split_;  ///< per node: 0 where n is one lane; else the left child's lanes
  std::unique_ptr<uint8_t[]> open_;          ///< per node: the left child's lanes when n becomes a wide node
};

/// Recursive collapse of the binary tree (PairedTree or SlotTree) into the wide array, with the children
/// chosen by Children.
template <class Tree, class Children>
class Bvh8Collapser {
 public:
  Bvh8Collapser(const Tree& binary, const Children& children, Bvh8NodeArray& wide)
      : binary_(binary), children_(children), wide_(wide) {}

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
    const Kids kids = children_.children_of(b);
    fill(w, kids);
    for (size_t k = 0; k < kids.size(); ++k) {
      if (binary_[kids[k]].is_leaf()) continue;
      const uint32_t child = uint32_t(wide_.size());
      wide_.emplace_back();
      wide_[w].child[k] = child;
      collapse(kids[k], child);
    }
  }

  const Tree& binary_;
  const Children& children_;
  Bvh8NodeArray& wide_;
};

/// The collapse of binary tree `tree` (`size` nodes or slots) by `method`.
template <class Tree>
Bvh8NodeArray collapse_tree(const Tree& tree, size_t size, BvhCollapse method) {
  Bvh8NodeArray wide;
  wide.reserve(size / 4 + 1);
  if (method == BvhCollapse::optimal && !tree[0].is_leaf()) {
    const OptimalChildren children(tree, size);
    Bvh8Collapser(tree, children, wide).run();
  } else {
    const GreedyChildren children(tree);
    Bvh8Collapser(tree, children, wide).run();
  }
  return wide;
}

}  // namespace

// Collapse after Wald, Benthin and Boulos 2008 (section 3: "pull up" the children of the largest-area
// interior child until the node is full), applied top down to the binary SAH tree; or with the children
// chosen by Ylitie, Karras and Laine 2017's dynamic programming (OptimalChildren above).
Bvh8NodeArray collapse_to_bvh8(const BvhNodeArray& binary, BvhCollapse method) {
  if (binary.empty()) return {};
  return collapse_tree(PairedTree{binary.data()}, binary.size(), method);
}

// The same straight from the slots: a slot tree and its flattened array have the same nodes and the same
// left-to-right order of children, so the wide tree is the same node for node.
Bvh8NodeArray collapse_to_bvh8(const BvhSlots& slots, BvhCollapse method) {
  if (slots.size == 0) return {};
  return collapse_tree(SlotTree{slots.slots.get()}, slots.size, method);
}

}  // namespace ab
