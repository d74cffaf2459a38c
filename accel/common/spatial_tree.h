// The compact k-d tree node (8 bytes, as in pbrt: Pharr, Jakob and Humphreys, "Physically Based Rendering",
// section 4.4), the flat node/primitive-index buffers every k-d builder writes, and the conservative
// insertion helpers shared by the k-d builders.
#pragma once

#include "accel/core/accelerator.h"
#include "accel/core/error.h"
#include "accel/core/aabb.h"
#include "accel/core/params.h"
#include "accel/core/primitives.h"
#include "accel/core/stats.h"
#include "accel/core/triangle.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <type_traits>
#include <vector>

namespace ab {

/// One k-d tree node: an interior node (axis, split coordinate, index of the above child, and a flag per
/// child that is an empty leaf; the below child, when not empty, follows it directly) or a leaf (offset and
/// count of its primitive indices). Empty children are flags rather than nodes (drop_empty_leaves), so the
/// traversal never visits or stacks them.
class KdNode {
 public:
  /// A leaf of `count` primitive indices starting at `first`.
  static KdNode leaf(uint32_t first, uint32_t count) { return KdNode(first, (count << 2) | 3u); }
  /// An interior node splitting `axis` at `split`; the above child is node `above`; a child flagged
  /// empty has no node.
  static KdNode interior(int axis, float split, uint32_t above, bool below_empty = false, bool above_empty = false) {
    return KdNode(std::bit_cast<uint32_t>(split),
                  (above << 4) | (uint32_t(above_empty) << 3) | (uint32_t(below_empty) << 2) | uint32_t(axis));
  }

  /// True for a leaf.
  bool is_leaf() const { return (bits_ & 3u) == 3u; }
  /// Split axis (interior nodes).
  int axis() const { return int(bits_ & 3u); }
  /// Split coordinate (interior nodes).
  float split() const { return std::bit_cast<float>(word_); }
  /// Index of the above child (interior nodes); the below child is this node's index + 1.
  uint32_t above() const { return bits_ >> 4; }
  /// True when the below child is an empty leaf (interior nodes).
  bool below_empty() const { return (bits_ & 4u) != 0; }
  /// True when the above child is an empty leaf (interior nodes).
  bool above_empty() const { return (bits_ & 8u) != 0; }
  /// First primitive index (leaves).
  uint32_t first() const { return word_; }
  /// Number of primitives (leaves).
  uint32_t count() const { return bits_ >> 2; }
  /// Moves the node by `node_base` nodes and `prim_base` primitive indices (splicing buffers).
  void rebase(uint32_t node_base, uint32_t prim_base) {
    if (is_leaf()) {
      word_ += prim_base;
    } else {
      bits_ += node_base << 4;
    }
  }
  /// This interior node with another above child and empty-child flags (drop_empty_leaves).
  KdNode relinked(uint32_t above, bool below_empty, bool above_empty) const {
    return interior(axis(), split(), above, below_empty, above_empty);
  }
  /// Largest node index an interior node can hold.
  static constexpr uint32_t kMaxIndex = (1u << 28) - 1;

 private:
  KdNode(uint32_t word, uint32_t bits) : word_(word), bits_(bits) {}
  uint32_t word_;
  uint32_t bits_;
};
static_assert(sizeof(KdNode) == 8);

/// Nodes in depth-first order (below child next to its parent) and the leaves' primitive indices.
struct KdBuffer {
  std::vector<KdNode> nodes;
  std::vector<uint32_t> prims;

