// CGAL's AABB tree over one triangle mesh, behind the accelerator interface: an outside peer (a reference
// like Embree, not a structure of the project's own), registered as `cgal` when CMake finds CGAL.
#pragma once

#include <memory>

#include "accel/reference/peer_mesh.h"

namespace ab {

/// CGAL 5.5's AABB_tree (Epick kernel, the kernel the CGAL manual recommends for ray shooting) over the
/// triangles of a mesh, each primitive only the triangle id. Closest hit through first_intersection on a
/// Ray_3 started at tmin; t, u, v of the triangle CGAL returns come from the project's kernel (peer.h).
/// Zero-area (collinear) triangles are left out of the tree (CGAL asserts on them; they never hit).
/// Any hit through CGAL's own do_intersect (a Segment_3 when tmax is finite). No traversal counters.
class CgalMesh final : public PeerMesh<CgalMesh> {
 public:
  /// Over prims (built by build()).
  CgalMesh(std::shared_ptr<const TrianglePrims> prims, const Config& config);
  /// Releases the tree.
  ~CgalMesh() override;
  CgalMesh(const CgalMesh&) = delete;
  CgalMesh& operator=(const CgalMesh&) = delete;

 protected:
  /// Builds the tree over the triangles that are not collinear.
  void do_build() override;
  /// Primitives, nodes and the bytes computed from them (CGAL does not expose its memory).
  void gather_stats(BuildStats& stats) const override;

 private:
  friend class PeerMesh<CgalMesh>;
  struct Tree;
  void closest(const Ray& ray, Hit& best, uint32_t inst) const;
  /// Any hit within [tmin, tmax] through CGAL's do_intersect.
  bool any(const Ray& ray) const;

  std::unique_ptr<Tree> tree_;
  uint64_t skipped_ = 0;  ///< collinear triangles left out
};

}  // namespace ab
