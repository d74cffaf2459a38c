// The adaptive octree build: a cube around the scene, subdivided into eight equal children while a node
// holds more than leaf_size primitives and is above the depth limit, and the subdivision still pays:
// - the depth limit grows with log N (auto_octree_depth_limit, Havran 2000's 8 + 1.3 log2 N in octree
//   levels), never below max_depth, and counts only the levels that divide the node's primitives (not
//   those whose largest child keeps more than 7/8 of them, zoom), within the walk's kMaxDepth in all;
// - pbrt-v3's bad refines (Pharr, Jakob and Humphreys 2016, 4.4.2): a subdivision is bad when its
//   estimated cost is not below the leaf's; with the surface-area estimate, each child cube has a quarter
//   of its parent's area, so it is bad when the children hold at least 4x the node's references; the
//   bad_refines-th bad one on a path makes a leaf instead (large overlapping triangles, copied into most
//   children, stop after a few levels); a subdivision whose every non-empty child holds all the node's
//   primitives is a bad one too (a fan's centre: the next level separates them), unless that child is
//   the only one (an empty cut, whose estimate is a quarter of the leaf's);
// - the reference budget (build_with_budget, refine_rules.h) as a safety net: at most ref_budget
//   references per primitive, the tree unchanged on any input whose tree stays under it.
// Primitives are inserted by exact primitive/box overlap against the child boxes grown by the insertion
// margin (InsertionMargin, conservative_insertion.h), so a primitive touching a cell or within rounding of
// its boundary is in every such cell. Large nodes build their eight subtrees in parallel, each into its own
// buffer, spliced in child order (the same tree for any thread count).
#pragma once

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <type_traits>
#include <vector>

#include "accel/common/conservative_insertion.h"
#include "accel/common/refine_rules.h"
#include "accel/core/clip.h"
#include "accel/core/primitives.h"
#include "accel/octree/config.h"
#include "accel/octree/node.h"
#include "accel/octree/octant_split.h"

namespace ab {

/// The nodes (the eight children of a node consecutive) and leaf references of an octree.
using OctBuffer = TreeBuffer<OctNode>;

/// The smallest cube around b (grown so that rounding never leaves a vertex outside); a flat or point-like
/// b gets a small cube at its scale.
inline AABB cube_around(const AABB& b) {
  if (b.empty()) return b;
  const vec3 c = b.center();
  const vec3 e = b.extent();
  float half = 0.5f * std::max({e.x, e.y, e.z});
  if (!(half > 0.0f))
    half = std::max(1.0f, std::max({std::fabs(c.x), std::fabs(c.y), std::fabs(c.z)})) * 0x1p-10f;
  AABB out{c - vec3(half), c + vec3(half)};
  out.extend(b);
  return out;
}

/// Builds octrees over a primitive set P.
template <class P>
class OctreeBuilder {
 public:
  /// Builder over prims with the tree's configuration.
  OctreeBuilder(const P& prims, const OctreeConfig& config, int depth_limit)
      : prims_(prims), config_(config), depth_limit_(depth_limit) {}

  /// Builds the tree over the primitives ids (finite bounds) inside the cube `box` into out (root: node 0).
  void build(std::vector<uint32_t>&& ids, const AABB& box, OctBuffer& out) const {
    if (ids.empty()) {
      out.nodes.push_back(OctNode::leaf(0, 0));
      return;
    }
    margins_ = InsertionMargin(box);
    auto attempt = [&](RefLedger* ledger, RefBudget budget) {
      ledger_ = ledger;
      out = OctBuffer{};
      out.nodes.push_back(OctNode::leaf(0, 0));
      build_node(std::vector<uint32_t>(ids), box, {0, 0, budget}, 0, out);
    };
    budget_exhausted_ = build_with_budget(ids.size(), config_.ref_budget, depth_limit_, attempt);
    ledger_ = nullptr;
  }
  /// True when the tree was built with the reference budget (build_with_budget).
  bool budget_exhausted() const { return budget_exhausted_; }

 private:
  /// Where a node sits: its depth, the bad refines on its path, its reference budget, and the levels on
  /// its path that divided nothing (zoom: the depth limit does not count them).
  struct Path {
    int depth;
    int bad;
    RefBudget budget;
    int zooms = 0;
  };

  /// True when one child holds all the node's primitives and the seven others none (every primitive lies
  /// in some child, so the one non-empty child holds them all): the level cuts empty space (stop).
  static bool empty_cut(const std::array<std::vector<uint32_t>, 8>& kids) {
    size_t filled = 0;
    for (const auto& k : kids) filled += !k.empty();
    return filled == 1;
  }
  /// True when a level divides nothing: its largest child keeps more than 7/8 of the node's n primitives
  /// (an empty cut, or one beside a few large triangles: a ground plane's). The depth limit counts only
  /// the other levels (as the bsp counts only splits with primitives on both sides), so a small object in
  /// a large scene is reached without spending it: the bunny on a ground plane a hundred times its size
  /// takes eight such levels, which left it two of the ten, and 876 tests per ray.
  static bool zoom(const std::array<std::vector<uint32_t>, 8>& kids, size_t n) {
    size_t most = 0;
    for (const auto& k : kids) most = std::max(most, k.size());
    return n > kZoomMin && 8 * most > 7 * n;
  }
  /// Nodes of at most this many primitives count every level (their few primitives in one child are a
  /// cluster, not an object in a large scene: the bunny alone went to depth 20 in 47 % more build time).
  static constexpr size_t kZoomMin = 64;
  /// True when a node of n primitives on path may be subdivided: above leaf_size, above the depth limit in
  /// the levels that divide (zoom), and above the walk's deepest level (kMaxDepth) in all of them.
  bool may_subdivide(size_t n, const Path& path) const {
    return n > config_.leaf_size && path.depth - path.zooms < depth_limit_ &&
           path.depth < OctreeConfig::kMaxDepth;
  }