  /// Appends a leaf holding ids.
  void add_leaf(const std::vector<uint32_t>& ids) {
    nodes.push_back(KdNode::leaf(uint32_t(prims.size()), uint32_t(ids.size())));
    prims.insert(prims.end(), ids.begin(), ids.end());
  }
  /// Appends a subtree built into its own buffer (parallel builds), fixing its indices.
  void append(const KdBuffer& sub) {
    const uint32_t node_base = uint32_t(nodes.size());
    const uint32_t prim_base = uint32_t(prims.size());
    for (KdNode n : sub.nodes) {
      n.rebase(node_base, prim_base);
      nodes.push_back(n);
    }
    prims.insert(prims.end(), sub.prims.begin(), sub.prims.end());
  }
};

/// Removes the empty leaves of a depth-first tree (all but an empty root): their parents flag them instead.
/// Node provides is_leaf(), count(), above() and relinked(above, below_empty, above_empty) (a copy of an
/// interior node with a new above index and flags), and kMaxIndex. Throws InputError when the remaining
/// nodes do not fit the node's index field. Shared by the k-d trees and the BSP tree.
template <class Node>
void drop_empty_leaves(std::vector<Node>& nodes) {
  const size_t n = nodes.size();
  auto empty = [&](size_t i) { return i != 0 && nodes[i].is_leaf() && nodes[i].count() == 0; };
  std::vector<uint32_t> remap(n);
  size_t kept = 0;
  for (size_t i = 0; i < n; ++i) {
    remap[i] = uint32_t(kept);
    kept += !empty(i);
  }
  if (kept > Node::kMaxIndex) throw InputError("tree of more nodes than its node format can index (mesh too large)");
  std::vector<Node> out;
  out.reserve(kept);
  for (size_t i = 0; i < n; ++i) {
    const Node& nd = nodes[i];
    if (empty(i)) continue;
    if (nd.is_leaf()) {
      out.push_back(nd);
      continue;
    }
    const bool below_empty = empty(i + 1);
    const bool above_empty = empty(nd.above()) && !below_empty;  // a split always keeps one side
    out.push_back(nd.relinked(above_empty ? 0 : remap[nd.above()], below_empty, above_empty));
  }
  nodes.swap(out);
}

/// Margin of conservative insertion for a node box: a primitive within it of a split plane goes to both
/// children. Same scale as inflate_for_insertion (clip.h): relative to the box's size and position.
inline float insertion_margin(const AABB& box) {
  const vec3 e = box.extent();
  const vec3 a = glm::max(glm::abs(box.lo), glm::abs(box.hi));
  return std::max({e.x, e.y, e.z, a.x, a.y, a.z}) * 0x1p-18f;
}

/// The part of primitive i that a child box holds for the builders: its perfect-split bounds in the child
/// box grown by `margin`, clamped back into the child box (so a primitive that only comes within the
/// margin becomes a flat sliver on the child's face instead of disappearing).
template <class P>
AABB clip_into_child(const P& prims, uint32_t i, const AABB& child, float margin) {
  const AABB grown{child.lo - vec3(margin), child.hi + vec3(margin)};
  AABB cb = prims.clipped_bounds(i, grown);
  if (cb.empty()) cb = AABB::intersection(prims.bounds(i), grown);
  cb.lo = glm::clamp(cb.lo, child.lo, child.hi);
  cb.hi = glm::clamp(cb.hi, child.lo, child.hi);
  cb.lo = glm::min(cb.lo, cb.hi);
  return cb;
}

/// True when every coordinate of b is finite (primitives with NaN or infinite bounds are never hit
/// and are left out of spatial structures).
inline bool finite_box(const AABB& b) {
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(b.lo[a]) || !std::isfinite(b.hi[a])) return false;
  return !b.empty();
}

/// Splits the primitives of `prims` into those with finite bounds (returned; their union goes into `box`)
/// and the rest (`unbounded`: tested for every ray, so their ids and any hit are kept).
template <class P>
std::vector<uint32_t> partition_finite(const P& prims, std::vector<uint32_t>& unbounded, AABB& box) {
  std::vector<uint32_t> ids;
  unbounded.clear();
  box = AABB{};
  for (size_t i = 0; i < prims.size(); ++i) {
    const AABB b = prims.bounds(i);
    if (finite_box(b)) {
      ids.push_back(uint32_t(i));
      box.extend(b);
    } else {
      unbounded.push_back(uint32_t(i));
    }
  }
  return ids;
}

/// Closest hit over a leaf's id list, on a copy of the ray whose tmax follows best.t (the kernel's t, u, v
/// do not depend on tmax, so hits stay identical). Returns true when best changed.
template <bool kCount, class P>
bool intersect_id_list(const P& prims, const uint32_t* ids, uint32_t count, const Ray& ray, Hit& best,
                       uint32_t inst, RayCounters& c) {
  Ray r = ray;
  r.tmax = std::min(ray.tmax, best.t);
  bool changed = false;
  for (uint32_t k = 0; k < count; ++k)
    if (prims.template intersect<kCount>(ids[k], r, best, inst, c)) {
      r.tmax = std::min(ray.tmax, best.t);
      changed = true;
    }
  return changed;
}

/// True when any primitive of a leaf's id list blocks the ray.
template <bool kCount, class P>
bool occluded_id_list(const P& prims, const uint32_t* ids, uint32_t count, const Ray& ray, RayCounters& c) {
  for (uint32_t k = 0; k < count; ++k)
    if (prims.template occluded<kCount>(ids[k], ray, c)) return true;
  return false;
}

/// When the leaves copy their triangles (parameter leaf_copies: on, off, or auto = when the leaves hold at most
/// kAutoCopyReferences references per triangle, so the copies cost at most about 108 bytes per triangle).
enum class LeafCopies { kOff, kOn, kAuto };
/// References per triangle up to which leaf_copies=auto copies.
inline constexpr double kAutoCopyReferences = 3.0;

/// Reads the leaf_copies parameter (on, off or auto).
inline LeafCopies read_leaf_copies(Params& params) {
  const std::string v = params.get_choice("leaf_copies", "auto", {"auto", "on", "off"});
  return v == "on" ? LeafCopies::kOn : v == "off" ? LeafCopies::kOff : LeafCopies::kAuto;
}

