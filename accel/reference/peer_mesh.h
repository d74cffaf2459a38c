// The frame every outside peer over one triangle mesh shares (cgal, bullet): no parameters, the mesh's
// bounds, the peer's own closest-hit and any-hit queries behind the accelerator interface with no traversal
// counters, and the peer's registry entry.
#pragma once

#include <memory>
#include <string>
#include <utility>

#include "accel/core/accelerator.h"
#include "accel/core/params.h"
#include "accel/core/primitives.h"
#include "accel/core/registry.h"

namespace ab {

/// Base of outside peer Peer over the triangles of a mesh (CRTP, as AcceleratorBase): Peer provides
/// closest(ray, best, inst), the triangle its query found turned into the contract's hit (peer.h) and kept in
/// best by the acceptance rule, and any(ray), whether a hit exists within [tmin, tmax].
template <class Peer>
class PeerMesh : public AcceleratorBase<Peer> {
 public:
  using Prims = TrianglePrims;  ///< over triangle meshes only
  /// A peer is built with its defaults: no parameters.
  struct Config {
    /// Reads nothing.
    static Config read(Params&) { return {}; }
  };

  /// Bounds of the mesh.
  AABB bounds() const override { return prims_->bounds(); }

  /// Closest hit of one ray, kept in best by the acceptance rule (counters stay zero).
  template <bool kCount>
  void intersect_ray(const Ray& ray, Hit& best, uint32_t inst, RayCounters&) const {
    peer().closest(ray, best, inst);
  }
  /// Any hit of one ray within [tmin, tmax] (counters stay zero).
  template <bool kCount>
  bool occluded_ray(const Ray& ray, RayCounters&) const {
    return peer().any(ray);
  }

 protected:
  /// Over prims (built by build()).
  explicit PeerMesh(std::shared_ptr<const TrianglePrims> prims) : prims_(std::move(prims)) {}

  std::shared_ptr<const TrianglePrims> prims_;  ///< the mesh's triangles

 private:
  const Peer& peer() const { return static_cast<const Peer&>(*this); }
};

/// The registry entry of peer Peer: a reference (not a structure of the project's own), over meshes only.
template <class Peer>
AcceleratorInfo peer_info(std::string name, std::string description, int order) {
  AcceleratorInfo info;
  info.name = std::move(name);
  info.description = std::move(description);
  info.order = order;
  info.is_reference = true;
  info.make_for_mesh = create_structure<Peer>;
  return info;
}

}  // namespace ab
