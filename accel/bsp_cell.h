// The convex cell of a BSP node as an explicit polyhedron (its face polygons, outward oriented), so that
// the surface-area cost of an arbitrary plane uses the true areas of the two parts (Ize, Wald and Parker
// 2008 track the cell the same way; a bounding box would make every oblique cut look useless). The area of
// a part is the area of the clipped faces plus that of the cut face, and the cut face's area comes free
// from the closed-surface identity: the outward vector areas of a closed polyhedron sum to zero.
#pragma once

#include "accel/bsp_candidates.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace ab {

/// A convex polyhedron given by its faces (each a convex polygon, counter-clockwise seen from outside).
class ConvexCell {
 public:
  /// The six faces of box b.
  static ConvexCell from_box(const AABB& b) {
    ConvexCell c;
    if (b.empty()) return c;
    auto corner = [&](int k) {
      return vec3((k & 1) ? b.hi.x : b.lo.x, (k & 2) ? b.hi.y : b.lo.y, (k & 4) ? b.hi.z : b.lo.z);
    };
    const int quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
    for (const auto& q : quads) c.faces_.push_back({corner(q[0]), corner(q[1]), corner(q[2]), corner(q[3])});
    return c;
  }

  /// Surface area.
  float area() const {
    float a = 0.0f;
    for (const auto& f : faces_) a += glm::length(vector_area(f));
    return a;
  }

  /// Areas of the parts below and above plane (each including the cut face). Streams the clipped
  /// polygons' vector areas without building them.
  void areas(const BspPlane& p, float& below, float& above) const {
    vec3 sum_below(0.0f), sum_above(0.0f);
    below = above = 0.0f;
    for (const auto& f : faces_) {
      VectorAreaSum vb, va;
      for (size_t i = 0; i < f.size(); ++i) {
        const vec3& a = f[i];
        const vec3& b = f[(i + 1) % f.size()];
        const float da = p.distance(a), db = p.distance(b);
        if (da <= 0.0f) vb.add(a);
        if (da >= 0.0f) va.add(a);
        if ((da < 0.0f && db > 0.0f) || (da > 0.0f && db < 0.0f)) {
          const vec3 x = a + (da / (da - db)) * (b - a);
          vb.add(x);
          va.add(x);
        }
      }
      const vec3 ab = vb.done(), aa = va.done();
      sum_below += ab;
      sum_above += aa;
      below += glm::length(ab);
      above += glm::length(aa);
    }
    below += glm::length(sum_below);
    above += glm::length(sum_above);
  }

  /// Bounds of the cell's vertices.
  AABB bounds() const {
    AABB b;
    for (const auto& f : faces_)
      for (const vec3& v : f) b.extend(v);
    return b;
  }

  /// The part on one side of plane, closed by the cut face.
  ConvexCell part(const BspPlane& p, bool below) const {
    ConvexCell out;
    std::vector<vec3> cut;
    for (const auto& f : faces_) {
      std::vector<vec3> g = clip(f, p, below);
      for (const vec3& v : g)
        if (std::fabs(p.distance(v)) <= 1e-6f * (1.0f + glm::length(v))) cut.push_back(v);
      if (g.size() >= 3) out.faces_.push_back(std::move(g));
    }
    if (cut.size() >= 3) out.faces_.push_back(order_cut(cut, below ? p.n : -p.n));
    return out;
  }

 private:
  /// Running vector area of a polygon given vertex by vertex.
  struct VectorAreaSum {
    vec3 first{0.0f}, last{0.0f}, sum{0.0f};
    int n = 0;
    void add(const vec3& v) {
      if (n++ == 0) first = v;
      else sum += glm::cross(last, v);
      last = v;
    }
    vec3 done() const { return n >= 3 ? 0.5f * (sum + glm::cross(last, first)) : vec3(0.0f); }
  };

  /// Half the sum of the edge cross products: normal times area.
  static vec3 vector_area(const std::vector<vec3>& f) {
    vec3 s(0.0f);
    for (size_t i = 0; i < f.size(); ++i) s += glm::cross(f[i], f[(i + 1) % f.size()]);
    return 0.5f * s;
  }

  /// Sutherland-Hodgman against one plane, keeping the below (or above) side.
  static std::vector<vec3> clip(const std::vector<vec3>& f, const BspPlane& p, bool below) {
    std::vector<vec3> out;
    const float sign = below ? 1.0f : -1.0f;
    for (size_t i = 0; i < f.size(); ++i) {
      const vec3& a = f[i];
      const vec3& b = f[(i + 1) % f.size()];
      const float da = sign * p.distance(a), db = sign * p.distance(b);
      if (da <= 0.0f) out.push_back(a);
      if ((da < 0.0f && db > 0.0f) || (da > 0.0f && db < 0.0f)) out.push_back(a + (da / (da - db)) * (b - a));
    }
    return out;
  }

  /// The cut face's vertices, without near-duplicates, in counter-clockwise order around outward normal n.
  static std::vector<vec3> order_cut(std::vector<vec3> pts, const vec3& n) {
    vec3 c(0.0f);
    for (const vec3& v : pts) c += v;
    c /= float(pts.size());
    const vec3 u = glm::normalize(std::fabs(n.x) < 0.9f ? glm::cross(n, vec3(1, 0, 0)) : glm::cross(n, vec3(0, 1, 0)));
    const vec3 w = glm::cross(n, u);
    std::sort(pts.begin(), pts.end(), [&](const vec3& a, const vec3& b) {
      return std::atan2(glm::dot(a - c, w), glm::dot(a - c, u)) < std::atan2(glm::dot(b - c, w), glm::dot(b - c, u));
    });
    std::vector<vec3> out;
    for (const vec3& v : pts)
      if (out.empty() || glm::length(v - out.back()) > 1e-7f * (1.0f + glm::length(v))) out.push_back(v);
    while (out.size() > 1 && glm::length(out.front() - out.back()) <= 1e-7f * (1.0f + glm::length(out.back())))
      out.pop_back();
    return out;
  }

  std::vector<std::vector<vec3>> faces_;
};

}  // namespace ab
