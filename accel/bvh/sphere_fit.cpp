#include "accel/bvh/sphere_fit.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <glm/glm.hpp>
#include <vector>

namespace ab {
namespace {

using glm::dvec3;

/// Relative bound on the rounding of a distance measured in double from float coordinates (three
/// subtractions, squares, sums and a square root: a few 2^-53), with room to spare.
constexpr double kDistanceRounding = 0x1p-40;

/// The smallest float not below x (x >= 0).
float round_up(double x) {
  float f = float(x);
  if (double(f) < x) f = std::nextafter(f, kInf);
  return f;
}

/// The point of pts farthest from p.
dvec3 farthest(std::span<const vec3> pts, const dvec3& p) {
  dvec3 best = dvec3(pts[0]);
  double best_d2 = -1.0;
  for (const vec3& q : pts) {
    const dvec3 e = dvec3(q) - p;
    const double d2 = glm::dot(e, e);
    if (d2 > best_d2) best_d2 = d2, best = dvec3(q);
  }
  return best;
}

/// Ritter 1990, "An efficient bounding sphere" (Graphics Gems): the sphere on the diameter between a
/// point far from an arbitrary one and the point farthest from that, grown in one pass over every point
/// left outside (the centre moves towards it, the new sphere just holds the old one and the point). Its
/// radius is within about 5-20% of the minimal one; only its centre is kept (the radius is measured
/// exactly afterwards).
dvec3 ritter_centre(std::span<const vec3> pts) {
  const dvec3 y = farthest(pts, dvec3(pts[0]));
  const dvec3 z = farthest(pts, y);
  dvec3 c = 0.5 * (y + z);
  double r = 0.5 * glm::length(z - y);
  for (const vec3& q : pts) {
    const dvec3 e = dvec3(q) - c;
    const double d = glm::length(e);
    if (d <= r) continue;
    const double grown = 0.5 * (r + d);
    c += e * ((d - grown) / d);
    r = grown;
  }
  return c;
}

/// A node's sphere (centre and radius) with its topology copied from the binary node.
SphereNode with_sphere(const BvhNode& node, const vec3& centre, float radius) {
  SphereNode s{};
  s.center[0] = centre.x, s.center[1] = centre.y, s.center[2] = centre.z;
  s.radius = radius;
  s.offset = node.offset;
  s.count = node.count;
  return s;
}

/// Ritter's sphere of a node's points with the exactly measured radius (the empty sphere for no points).
SphereNode points_sphere(const BvhNode& node, std::span<const vec3> pts) {
  if (pts.empty()) return with_sphere(node, vec3(kEmptySphere), 0.0f);
  const vec3 centre = vec3(ritter_centre(pts));
  return with_sphere(node, centre, enclosing_radius(centre, pts));
}

/// Smallest float radius around centre holding both spheres a and b (not empty), measured in double.
float radius_around(const vec3& centre, const SphereNode& a, const SphereNode& b) {
  const double da = glm::length(dvec3(centre) - dvec3(a.centre())) + double(a.radius);
  const double db = glm::length(dvec3(centre) - dvec3(b.centre())) + double(b.radius);
  return round_up(std::max(da, db) * (1.0 + kDistanceRounding));
}

/// Replaces node's sphere by the smallest sphere around its children's when that one is smaller: the
/// sphere on the segment through both centres reaching from the far side of one to the far side of the
/// other (or the larger child's, when it contains the smaller).
void tighten_around_children(SphereNode& node, const SphereNode& left, const SphereNode& right) {
  if (left.empty() || right.empty()) {
    const SphereNode& only = left.empty() ? right : left;
    if (!only.empty() && (node.empty() || only.radius < node.radius))
      std::copy(only.center, only.center + 3, node.center), node.radius = only.radius;
    return;
  }
  const dvec3 ca(left.centre()), cb(right.centre());
  const double d = glm::length(cb - ca), ra = left.radius, rb = right.radius;
  dvec3 c = ca;
  if (d + ra <= rb)
    c = cb;
  else if (d + rb > ra)
    c = ca + (cb - ca) * ((0.5 * (d + ra + rb) - ra) / d);
  const vec3 centre(c);
  const float radius = radius_around(centre, left, right);
  if (node.empty() || radius < node.radius)
    node.center[0] = centre.x, node.center[1] = centre.y, node.center[2] = centre.z, node.radius = radius;
}

/// Each node's range of leaf order [first[i], end[i]) (children follow their parent in the array).
void leaf_ranges(const BvhNodeArray& tree, std::vector<uint32_t>& first, std::vector<uint32_t>& end) {
  for (size_t i = tree.size(); i-- > 0;) {
    if (i == 1) continue;  // padding
    const BvhNode& n = tree[i];
    if (n.is_leaf()) {
      first[i] = n.offset, end[i] = n.offset + n.count;
    } else {
      first[i] = std::min(first[n.offset], first[n.offset + 1]);
      end[i] = std::max(end[n.offset], end[n.offset + 1]);
    }
  }
}

}  // namespace

float enclosing_radius(const vec3& centre, std::span<const vec3> points) {
  if (points.empty()) return -1.0f;
  const dvec3 c(centre);
  double d2 = 0.0;
  for (const vec3& p : points) {
    const dvec3 e = dvec3(p) - c;
    d2 = std::max(d2, glm::dot(e, e));
  }
  return round_up(std::sqrt(d2) * (1.0 + kDistanceRounding));
}

SphereNodeArray fit_spheres(const BvhNodeArray& tree, const LeafOrderPoints& points) {
  const size_t n = tree.size();
  std::vector<uint32_t> first(n, 0), end(n, 0);
  leaf_ranges(tree, first, end);
  SphereNodeArray out(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 8), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const uint32_t p0 = points.begin[first[i]], p1 = points.begin[end[i]];
      out[i] = i == 1 ? with_sphere(tree[i], vec3(kEmptySphere), 0.0f)
                      : points_sphere(tree[i], points.points.subspan(p0, p1 - p0));
    }
  });
  for (size_t i = n; i-- > 0;)
    if (i != 1 && !tree[i].is_leaf())
      tighten_around_children(out[i], out[tree[i].offset], out[tree[i].offset + 1]);
  return out;
}

}  // namespace ab
