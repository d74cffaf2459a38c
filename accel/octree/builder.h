// The adaptive octree build: a cube around the scene, subdivided into eight equal children while a node
// holds more than leaf_size primitives and is above the depth limit. Primitives are inserted by exact
// primitive/box overlap against the child boxes grown by the insertion margin (inflate_for_insertion,
// clip.h), so a primitive touching a cell or within rounding of its boundary is in every such cell. Large
// nodes build their eight subtrees in parallel, each into its own buffer, spliced in child order (the same
// tree for any thread count).
#pragma once

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "accel/core/clip.h"
#include "accel/octree/config.h"
#include "accel/octree/node.h"

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
  OctreeBuilder(const P& prims, const OctreeConfig& config) : prims_(prims), config_(config) {}

  /// Builds the tree over the primitives ids (finite bounds) inside the cube `box` into out (root: node 0).
  void build(std::vector<uint32_t>&& ids, const AABB& box, OctBuffer& out) const {
    out.nodes.push_back(OctNode::leaf(0, 0));
    if (!ids.empty()) build_node(std::move(ids), box, 0, 0, out);
  }

 private:
  /// Builds node `self` (already allocated) over ids inside box.
  void build_node(std::vector<uint32_t>&& ids, const AABB& box, int depth, uint32_t self,
                  OctBuffer& out) const {
    std::array<std::vector<uint32_t>, 8> kids;
    if (ids.size() > config_.leaf_size && depth < config_.max_depth) distribute(ids, box, kids);
    bool progress = false;
    for (const auto& k : kids) progress |= !k.empty() && k.size() < ids.size();
    if (!progress) {
      out.nodes[self] = out.make_leaf(ids);
      return;
    }
    const size_t n = ids.size();
    std::vector<uint32_t>().swap(ids);
    const uint32_t first = uint32_t(out.nodes.size());
    out.nodes[self] = OctNode::interior(first);
    out.nodes.resize(first + 8, OctNode::leaf(0, 0));
    if (n < kParallelMin) {
      for (int k = 0; k < 8; ++k)
        build_node(std::move(kids[k]), octant_box(box, k), depth + 1, first + k, out);
      return;
    }
    std::array<OctBuffer, 8> subs;
    tbb::parallel_for(0, 8, [&](int k) {
      subs[k].nodes.push_back(OctNode::leaf(0, 0));
      build_node(std::move(kids[k]), octant_box(box, k), depth + 1, 0, subs[k]);
    });
    for (int k = 0; k < 8; ++k) out.splice(subs[k], first + k);
  }

  /// Exact overlap of every primitive with the eight (grown) child boxes.
  void distribute(const std::vector<uint32_t>& ids, const AABB& box,
                  std::array<std::vector<uint32_t>, 8>& kids) const {
    for (int k = 0; k < 8; ++k) {
      const AABB grown = inflate_for_insertion(octant_box(box, k));
      for (uint32_t i : ids)
        if (prims_.overlaps(i, grown)) kids[k].push_back(i);
    }
  }

  /// Nodes at least this large build their children in parallel.
  static constexpr size_t kParallelMin = 20000;
  const P& prims_;
  OctreeConfig config_;
};

}  // namespace ab
