// Comparing hit arrays: byte-identical against brute, and the explained agreement with Embree.
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <span>
#include <vector>

#include "accel/core/aabb.h"
#include "accel/core/triangle.h"

namespace ab {

/// Result of a byte-for-byte comparison.
struct IdenticalResult {
  uint64_t compared = 0;   ///< records compared (the shorter array's length)
  uint64_t differing = 0;  ///< records that differ (plus every record of the longer array beyond it)
  std::vector<uint64_t> first_differences;  ///< up to 10 ray indices
  /// True when every record matched.
  bool identical() const { return differing == 0; }
};

/// Compares two hit arrays record by record, bit for bit (t, prim, inst, u, v).
IdenticalResult compare_identical(std::span<const Hit> expected, std::span<const Hit> actual);

/// How two independent implementations (ours and Embree's) relate on each ray.
struct Agreement {
  uint64_t agree = 0;  ///< same (inst, prim) and t within a relative 1e-4, or both miss
  uint64_t tie = 0;    ///< different primitives hit at the same t (duplicates, shared edges, coplanar)
  /// A hit lies within 1e-4 (barycentric) or 1e-5 of the coordinates' scale (distance) of an edge.
  uint64_t edge = 0;
  /// A hit triangle is nearly parallel to the ray (|cos| < 1e-3, or the kernel calls it parallel).
  uint64_t graze = 0;
  uint64_t limit = 0;  ///< a hit t is within rounding of tmin or tmax
  /// The same triangle at t's apart by less than the two kernels' rounding bound on t (on a sliver, whose
  /// normal is ill-conditioned, a few percent of t at ordinary angles).
  uint64_t rounding = 0;
  uint64_t unexplained = 0;                ///< anything else: a real disagreement
  std::vector<uint64_t> unexplained_rays;  ///< up to 10 ray indices

  /// Disagreements that are explained by arithmetic (tie, edge, graze, limit, rounding).
  uint64_t explained() const { return tie + edge + graze + limit + rounding; }
};

/// World-space triangle of a hit (mesh: triangle prim; scene: the instance's transformed triangle).
using HitTriangleFn = std::function<Triangle(const Hit&)>;
/// World-space triangle of a hit at a ray's time (a deforming mesh's triangle and a moving instance's
/// transform at that time, as every structure sees them).
using HitTriangleAtFn = std::function<Triangle(const Hit&, float time)>;

/// Classifies each ray's pair of hits (ours, embree's), with each hit's triangle at its ray's time.
Agreement classify_agreement(std::span<const Ray> rays, std::span<const Hit> ours,
                             std::span<const Hit> theirs, const HitTriangleAtFn& triangle_at);
/// The same for triangles that do not move.
Agreement classify_agreement(std::span<const Ray> rays, std::span<const Hit> ours,
                             std::span<const Hit> theirs, const HitTriangleFn& triangle_of);

/// The JSON form of a comparison (for reports).
nlohmann::json to_json(const IdenticalResult& r);
/// The JSON form of a classification (for reports).
nlohmann::json to_json(const Agreement& a);

}  // namespace ab
