// The convex cell of a BSP node as an explicit polyhedron (its face polygons, outward oriented), so that
// the surface-area cost of an arbitrary plane uses the true areas of the two parts (Ize, Wald and Parker
// 2008 track the cell the same way; a bounding box would make every oblique cut look useless). The area of
// a part is the area of the clipped faces plus that of the cut face, and the cut face's area comes free
// from the closed-surface identity: the outward vector areas of a closed polyhedron sum to zero.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <span>
#include <vector>

#include "accel/bsp/candidates.h"

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
    const int quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                             {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
    for (const auto& q : quads) c.faces_.push_back({corner(q[0]), corner(q[1]), corner(q[2]), corner(q[3])});
    c.box_ = true;
    return c;
  }

  /// True when the cell is its bounding box (the root's, cut by axis planes only).
  bool is_box() const { return box_; }

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

  /// Faces (for CellSurface).
  const std::vector<std::vector<vec3>>& faces() const { return faces_; }

  /// Bounds of the cell's vertices.
  AABB bounds() const {
    AABB b;
    for (const auto& f : faces_)
      for (const vec3& v : f) b.extend(v);
    return b;
  }

  /// The part on one side of plane, closed by the cut face.
  /// A plane that does not cut the cell (every vertex within rounding of it or on one side, for example
  /// one of the cell's own faces) leaves the whole cell on that side and nothing on the other, so no
  /// face is ever duplicated.
  ConvexCell part(const BspPlane& p, bool below) const {
    bool removes = false, keeps = false;
    for (const auto& f : faces_)
      for (const vec3& v : f) {
        const float s = below ? p.distance(v) : -p.distance(v);
        const float tol = 1e-6f * (1.0f + glm::length(v));
        removes |= s > tol;
        keeps |= s < -tol;
      }
    if (!keeps) return ConvexCell{};
    if (!removes) return *this;
    if (const int a = exact_axis(p); box_ && a >= 0) {
      // A box cut by an axis plane is a box: the k-d tree's split of the box instead of a polyhedron clip.
      AABB b = bounds();
      (below ? b.hi : b.lo)[a] = p.d;
      return from_box(b);
    }
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
      if (n++ == 0)
        first = v;
      else
        sum += glm::cross(last, v);
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
    const vec3 u =
        glm::normalize(std::fabs(n.x) < 0.9f ? glm::cross(n, vec3(1, 0, 0)) : glm::cross(n, vec3(0, 1, 0)));
    const vec3 w = glm::cross(n, u);
    // A pseudo-angle (monotonic in the angle, no atan2): position on the unit diamond, 0..4.
    auto angle = [&](const vec3& p) {
      const float x = glm::dot(p - c, u), y = glm::dot(p - c, w);
      const float r = std::fabs(x) + std::fabs(y);
      if (!(r > 0.0f)) return 0.0f;
      const float q = y / r;
      return x >= 0.0f ? (y >= 0.0f ? q : 4.0f + q) : 2.0f - q;
    };
    std::sort(pts.begin(), pts.end(), [&](const vec3& a, const vec3& b) { return angle(a) < angle(b); });
    std::vector<vec3> out;
    for (const vec3& v : pts)
      if (out.empty() || glm::length(v - out.back()) > 1e-7f * (1.0f + glm::length(v))) out.push_back(v);
    while (out.size() > 1 &&
           glm::length(out.front() - out.back()) <= 1e-7f * (1.0f + glm::length(out.back())))
      out.pop_back();
    return out;
  }

  std::vector<std::vector<vec3>> faces_;
  bool box_ = false;  ///< the faces are those of an axis-aligned box (from_box)
};

/// The areas of a box cell cut by axis planes, in closed form (the k-d tree's SAH areas): the same
/// interface as CellSurface (extent, areas along one of the three axes) for the nodes above oblique_max,
/// whose cells are boxes, without triangulating the cell's surface.
class BoxSurface {
 public:
  /// The surface of box b.
  explicit BoxSurface(const AABB& b) : box_(b) {
    for (const vec3& v : {b.lo, b.hi}) tol_ = std::max(tol_, 1e-6f * (1.0f + glm::length(v)));
  }

