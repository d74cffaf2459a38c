// The conservative ray/sphere test of bvh-sphere: the entry distance of a ray into a node's sphere, never
// greater than the distance of any hit of a triangle inside the sphere, so that the walk's strict pruning
// (TraversalStack) keeps hits identical to brute's.
//
// Geometry (the "closest approach" form of Haines, Guenther and Akenine-Moller 2019, "Precision
// Improvements for Ray/Sphere Intersection", Ray Tracing Gems ch. 7): with f = c - o the centre relative to
// the origin and a = d.d, the ray passes closest to the centre at tc = (f.d) / a, at squared distance
// h2 = |f - tc d|^2; it meets the sphere of radius R when h2 <= R^2, over tc -+ sqrt((R^2 - h2) / a). That
// form subtracts nothing of similar size when the sphere is small and far away (b^2 - ac does).
//
// Why it is conservative (the sphere's counterpart of box_test.h's rule):
// - The stored sphere contains every vertex below the node in exact arithmetic (sphere_fit.cpp measures the
//   radius in double from the float centre and rounds it up), so it contains the triangles themselves.
// - The test runs in double from the float inputs: f, a, tc, h2 and the half chord carry relative errors of
//   a few 2^-53 of |f| and R, and nothing over- or underflows for any float ray (unnormalized directions of
//   any size, zero components: no reciprocal is taken of a component).
// - The kernel (triangle.h, single precision) accepts a point a few 2^-24 of |o - v0| <= |f| + r outside
//   the triangle. So the radius is grown to R = r + kSphereMargin (r + |f|_1), kSphereMargin = 2^-16
//   (kBoxEps), which covers the kernel's slack and the test's rounding with a factor of about 100 to
//   spare; the chord of R contains the chord of r widened by at least kSphereMargin |f| along the ray.
// - The interval's ends are then widened as the slab distances of the box test are (widen_near,
//   widen_far), covering the kernel's rounding of t (and the conversion to float) as box_test.h derives.
// - The limit this shares with the box test: at grazing angles the kernel's own t is off by about 2^-24 /
//   cos(angle to the plane) relative (its denominator is nearly zero), beyond any small relative widening.
//   Rays within about 2^-11 of a triangle's plane can have the kernel's t a few 1e-5 before the sphere's
//   (and the box's) entry; tests/bvh_sphere_test.cpp asserts the rule for every ray steeper than 2^-9.
// - A zero, infinite or NaN direction (a = 0 or not finite) enters every sphere at tmin: conservative
//   whatever the kernel makes of such a ray. A NaN origin or centre fails h2 <= R^2 (a miss; the kernel
//   never hits with a NaN origin, and a NaN centre is the empty sphere).
#pragma once

#include <algorithm>
#include <cmath>

#include "accel/bvh/sphere_node.h"
#include "accel/core/box_test.h"
#include "accel/core/ray.h"

namespace ab {

/// Relative growth of every sphere in the ray test, of the radius and of the distance from the ray's
/// origin to the centre (see the file comment). The same constant as the box test's widening.
inline constexpr double kSphereMargin = double(kBoxEps);

/// The ray/sphere test of bvh-sphere's sibling pairs (what walk_bvh2 calls BvhPairTest for boxes).
struct SpherePairTest {
  /// Prepares the per-ray data (in double).
  explicit SpherePairTest(const Ray& ray)
      : ox(ray.org.x),
        oy(ray.org.y),
        oz(ray.org.z),
        dx(ray.dir.x),
        dy(ray.dir.y),
        dz(ray.dir.z),
        tmin(ray.tmin) {
    const double a = dx * dx + dy * dy + dz * dz;
    degenerate = !(a > 0.0 && a < kInfD);
    inv_a = degenerate ? 0.0 : 1.0 / a;
  }

  /// Entry distance into node n's sphere clipped to [tmin, limit], or kInf for a miss.
  [[gnu::always_inline]] float entry(const SphereNode& n, float limit) const {
    if (degenerate) return tmin <= limit && !n.empty() ? tmin : kInf;
    const double fx = double(n.center[0]) - ox, fy = double(n.center[1]) - oy, fz = double(n.center[2]) - oz;
    const double tc = (fx * dx + fy * dy + fz * dz) * inv_a;
    const double qx = fx - tc * dx, qy = fy - tc * dy, qz = fz - tc * dz;
    const double h2 = qx * qx + qy * qy + qz * qz;
    const double r = double(n.radius);
    const double grown = r + kSphereMargin * (r + std::fabs(fx) + std::fabs(fy) + std::fabs(fz));
    const double gap = grown * grown - h2;
    if (!(gap >= 0.0)) return kInf;  // also NaN: origin or centre NaN
    const double half = std::sqrt(gap * inv_a);
    const float t0 = std::max(widen_near(float(tc - half)), tmin);
    const float t1 = std::min(widen_far(float(tc + half)), limit);
    return t0 <= t1 ? t0 : kInf;
  }
  /// Entries of pair[0] and pair[1] into tl and tr.
  [[gnu::always_inline]] void entries(const SphereNode* pair, float limit, float& tl, float& tr) const {
    tl = entry(pair[0], limit);
    tr = entry(pair[1], limit);
  }

  static constexpr double kInfD = std::numeric_limits<double>::infinity();  ///< +inf in double

  double ox, oy, oz;  ///< the ray's origin
  double dx, dy, dz;  ///< the ray's direction
  double inv_a = 0;   ///< 1 / (d.d)
  float tmin;         ///< the ray's tmin (lower clip of every entry)
  bool degenerate;    ///< zero, infinite or NaN direction: every non-empty sphere is entered at tmin
};

}  // namespace ab
