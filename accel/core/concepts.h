// What the compiler checks of a primitive set and of a structure, so that a structure that forgets a member
// fails to compile with a message naming it (docs/adding-a-structure.md walks through them).
#pragma once

#include <concepts>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "accel/core/aabb.h"
#include "accel/core/accelerator.h"
#include "accel/core/params.h"
#include "accel/core/ray.h"
#include "accel/core/stats.h"

namespace ab {

/// What a builder sees of its input, and what traversal tests (DESIGN.md: "the shape that makes instancing
/// and fairness work"): triangle meshes (TrianglePrims) and instance sets (InstancePrims) both are one.
/// intersect() applies the one acceptance rule (is_better_hit) and returns true when `best` changed.
template <class P>
concept PrimitiveSet = requires(const P& p, size_t i, const AABB& box, const Ray& ray, Hit& best,
                                uint32_t inst, RayCounters& c) {
  { p.size() } -> std::convertible_to<size_t>;
  { p.bounds() } -> std::same_as<AABB>;                // bounds of everything
  { p.bounds(i) } -> std::same_as<AABB>;               // bounds of primitive i
  { p.centroid(i) } -> std::same_as<vec3>;             // centre used by object-partitioning builders
  { p.clipped_bounds(i, box) } -> std::same_as<AABB>;  // bounds of the part of i inside box
  { p.overlaps(i, box) } -> std::same_as<bool>;        // exact overlap, touching counts
  { p.template intersect<false>(i, ray, best, inst, c) } -> std::same_as<bool>;
  { p.template intersect<true>(i, ray, best, inst, c) } -> std::same_as<bool>;
  { p.template occluded<false>(i, ray, c) } -> std::same_as<bool>;
  { p.template occluded<true>(i, ray, c) } -> std::same_as<bool>;
};

/// A structure's configuration: defaulted fields, read once from the parameters by `read` (each field's
/// initializer is its default; Params::read records the effective value for the reports).
template <class C>
concept StructureConfig = std::default_initializable<C> && std::copyable<C> && requires(Params& params) {
  { C::read(params) } -> std::same_as<C>;
};

/// The two per-ray queries AcceleratorBase turns into the batch entry points: closest hit (updates `best` by
/// the acceptance rule, with instance id `inst`) and any hit, each with counters compiled in or out.
template <class S>
concept RayQueries = requires(const S& s, const Ray& ray, Hit& best, uint32_t inst, RayCounters& c) {
  { s.template intersect_ray<false>(ray, best, inst, c) } -> std::same_as<void>;
  { s.template intersect_ray<true>(ray, best, inst, c) } -> std::same_as<void>;
  { s.template occluded_ray<false>(ray, c) } -> std::same_as<bool>;
  { s.template occluded_ray<true>(ray, c) } -> std::same_as<bool>;
};

/// A structure of the project over primitive set S::Prims: an Accelerator with a Config, constructed from the
/// primitives and that Config (the build is separate), answering both ray queries.
// (clang-format 14 misreads the template arguments of a concept's requirement as comparisons.)
// clang-format off
template <class S>
concept Structure = std::derived_from<S, Accelerator> && PrimitiveSet<typename S::Prims> &&
                    StructureConfig<typename S::Config> && RayQueries<S> &&
                    std::constructible_from<S, std::shared_ptr<const typename S::Prims>,
                                            const typename S::Config&>;
// clang-format on

}  // namespace ab