  /// Surface area.
  float area() const { return box_.area(); }
  /// The box's extent [lo, hi] along axis n.
  void extent(const vec3& n, float& lo, float& hi) const {
    const int a = axis(n);
    lo = box_.lo[a];
    hi = box_.hi[a];
  }
  /// Areas of the boxes below and above each plane dot(n, x) = d[k] along axis n; a plane within
  /// rounding of the box's extent does not cut it (one part gets zero area), as CellSurface::areas.
  void areas(const vec3& n, std::span<const float> d, float* below, float* above) const {
    const int a = axis(n), b = (a + 1) % 3, c = (a + 2) % 3;
    const vec3 e = box_.hi - box_.lo;
    const float caps = 2.0f * e[b] * e[c], ring = 2.0f * (e[b] + e[c]), total = area();
    for (size_t k = 0; k < d.size(); ++k) {
      const float t = d[k] - box_.lo[a];
      if (!(d[k] > box_.lo[a] + tol_)) {
        below[k] = 0.0f;
        above[k] = total;
      } else if (!(d[k] < box_.hi[a] - tol_)) {
        below[k] = total;
        above[k] = 0.0f;
      } else {
        below[k] = caps + ring * t;
        above[k] = caps + ring * (e[a] - t);
      }
    }
  }

 private:
  static int axis(const vec3& n) { return n.x != 0.0f ? 0 : (n.y != 0.0f ? 1 : 2); }
  AABB box_;
  float tol_ = 0.0f;  ///< rounding band of a plane at the box's faces (as CellSurface)
};

/// The cell's surface as triangles, for evaluating many planes of one direction at once. The area of a
/// triangle below the plane dot(n, x) = d is a piecewise quadratic in d given the heights h0 <= h1 <= h2
/// of its vertices along n; a clipped face keeps its normal, so by the closed-surface identity the cut
/// face's area is -sum(dot(n, N_i) a_i(d)) over the faces' unit normals N_i and areas below a_i(d). Each
/// plane then costs a few flops per surface triangle instead of clipping the polyhedron (ConvexCell::areas
/// gives the same areas up to rounding).
class CellSurface {
 public:
  /// Fan-triangulates the faces of cell.
  explicit CellSurface(const ConvexCell& cell) { assign(cell); }
  /// An empty surface (assign gives it a cell).
  CellSurface() = default;

  /// Makes this the surface of cell, keeping the buffers (one per thread in the BSP build).
  void assign(const ConvexCell& cell) {
    tris_.clear();
    total_ = 0.0f;
    tol_ = 0.0f;
    for (const auto& f : cell.faces())
      for (size_t i = 2; i < f.size(); ++i) {
        const vec3 cr = glm::cross(f[i - 1] - f[0], f[i] - f[0]);
        const float twice = glm::length(cr);
        if (!(twice > 0.0f)) continue;
        tris_.push_back({f[0], f[i - 1], f[i], 0.5f * twice, cr / twice});
        total_ += 0.5f * twice;
      }
    for (const auto& f : cell.faces())
      for (const vec3& v : f) tol_ = std::max(tol_, 1e-6f * (1.0f + glm::length(v)));
  }

  /// Surface area.
  float area() const { return total_; }

  /// The cell's extent [lo, hi] along direction n.
  void extent(const vec3& n, float& lo, float& hi) const {
    lo = kInf;
    hi = -kInf;
    for (const Tri& t : tris_)
      for (const vec3& v : {t.a, t.b, t.c}) {
        lo = std::min(lo, glm::dot(n, v));
        hi = std::max(hi, glm::dot(n, v));
      }
  }