/// The leaves' primitive references in leaf order: the original ids and, for triangle sets when asked, a
/// copy of each referenced triangle in the same order, so that a leaf reads its triangles from one
/// contiguous run (as the BVH's leaves do) instead of gathering them by id. A triangle referenced by several
/// leaves is copied once per reference (36 bytes each), which is why it is optional. Other primitive sets
/// (instances) are always reached through their ids.
template <class P>
class LeafRefs {
 public:
  /// True when the primitive set can be copied into leaf order.
  static constexpr bool kCanCopy = std::is_same_v<P, TrianglePrims>;

  /// Takes the leaf-ordered ids and copies the triangles they name as `mode` says.
  void assign(const P& prims, std::vector<uint32_t> ids, LeafCopies mode) {
    ids_ = std::move(ids);
    tris_.clear();
    if constexpr (kCanCopy) {
      const bool few = double(ids_.size()) <= kAutoCopyReferences * double(prims.size());
      if (mode == LeafCopies::kOn || (mode == LeafCopies::kAuto && few)) {
        tris_.resize(ids_.size());
        for (size_t k = 0; k < ids_.size(); ++k) tris_[k] = prims.triangle(ids_[k]);
      }
    }
  }
  /// The leaf-ordered ids.
  const std::vector<uint32_t>& ids() const { return ids_; }
  /// True when the triangles were copied.
  bool copied() const { return !tris_.empty(); }
  /// Memory of the ids and copies.
  size_t bytes() const { return ids_.size() * sizeof(uint32_t) + tris_.size() * sizeof(Triangle); }

  /// Closest hit over references [first, first + count): the one kernel with the original ray and ids.
  template <bool kCount>
  [[gnu::always_inline]] void intersect(const P& prims, uint32_t first, uint32_t count, const Ray& ray, Hit& best,
                                        uint32_t inst, RayCounters& c) const {
    if constexpr (kCanCopy) {
      if (!tris_.empty()) {
        if constexpr (kCount) c.prims += count;
        for (uint32_t k = first, e = first + count; k < e; ++k) {
          TriangleHit th;  // the id (another array) is read only for a hit
          if (intersect_triangle(ray, tris_[k], th) && is_better_hit(th.t, inst, ids_[k], best))
            best = {th.t, ids_[k], inst, th.u, th.v};
        }
        return;
      }
    }
    intersect_id_list<kCount>(prims, ids_.data() + first, count, ray, best, inst, c);
  }
  /// True when any reference in [first, first + count) blocks the ray.
  template <bool kCount>
  [[gnu::always_inline]] bool occluded(const P& prims, uint32_t first, uint32_t count, const Ray& ray,
                                       RayCounters& c) const {
    if constexpr (kCanCopy) {
      if (!tris_.empty()) {
        for (uint32_t k = first, e = first + count; k < e; ++k) {
          if constexpr (kCount) ++c.prims;
          TriangleHit th;
          if (intersect_triangle(ray, tris_[k], th)) return true;
        }
        return false;
      }
    }
    return occluded_id_list<kCount>(prims, ids_.data() + first, count, ray, c);
  }

 private:
  std::vector<uint32_t> ids_;
  std::vector<Triangle> tris_;
};

/// Default depth limit of the k-d builders: 8 + 1.3 log2 N (Havran 2000; pbrt).
inline int auto_kd_depth(size_t n) { return int(std::lround(8.0 + 1.3 * std::log2(double(std::max<size_t>(n, 1))))); }

/// The closest-hit and any-hit queries of a spatial tree D (k-d trees, octree, BSP), written once: the
/// unbounded primitives by list, then D's front-to-back traverse<kCount>(ray, c, leaf(first, count),
/// best_t()) over the leaves' lists (LeafRefs). D declares this class a friend for prims_, unbounded_,
/// leaves_ and traverse.
template <class D>
class SpatialTreeQueries : public AcceleratorBase<D> {
 public:
  /// Closest hit, front to back; a leaf's cells are pruned by best.t.
  template <bool kCount>
  [[gnu::flatten]] void intersect_ray(const Ray& ray, Hit& best, uint32_t inst, RayCounters& c) const {
    const D& d = static_cast<const D&>(*this);
    if (!d.unbounded_.empty())
      intersect_id_list<kCount>(*d.prims_, d.unbounded_.data(), uint32_t(d.unbounded_.size()), ray, best, inst, c);
    d.template traverse<kCount>(
        ray, c,
        [&](uint32_t first, uint32_t count) {
          d.leaves_.template intersect<kCount>(*d.prims_, first, count, ray, best, inst, c);
          return false;
        },
        [&] { return best.t; });
  }

  /// Any hit: the same walk, stopping at the first primitive that blocks the ray.
  template <bool kCount>
  bool occluded_ray(const Ray& ray, RayCounters& c) const {
    const D& d = static_cast<const D&>(*this);
    if (occluded_id_list<kCount>(*d.prims_, d.unbounded_.data(), uint32_t(d.unbounded_.size()), ray, c)) return true;
    return d.template traverse<kCount>(
        ray, c,
        [&](uint32_t first, uint32_t count) { return d.leaves_.template occluded<kCount>(*d.prims_, first, count, ray, c); },
        [] { return kInf; });
  }
};

}  // namespace ab
