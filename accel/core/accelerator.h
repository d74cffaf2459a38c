// The accelerator interface: build, closest hit, any hit, bounds, statistics.
// The virtual boundary is a batch of rays, so dispatch costs the same for every structure; the
// per-ray loops below are non-virtual and inline the structure's traversal.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <utility>

#include "accel/core/aabb.h"
#include "accel/core/memory.h"
#include "accel/core/mesh.h"
#include "accel/core/primitives.h"
#include "accel/core/stats.h"

namespace ab {

class InstancePrims;

/// An acceleration structure over one primitive set.
class Accelerator {
 public:
  virtual ~Accelerator() = default;

  /// Builds the structure and records the wall time of that build alone in stats().build_seconds and its
  /// heap high-water mark in stats().peak_bytes (memory.h; added to what do_build recorded there for
  /// memory the heap does not see, such as Embree's); the
  /// statistics of the finished structure are gathered afterwards (gather_stats), outside the timing.
  void build() {
    stats_ = BuildStats{};
    const HeapPeak peak;
    const auto start = std::chrono::steady_clock::now();
    do_build();
    stats_.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    stats_.peak_bytes += peak.bytes();
    gather_stats(stats_);
  }

  /// Moves the structure to new positions of its primitives (the same count and ids) by refitting over the
  /// unchanged topology (accel/bvh/refit.h). False, with nothing changed, when the structure does not refit;
  /// on success stats() describe the refitted structure and build_seconds is the refit's wall time.
  bool refit(std::shared_ptr<const TrianglePrims> geometry) {
    return timed_refit([&] { return do_refit_triangles(std::move(geometry)); });
  }
  /// The same from the frame's indexed mesh (new vertex positions, the same triangles): the whole cost of
  /// making the structure traversable for that frame. BVHs over triangles gather their leaves from the mesh
  /// itself; other structures get the frame's TrianglePrims made inside the timing.
  bool refit(std::shared_ptr<const Mesh> mesh) {
    return timed_refit([&] { return do_refit_mesh(std::move(mesh)); });
  }
  /// The same for a top level over instances that moved (their bottom levels already updated).
  bool refit(std::shared_ptr<const InstancePrims> instances) {
    return timed_refit([&] { return do_refit_instances(std::move(instances)); });
  }

  /// Registry name (for example "bvh-sah"), as the registry recorded it (identify()).
  virtual std::string name() const { return name_; }
  /// Effective configuration (every field, defaults included), as the registry recorded it.
  virtual nlohmann::json config() const { return config_; }
  /// Records the registry name and the effective configuration; the registry calls this once, when it
  /// creates the structure, so a structure never repeats its own name or parameters.
  void identify(std::string name, nlohmann::json config) {
    name_ = std::move(name);
    config_ = std::move(config);
  }
  /// Bounds of everything it holds.
  virtual AABB bounds() const = 0;
  /// Statistics of the last build.
  const BuildStats& stats() const { return stats_; }
  /// Adds the quality metrics that cost more than a build (the BVHs' end-point overlap) to stats(); not
  /// part of build(), so repeated timed builds do not pay for them: call it once where they are reported.
  void measure_quality() { gather_quality(stats_); }

  /// Closest hit of every ray (hits[i] is overwritten).
  virtual void intersect(std::span<const Ray> rays, std::span<Hit> hits) const = 0;
  /// Any hit within [tmin, tmax] of every ray (1 = occluded).
  virtual void occluded(std::span<const Ray> rays, std::span<uint8_t> out) const = 0;
  /// Closest hit with counters summed into `total` (the separate counting pass).
  virtual void intersect_counted(std::span<const Ray> rays, std::span<Hit> hits,
                                 RayCounters& total) const = 0;
  /// Any hit with counters summed into `total`.
  virtual void occluded_counted(std::span<const Ray> rays, std::span<uint8_t> out,
                                RayCounters& total) const = 0;