  /// Areas of the parts below and above each plane dot(n, x) = d[k] (each including the cut face); a
  /// plane within rounding of the cell's extent along n does not cut it (one part gets zero area).
  void areas(const vec3& n, std::span<const float> d, float* below, float* above) const {
    float* cut = above;  // the cut face's area goes to above[] until the end
    float lowest = kInf, highest = -kInf;
    const size_t chunks = (tris_.size() + kLanes - 1) / kLanes;
    heights_.assign(chunks * kFields * kLanes, 0.0f);  // padding: zero area, so it adds nothing
    for (size_t i = 0; i < tris_.size(); ++i) {
      const Tri& t = tris_[i];
      float h[3] = {glm::dot(n, t.a), glm::dot(n, t.b), glm::dot(n, t.c)};
      if (h[0] > h[1]) std::swap(h[0], h[1]);
      if (h[1] > h[2]) std::swap(h[1], h[2]);
      if (h[0] > h[1]) std::swap(h[0], h[1]);
      lowest = std::min(lowest, h[0]);
      highest = std::max(highest, h[2]);
      const float fields[kFields] = {h[0],
                                     h[1],
                                     h[2],
                                     1.0f / ((h[1] - h[0]) * (h[2] - h[0])),
                                     1.0f / ((h[2] - h[0]) * (h[2] - h[1])),
                                     t.area,
                                     glm::dot(n, t.normal) * t.area};
      float* chunk = &heights_[i / kLanes * kFields * kLanes + i % kLanes];
      for (size_t f = 0; f < kFields; ++f) chunk[f * kLanes] = fields[f];
    }
    for (size_t k = 0; k < d.size(); ++k) area_below(d[k], below[k], cut[k]);
    for (size_t k = 0; k < d.size(); ++k) {
      if (!(d[k] >
            lowest + tol_)) {  // within rounding of the cell's lowest vertex: no cut (as ConvexCell::part)
        below[k] = 0.0f;
        above[k] = total_;
      } else if (!(d[k] < highest - tol_)) {
        below[k] = total_;
        above[k] = 0.0f;
      } else {
        const float x = std::max(cut[k], 0.0f);  // cut aliases above: read before writing
        above[k] = std::max(total_ - below[k], 0.0f) + x;
        below[k] += x;
      }
    }
  }

 private:
  struct Tri {
    vec3 a, b, c;
    float area;
    vec3 normal;
  };

  /// Sums of the surface's area below d and of the cut face's share, over kLanes triangles at a time
  /// (one accumulator per lane: the loop over the lanes is vectorized). The heights are kept by chunks of
  /// kLanes triangles, field by field: h0, h1, h2 (sorted), the reciprocals of the two quadratics'
  /// denominators, the area and the area times dot(n, normal).
  void area_below(float d, float& below, float& cut) const {
    std::array<float, kLanes> b{}, c{};
    for (size_t i = 0; i < heights_.size(); i += kFields * kLanes) {
      const float *h0 = &heights_[i], *h1 = h0 + kLanes, *h2 = h1 + kLanes, *il = h2 + kLanes;
      const float *ih = il + kLanes, *area = ih + kLanes, *weighted = area + kLanes;
      for (size_t l = 0; l < kLanes; ++l) {
        // The fraction of the triangle's area below d, without branches (the reciprocal of a zero
        // denominator is only ever in a lane the selects discard).
        const float lo = d - h0[l], hi = h2[l] - d;
        float f = d < h1[l] ? lo * lo * il[l] : 1.0f - hi * hi * ih[l];
        f = d > h0[l] ? f : 0.0f;
        f = d < h2[l] ? f : (d > h0[l] ? 1.0f : 0.0f);
        b[l] += area[l] * f;
        c[l] += weighted[l] * f;
      }
    }
    below = 0.0f;
    cut = 0.0f;
    for (size_t l = 0; l < kLanes; ++l) {
      below += b[l];
      cut -= c[l];
    }
  }
  static constexpr size_t kLanes = 16, kFields = 7;

  std::vector<Tri> tris_;
  mutable std::vector<float> heights_;  ///< areas()'s scratch (area_below), kept over the node's directions
  float total_ = 0.0f;
  float tol_ = 0.0f;  ///< rounding band of a vertex's distance from a plane (as ConvexCell::part)
};

}  // namespace ab