  /// True when the eight children `kids` of a node of n primitives should not be made (a leaf instead).
  bool stop(const std::array<std::vector<uint32_t>, 8>& kids, size_t n, Path& path) const {
    bool progress = false;
    size_t refs = 0;
    for (const auto& k : kids) {
      progress |= !k.empty() && k.size() < n;
      refs += k.size();
    }
    // One child holding all n and seven empty ones cuts empty space: the references stay n and the cell's
    // area falls to a quarter, so the surface-area estimate (traversal + intersection n / 4) is below the
    // leaf's and it is no bad refine. It is how the octree zooms in on a small object in a large scene (the
    // bunny on a ground plane ten times its size: three such levels above its top half counted as bad
    // refines made it one leaf of 9,935 triangles, 10,848 tests per ray). The depth limit bounds them.
    // No progress otherwise (every non-empty child holds all n) is a bad refine too, not a leaf at once: at
    // a fan's centre (the poles of a tessellated sphere, all triangles sharing one vertex on the children's
    // common corner) every child holds all n, but a level further down only the cell at the vertex does,
    // and that cell shrinks eightfold per level. (bad_refines=0: no progress stops, as the rule is off.)
    const bool stalled = !progress && !empty_cut(kids);
    if (refs == 0 || (stalled && config_.bad_refines == 0)) return true;  // refs 0: not distributed
    if (too_many_bad_refines(stalled || refs >= 4 * n, config_.bad_refines, path.bad)) return true;
    return !path.budget.allows(refs);
  }

  /// Builds node `self` (already allocated) over ids inside box.
  void build_node(std::vector<uint32_t>&& ids, const AABB& box, Path path, uint32_t self,
                  OctBuffer& out) const {
    if (ledger_ && ledger_->over()) return;  // an abandoned attempt
    std::array<std::vector<uint32_t>, 8> kids;
    if (may_subdivide(ids.size(), path)) distribute(ids, box, kids);
    if (stop(kids, ids.size(), path)) {
      if (ledger_) ledger_->add_leaf(ids.size());
      out.nodes[self] = out.make_leaf(ids);
      return;
    }
    size_t refs = 0;
    for (const auto& k : kids) refs += k.size();
    if (ledger_) ledger_->add_children(refs);
    std::array<Path, 8> sub;
    const size_t n = ids.size();
    const int zooms = path.zooms + int(zoom(kids, n));
    for (int k = 0; k < 8; ++k)
      sub[k] = {path.depth + 1, path.bad, path.budget.share(kids[k].size(), refs), zooms};
    std::vector<uint32_t>().swap(ids);
    const uint32_t first = uint32_t(out.nodes.size());
    out.nodes[self] = OctNode::interior(first);
    out.nodes.resize(first + 8, OctNode::leaf(0, 0));
    if (n < kParallelMin) {
      for (int k = 0; k < 8; ++k) build_node(std::move(kids[k]), octant_box(box, k), sub[k], first + k, out);
      return;
    }
    std::array<OctBuffer, 8> subs;
    tbb::parallel_for(0, 8, [&](int k) {
      subs[k].nodes.push_back(OctNode::leaf(0, 0));
      build_node(std::move(kids[k]), octant_box(box, k), sub[k], 0, subs[k]);
    });
    for (int k = 0; k < 8; ++k) out.splice(subs[k], first + k);
  }

  /// Every primitive into each child whose grown box it overlaps: triangles by the one-pass octant split
  /// (octant_split.h; the exact test when a clip overflows), other primitives by the exact test.
  void distribute(const std::vector<uint32_t>& ids, const AABB& box,
                  std::array<std::vector<uint32_t>, 8>& kids) const {
    std::array<AABB, 8> child, grown;
    for (int k = 0; k < 8; ++k) child[k] = octant_box(box, k), grown[k] = margins_.inflate(child[k]);
    if constexpr (std::is_same_v<P, TrianglePrims>) {
      const OctantFrame frame(box, child, grown);
      for (uint32_t i : ids) {
        const int bits = triangle_octants(prims_.triangle(i), frame);
        for (int k = 0; k < 8; ++k)
          if (bits < 0 ? prims_.overlaps(i, grown[k]) : ((bits >> k) & 1)) kids[k].push_back(i);
      }
      return;
    }
    for (int k = 0; k < 8; ++k)
      for (uint32_t i : ids)
        if (prims_.overlaps(i, grown[k])) kids[k].push_back(i);
  }

  /// Nodes at least this large build their children in parallel.
  static constexpr size_t kParallelMin = 20000;
  const P& prims_;
  OctreeConfig config_;
  int depth_limit_;
  mutable RefLedger* ledger_ = nullptr;  ///< the unbudgeted attempt's ledger (build_with_budget)
  mutable bool budget_exhausted_ = false;
  mutable InsertionMargin margins_;  ///< the tree's insertion margins (its root box's rule, set by build)
};

}  // namespace ab