  /// One ray against the structure as the bottom level of an instance: `best` holds the best hit so far
  /// (from other instances) and is updated by the acceptance rule with instance id `inst`.
  /// `counters` may be null (no counting).
  virtual void intersect_one(const Ray& ray, Hit& best, uint32_t inst, RayCounters* counters) const = 0;
  /// Any hit of one ray; `counters` may be null.
  virtual bool occluded_one(const Ray& ray, RayCounters* counters) const = 0;

 protected:
  /// The build itself (timed). It may record figures only the build knows in stats_ (stats_ is reset
  /// before it runs).
  virtual void do_build() = 0;
  /// Fills the statistics of the finished structure (not timed): most structures describe their tree to
  /// the one statistics walk (accel/common/tree_stats.h) and add their bytes.
  virtual void gather_stats(BuildStats& stats) const { (void)stats; }
  /// The refit over moved triangles (refit()); false when unsupported.
  virtual bool do_refit_triangles(std::shared_ptr<const TrianglePrims>) { return false; }
  /// The refit from a frame's mesh (refit()): by default the frame's TrianglePrims, refitted over.
  virtual bool do_refit_mesh(std::shared_ptr<const Mesh> mesh) {
    return do_refit_triangles(std::make_shared<const TrianglePrims>(std::move(mesh)));
  }
  /// The refit over moved instances (refit()); false when unsupported.
  virtual bool do_refit_instances(std::shared_ptr<const InstancePrims>) { return false; }
  /// Fills the expensive quality metrics of the finished structure (measure_quality()).
  virtual void gather_quality(BuildStats& stats) const { (void)stats; }
  BuildStats stats_;

 private:
  /// Runs a refit, timing it alone as build() does; the statistics are gathered again on success.
  template <class F>
  bool timed_refit(F&& f) {
    const auto start = std::chrono::steady_clock::now();
    if (!f()) return false;
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    stats_ = BuildStats{};
    stats_.build_seconds = seconds;
    gather_stats(stats_);
    return true;
  }

  std::string name_;
  nlohmann::json config_ = nlohmann::json::object();
};

/// Implements the batch entry points for a structure D that provides
///   template <bool kCount> void intersect_ray(const Ray&, Hit& best, uint32_t inst, RayCounters&) const;
///   template <bool kCount> bool occluded_ray(const Ray&, RayCounters&) const;
template <class D>
class AcceleratorBase : public Accelerator {
 public:
  void intersect(std::span<const Ray> rays, std::span<Hit> hits) const override {
    RayCounters unused;
    for (size_t i = 0; i < rays.size(); ++i) {
      hits[i] = Hit{};
      self().template intersect_ray<false>(rays[i], hits[i], kInvalidId, unused);
    }
  }
  void occluded(std::span<const Ray> rays, std::span<uint8_t> out) const override {
    RayCounters unused;
    for (size_t i = 0; i < rays.size(); ++i) out[i] = self().template occluded_ray<false>(rays[i], unused);
  }
  void intersect_counted(std::span<const Ray> rays, std::span<Hit> hits, RayCounters& total) const override {
    for (size_t i = 0; i < rays.size(); ++i) {
      hits[i] = Hit{};
      self().template intersect_ray<true>(rays[i], hits[i], kInvalidId, total);
    }
  }
  void occluded_counted(std::span<const Ray> rays, std::span<uint8_t> out,
                        RayCounters& total) const override {
    for (size_t i = 0; i < rays.size(); ++i) out[i] = self().template occluded_ray<true>(rays[i], total);
  }
  void intersect_one(const Ray& ray, Hit& best, uint32_t inst, RayCounters* counters) const override {
    if (counters) {
      self().template intersect_ray<true>(ray, best, inst, *counters);
    } else {
      RayCounters unused;
      self().template intersect_ray<false>(ray, best, inst, unused);
    }
  }
  bool occluded_one(const Ray& ray, RayCounters* counters) const override {
    if (counters) return self().template occluded_ray<true>(ray, *counters);
    RayCounters unused;
    return self().template occluded_ray<false>(ray, unused);
  }

 private:
  const D& self() const { return static_cast<const D&>(*this); }
};

}  // namespace ab
