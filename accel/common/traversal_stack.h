// The stack of every front-to-back walk (the binary and 8-wide BVHs, the k-d trees, the octree, the BSP
// tree): entries are pushed with their entry distance, and an entry is skipped when popped only when that
// distance lies strictly beyond the current limit (the best hit so far, or tmax for any hit). That is
// DESIGN.md's pruning rule, so every walk keeps hits identical by using this one stack.
#pragma once

namespace ab {

/// A fixed-capacity stack of Items (trivially copyable, with `float entry() const`). Its storage is left
/// uninitialized: only pushed entries are read.
template <class Item, int kCapacity>
class TraversalStack {
 public:
  /// Pushes an entry (the caller's depth bound guarantees the capacity).
  [[gnu::always_inline]] void push(const Item& item) { items_[size_++] = item; }
  /// Pops the topmost entry whose entry() is not beyond limit into out, dropping the ones above it that
  /// are; false when none is left.
  [[gnu::always_inline]] bool pop(float limit, Item& out) {
    while (size_ > 0) {
      const Item& top = items_[--size_];
      if (top.entry() > limit) continue;
      out = top;
      return true;
    }
    return false;
  }
  /// True when nothing is stacked.
  bool empty() const { return size_ == 0; }

 private:
  Item items_[kCapacity];
  int size_ = 0;
};

}  // namespace ab
