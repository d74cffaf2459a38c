// The convex cell of a BSP node as an explicit polyhedron (its face polygons, outward oriented), so that
// the surface-area cost of an arbitrary plane uses the true areas of the two parts (Ize, Wald and Parker
// 2008 track the cell the same way; a bounding box would make every oblique cut look useless). The area of
// a part is the area of the clipped faces plus that of the cut face, and the cut face's area comes free
// from the closed-surface identity: the outward vector areas of a closed polyhedron sum to zero.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

#include "accel/bsp/candidates.h"

namespace ab {

/// The rounding band of a vertex's signed distance from a plane: 1e-6 of floor + |v|, where floor is the
/// root cell's magnitude up to 1 (band_floor). An absolute floor of 1 was 3 % of a teapot scaled by 1e-5:
/// planes cutting such a cell were taken for no cut, cut faces' points merged (near_duplicate), and the
/// cells lost triangles of the teapot at 1e-5 and of the bunny at 1e-2 to 1e-4 (docs/structures.md).
inline float distance_band(const vec3& v, float floor) {
  return 1e-6f * (floor + robust_length(v));
}

/// The distance within which two points of a cut face are one (a tenth of distance_band).
inline float near_duplicate(const vec3& v, float floor) {
  return 1e-7f * (floor + robust_length(v));
}

/// The bands' absolute floor for a tree whose root cell is box b: its largest coordinate magnitude, at
/// most 1 (so a mesh of unit size or larger keeps the floor 1) and at least the smallest normal float.
inline float band_floor(const AABB& b) {
  const vec3 m = glm::max(glm::abs(b.lo), glm::abs(b.hi));
  const float mag = std::max({m.x, m.y, m.z});
  return mag < 1.0f ? std::max(mag, std::numeric_limits<float>::min()) : 1.0f;  // NaN: 1
}

/// Makes kept buffer v at least n long; it never shrinks, so once grown the call does nothing (its users
/// index it, never read its size).
template <class T>
inline void grow_buffer(std::vector<T>& v, size_t n) {
  if (v.size() < n) v.resize(n);
}

/// A convex polyhedron given by its faces (each a convex polygon, counter-clockwise seen from outside), kept
/// in one flat array of vertices with each face's first index (two allocations per cell, not one per face).
class ConvexCell {
 public:
  /// The six faces of box b, whose rounding bands have absolute floor `floor` (band_floor of the root's
  /// box; inherited by every part).
  static ConvexCell from_box(const AABB& b, float floor) {
    ConvexCell c;
    c.floor_ = floor;
    if (b.empty()) return c;
    auto corner = [&](int k) {
      return vec3((k & 1) ? b.hi.x : b.lo.x, (k & 2) ? b.hi.y : b.lo.y, (k & 4) ? b.hi.z : b.lo.z);
    };
    const int quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                             {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
    c.verts_.reserve(24);
    c.starts_.reserve(7);
    c.starts_.push_back(0);
    for (const auto& q : quads) {
      for (int k : q) c.verts_.push_back(corner(k));
      c.starts_.push_back(uint32_t(c.verts_.size()));
    }
    c.box_ = true;
    c.bounds_ = b;
    return c;
  }

  /// The rounding bands' absolute floor (from_box).
  float floor() const { return floor_; }

  /// True when the cell is its bounding box (the root's, cut by axis planes only).
  bool is_box() const { return box_; }

  /// Number of faces.
  size_t face_count() const { return starts_.empty() ? 0 : starts_.size() - 1; }
  /// Face k's vertices.
  std::span<const vec3> face(size_t k) const {
    return {verts_.data() + starts_[k], verts_.data() + starts_[k + 1]};
  }

  /// Surface area.
  float area() const {
    float a = 0.0f;
    for (size_t k = 0; k < face_count(); ++k) a += robust_length(vector_area(face(k)));
    return a;
  }

  /// Areas of the parts below and above plane (each including the cut face). Streams the clipped
  /// polygons' vector areas without building them.
  void areas(const BspPlane& p, float& below, float& above) const {
    vec3 sum_below(0.0f), sum_above(0.0f);
    below = above = 0.0f;
    for (size_t k = 0; k < face_count(); ++k) {
      const std::span<const vec3> f = face(k);
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
      below += robust_length(ab);
      above += robust_length(aa);
    }
    below += robust_length(sum_below);
    above += robust_length(sum_above);
  }

  /// Every face's vertices, face after face (for CellSurface).
  std::span<const vec3> vertices() const { return verts_; }

  /// Bounds of the cell's vertices.
  const AABB& bounds() const { return bounds_; }

  /// The part on one side of plane, closed by the cut face.
  /// A plane that does not cut the cell (every vertex within rounding of it or on one side, for example
  /// one of the cell's own faces) leaves the whole cell on that side, so no face is ever duplicated; the
  /// other side, when asked for, is the whole cell too (side()).
  ConvexCell part(const BspPlane& p, bool below) const {
    std::pair<ConvexCell, ConvexCell> both = parts_of(p, below ? kBelow : kAbove);
    return below ? std::move(both.first) : std::move(both.second);
  }
  /// Both parts (below, above) of part(): the vertices' distances from the plane computed once. Only the
  /// parts asked for (`below`, `above`) are made; the others are left empty.
  std::pair<ConvexCell, ConvexCell> parts(const BspPlane& p, bool below = true, bool above = true) const {
    return parts_of(p, (below ? kBelow : 0) | (above ? kAbove : 0));
  }

 private:
  static constexpr int kBelow = 1, kAbove = 2;

  /// The parts of part() on the sides in `which` (the others left empty).
  std::pair<ConvexCell, ConvexCell> parts_of(const BspPlane& p, int which) const {
    thread_local std::vector<float> dist, tol;
    grow_buffer(dist, verts_.size());
    grow_buffer(tol, verts_.size());
    bool pos = false, neg = false;  // some vertex clearly above, clearly below
    for (size_t i = 0; i < verts_.size(); ++i) {
      dist[i] = p.distance(verts_[i]);
      tol[i] = distance_band(verts_[i], floor_);
      pos |= dist[i] > tol[i];
      neg |= dist[i] < -tol[i];
    }
    std::pair<ConvexCell, ConvexCell> out;
    if (which & kBelow) out.first = side(p, true, neg, pos, dist, tol);
    if (which & kAbove) out.second = side(p, false, pos, neg, dist, tol);
    return out;
  }

  /// The part on one side: `keeps` (some vertex clearly on that side), `removes` (some on the other).
  ConvexCell side(const BspPlane& p, bool below, bool keeps, bool removes, const std::vector<float>& dist,
                  const std::vector<float>& tol) const {
    // No vertex clearly on the other side: the whole cell. No vertex clearly on this side: the part is a
    // sliver within rounding of the plane, or nothing; it is asked for only when primitives were placed on
    // this side (within the insertion margin), so it is the whole cell too, which is conservative for the
    // parts clipped to its box. (It was the empty cell, and those primitives lost their parts: an outside
    // check found the bsp missing hits on a teapot moved to 3e4.)
    if (!keeps || !removes) return *this;
    if (const int a = exact_axis(p); box_ && a >= 0) {
      // A box cut by an axis plane is a box: the k-d tree's split of the box instead of a polyhedron clip.
      AABB b = bounds_;
      (below ? b.hi : b.lo)[a] = p.d;
      return from_box(b, floor_);
    }
    ConvexCell out;
    out.floor_ = floor_;
    out.verts_.reserve(verts_.size() + 8);
    out.starts_.reserve(face_count() + 2);
    out.starts_.push_back(0);
    thread_local std::vector<vec3> cut;
    cut.clear();
    const float sign = below ? 1.0f : -1.0f;
    for (size_t k = 0; k < face_count(); ++k) {
      const size_t first = out.verts_.size();
      clip(k, p, sign, dist, tol, out.verts_, cut);
      if (out.verts_.size() - first >= 3)
        out.starts_.push_back(uint32_t(out.verts_.size()));
      else
        out.verts_.resize(first);
    }
    if (cut.size() >= 3) {
      order_cut(cut, below ? p.n : -p.n, floor_, out.verts_);
      out.starts_.push_back(uint32_t(out.verts_.size()));
    }
    for (const vec3& v : out.verts_) out.bounds_.extend(v);
    return out;
  }

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
  static vec3 vector_area(std::span<const vec3> f) {
    // Fanned from the first vertex (edge vectors, not positions): far from the origin (1e6, the `far`
    // generator) the cross products of positions cancel to noise.
    vec3 s(0.0f);
    for (size_t i = 2; i < f.size(); ++i) s += glm::cross(f[i - 1] - f[0], f[i] - f[0]);
    return 0.5f * s;
  }

  /// Sutherland-Hodgman of face k against plane p, whose signed distances (times sign: keeping the below
  /// side for sign 1, the above side for -1) are dist, with each vertex's rounding band tol; appends the
  /// kept polygon to out, and its points within rounding of the plane to cut.
  void clip(size_t k, const BspPlane& p, float sign, const std::vector<float>& dist,
            const std::vector<float>& tol, std::vector<vec3>& out, std::vector<vec3>& cut) const {
    const uint32_t b0 = starts_[k], m = starts_[k + 1] - b0;
    for (uint32_t i = 0; i < m; ++i) {
      const uint32_t j = i + 1 == m ? 0 : i + 1;
      const vec3 &a = verts_[b0 + i], &b = verts_[b0 + j];
      const float da = sign * dist[b0 + i], db = sign * dist[b0 + j];
      if (da <= 0.0f) {
        out.push_back(a);
        if (std::fabs(dist[b0 + i]) <= tol[b0 + i]) cut.push_back(a);
      }
      if ((da < 0.0f && db > 0.0f) || (da > 0.0f && db < 0.0f)) {
        const vec3 x = a + (da / (da - db)) * (b - a);
        out.push_back(x);
        if (std::fabs(p.distance(x)) <= distance_band(x, floor_)) cut.push_back(x);
      }
    }
  }

  /// Appends the cut face's vertices pts, without near-duplicates, in counter-clockwise order around
  /// outward normal n.
  static void order_cut(std::vector<vec3>& pts, const vec3& n, float floor, std::vector<vec3>& out) {
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
    thread_local std::vector<std::pair<float, uint32_t>> keys;  // each point's angle, computed once
    keys.clear();
    for (size_t i = 0; i < pts.size(); ++i) keys.emplace_back(angle(pts[i]), uint32_t(i));
    std::sort(keys.begin(), keys.end());
    const size_t first = out.size();
    for (const auto& [key, i] : keys)
      if (const vec3& v = pts[i];
          out.size() == first || robust_length(v - out.back()) > near_duplicate(v, floor))
        out.push_back(v);
    while (out.size() > first + 1 &&
           robust_length(out[first] - out.back()) <= near_duplicate(out.back(), floor))
      out.pop_back();
  }

  std::vector<vec3> verts_;  ///< every face's vertices, face after face
  /// Face k is verts_[starts_[k], starts_[k + 1]); empty for an empty cell (no allocation for the empty
  /// cells a split's parts start as).
  std::vector<uint32_t> starts_;
  AABB bounds_;         ///< bounds of verts_
  bool box_ = false;    ///< the faces are those of an axis-aligned box (from_box)
  float floor_ = 1.0f;  ///< the rounding bands' absolute floor (from_box)
};

/// The areas of a box cell cut by axis planes, in closed form (the k-d tree's SAH areas): the same
/// interface as CellSurface (extent, areas along one of the three axes) for the nodes above oblique_max,
/// whose cells are boxes, without triangulating the cell's surface.
class BoxSurface {
 public:
  /// The surface of box cell c.
  explicit BoxSurface(const ConvexCell& c) : box_(c.bounds()) {
    for (const vec3& v : {box_.lo, box_.hi}) tol_ = std::max(tol_, distance_band(v, c.floor()));
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
/// gives the same areas up to rounding). The triangles are kept field by field (structure of arrays), so
/// that a direction's heights are computed kLanes triangles at a time, and kept for the next call with the
/// same direction (extent, then areas).
class CellSurface {
 public:
  /// Fan-triangulates the faces of cell.
  explicit CellSurface(const ConvexCell& cell) { assign(cell); }
  /// An empty surface (assign gives it a cell).
  CellSurface() = default;

  /// Makes this the surface of cell, keeping the buffers (one per thread in the BSP build).
  void assign(const ConvexCell& cell) {
    count_ = 0;
    total_ = 0.0f;
    tol_ = 0.0f;
    size_t most = 0;  // the triangles of the fans, before those of no area are left out
    for (size_t k = 0; k < cell.face_count(); ++k) most += std::max<size_t>(cell.face(k).size(), 2) - 2;
    for (auto& f : in_) grow_buffer(f, most);  // written by index (add), up to count_
    for (size_t k = 0; k < cell.face_count(); ++k) {
      const std::span<const vec3> f = cell.face(k);
      for (size_t i = 2; i < f.size(); ++i) add(f[0], f[i - 1], f[i]);
    }
    for (const vec3& v : cell.vertices()) tol_ = std::max(tol_, distance_band(v, cell.floor()));
    padded_ = (count_ + kLanes - 1) / kLanes * kLanes;
    // Padding lanes: h0 = +inf and h2 = -inf (no part below any plane, and no effect on the extent),
    // zero area.
    heights_.assign(kFields * padded_, 0.0f);
    for (size_t i = count_; i < padded_; ++i) {
      heights_[i] = kInf;
      heights_[2 * padded_ + i] = -kInf;
    }
    std::copy(in_[kArea].begin(), in_[kArea].begin() + ptrdiff_t(count_),
              heights_.begin() + ptrdiff_t(5 * padded_));
    prepared_ = false;
  }

  /// Surface area.
  float area() const { return total_; }

  /// The cell's extent [lo, hi] along direction n.
  void extent(const vec3& n, float& lo, float& hi) const {
    prepare(n);
    lo = lowest_;
    hi = highest_;
  }

  /// The width of the vectors the area profile is computed in: the target's, 16 floats with AVX-512 and 8
  /// without (a 16-float vector on an AVX2 target, a Zen 3 host, went through the stack, its selects piece
  /// by piece: 37 % of the 1M sphereflake's bsp build in area_below). Any width gives the same bits: each
  /// of the kLanes lanes does the same operations in the same order.
#if defined(__AVX512F__)
  static constexpr size_t kChunk = 16;
#else
  static constexpr size_t kChunk = 8;
#endif

  /// Areas of the parts below and above each plane dot(n, x) = d[k] (each including the cut face); a
  /// plane within rounding of the cell's extent along n does not cut it (one part gets zero area). Chunk:
  /// the vector width (kChunk; another only in the test that the widths agree).
  template <size_t Chunk = kChunk>
  void areas(const vec3& n, std::span<const float> d, float* below, float* above) const {
    prepare(n);
    // The planes that cut the cell, the others within rounding of its extent (no cut, as part).
    thread_local std::vector<uint32_t> cutting;  // the first `count`, written by index (no push_back call)
    grow_buffer(cutting, d.size());
    size_t count = 0;
    for (size_t k = 0; k < d.size(); ++k) {
      if (!(d[k] > lowest_ + tol_)) {
        below[k] = 0.0f;
        above[k] = total_;
      } else if (!(d[k] < highest_ - tol_)) {
        below[k] = total_;
        above[k] = 0.0f;
      } else {
        cutting[count++] = uint32_t(k);
      }
    }
    for (size_t q = 0; q < count; ++q) {
      float sb, sc;
      area_below<Chunk>(d[cutting[q]], sb, sc);
      const size_t k = cutting[q];
      const float x = std::max(sc, 0.0f);
      above[k] = std::max(total_ - sb, 0.0f) + x;
      below[k] = sb + x;
    }
  }

 private:
  /// The input fields, one array each: the three corners' coordinates, the area and the unit normal.
  enum In { kAx, kAy, kAz, kBx, kBy, kBz, kCx, kCy, kCz, kArea, kNx, kNy, kNz, kInFields };

  /// Appends triangle (a, b, c) unless it has no area.
  void add(const vec3& a, const vec3& b, const vec3& c) {
    const vec3 cr = glm::cross(b - a, c - a);
    const float twice = robust_length(cr);
    if (!(twice > 0.0f)) return;
    const vec3 nrm = cr / twice;
    const float v[kInFields] = {a.x, a.y, a.z,          b.x,   b.y,   b.z,  c.x,
                                c.y, c.z, 0.5f * twice, nrm.x, nrm.y, nrm.z};
    for (size_t f = 0; f < kInFields; ++f) in_[f][count_] = v[f];
    total_ += 0.5f * twice;
    ++count_;
  }

  /// prepare's fields of the count triangles of in (field by field) along n, into out (padded each; the
  /// area is there already, set by assign). Two loops, as one with every field is not vectorized.
  static void heights(size_t count, size_t padded, const vec3& n,
                      const std::array<std::vector<float>, kInFields>& in, float* __restrict out) {
    float* __restrict h0 = out, * __restrict h1 = h0 + padded, * __restrict h2 = h1 + padded;
    float* __restrict il = h2 + padded, * __restrict ih = il + padded, * __restrict weighted = ih + 2 * padded;
    const float *ax = in[kAx].data(), *ay = in[kAy].data(), *az = in[kAz].data();
    const float *bx = in[kBx].data(), *by = in[kBy].data(), *bz = in[kBz].data();
    const float *cx = in[kCx].data(), *cy = in[kCy].data(), *cz = in[kCz].data();
    const float x = n.x, y = n.y, z = n.z;
    for (size_t i = 0; i < count; ++i) {  // vectorized: a vector of triangles at a time
      const float ha = x * ax[i] + y * ay[i] + z * az[i];
      const float hb = x * bx[i] + y * by[i] + z * bz[i];
      const float hc = x * cx[i] + y * cy[i] + z * cz[i];
      const float lo = std::min(ha, hb), hi = std::max(ha, hb);
      const float top = std::max(hi, hc), m = std::min(hi, hc);
      const float low = std::min(lo, m), mid = std::max(lo, m);
      h0[i] = low;
      h1[i] = mid;
      h2[i] = top;
      il[i] = 1.0f / ((mid - low) * (top - low));
      ih[i] = 1.0f / ((top - low) * (top - mid));
    }
    const float *ar = in[kArea].data(), *nx = in[kNx].data(), *ny = in[kNy].data(), *nz = in[kNz].data();
    for (size_t i = 0; i < count; ++i) weighted[i] = (x * nx[i] + y * ny[i] + z * nz[i]) * ar[i];
  }

  using Lanes8 = float __attribute__((vector_size(8 * sizeof(float))));    ///< 8 floats as one value
  using Lanes16 = float __attribute__((vector_size(16 * sizeof(float))));  ///< 16 floats as one value
  /// The smallest of the 8 lanes of v (halves, quarters, pairs).
  static float lowest_of(Lanes8 v) {
    using M = int32_t __attribute__((vector_size(8 * sizeof(int32_t))));
    for (const M& m : {M{4, 5, 6, 7, 0, 1, 2, 3}, M{2, 3, 0, 1, 6, 7, 4, 5}, M{1, 0, 3, 2, 5, 4, 7, 6}}) {
      const Lanes8 w = __builtin_shuffle(v, m);
      v = w < v ? w : v;
    }
    return v[0];
  }

  /// The heights of every triangle along n, sorted, with the reciprocals of the two quadratics'
  /// denominators, the area and the area times dot(n, normal), field by field (heights_), and the
  /// extent; nothing when they are those of n already.
  void prepare(const vec3& n) const {
    if (prepared_ && n == dir_) return;
    prepared_ = true;
    dir_ = n;
    const size_t padded = padded_;
    heights(count_, padded, n, in_, heights_.data());
    const float *h0 = heights_.data(), *h2 = h0 + 2 * padded;
    // Each block's lowest h0 and the extent, in vectors of 8 (a block's minimum as a scalar chain was
    // most of prepare's instructions). Minima and maxima of finite heights in any order: the same values
    // (a zero's sign aside, which no comparison or difference below tells apart).
    static_assert(kLanes == 16, "a block is two vectors of 8");
    Lanes8 lo = Lanes8{} + kInf, hi = Lanes8{} - kInf;
    grow_buffer(block_low_, padded / kLanes);
    for (size_t i = 0; i < padded; i += kLanes) {
      Lanes8 a, b, c, e;
      std::memcpy(&a, h0 + i, sizeof(Lanes8));
      std::memcpy(&b, h0 + i + 8, sizeof(Lanes8));
      std::memcpy(&c, h2 + i, sizeof(Lanes8));
      std::memcpy(&e, h2 + i + 8, sizeof(Lanes8));
      const Lanes8 low = b < a ? b : a;
      lo = low < lo ? low : lo;
      const Lanes8 high = e > c ? e : c;
      hi = high > hi ? high : hi;
      block_low_[i / kLanes] = lowest_of(low);
    }
    lowest_ = lowest_of(lo);
    highest_ = -lowest_of(-hi);  // exact: negation only flips the sign
  }

  /// The surface's area below d (sb) and the cut face's share (sc): kLanes triangles at a time, one
  /// accumulator per lane, in vectors of Chunk lanes (GCC's vector extension: the per-lane sums stay in
  /// registers from block to block; as arrays they went through memory every block, behind a run-time
  /// aliasing check), and the lanes added pairwise (halves, lane_sum; they were stored and added one after
  /// another, a chain of 32 additions per plane, and most calls price only a few planes).
  template <size_t Chunk>
  void area_below(float d, float& sb, float& sc) const {
    using Lanes = std::conditional_t<Chunk == 8, Lanes8, Lanes16>;
    constexpr size_t kChunks = kLanes / Chunk;  // chunks per block of kLanes triangles
    static_assert((Chunk == 8 || Chunk == 16) && kChunks * Chunk == kLanes);
    Lanes b[kChunks] = {}, c[kChunks] = {};
    const Lanes at = d - Lanes{}, one = 1.0f - Lanes{};  // broadcasts (x - 0 is x, -0 included)
    const size_t padded = padded_;
    const float *h0 = heights_.data(), *h1 = h0 + padded, *h2 = h1 + padded, *il = h2 + padded;
    const float *ih = il + padded, *area = ih + padded, *weighted = area + padded;
    for (size_t i = 0; i < padded; i += kLanes) {
      // A block whose triangles all start at or above d adds zero to every lane (exactly: no lane's sum
      // is ever -0), so it is skipped; block_low_ is its lowest h0.
      if (!(d > block_low_[i / kLanes])) continue;
      for (size_t q = 0; q < kChunks; ++q) {
        const size_t at_i = i + q * Chunk;
        Lanes v0, v1, v2, vl, vh, va, vw;
        std::memcpy(&v0, h0 + at_i, sizeof(Lanes));
        std::memcpy(&v1, h1 + at_i, sizeof(Lanes));
        std::memcpy(&v2, h2 + at_i, sizeof(Lanes));
        std::memcpy(&vl, il + at_i, sizeof(Lanes));
        std::memcpy(&vh, ih + at_i, sizeof(Lanes));
        std::memcpy(&va, area + at_i, sizeof(Lanes));
        std::memcpy(&vw, weighted + at_i, sizeof(Lanes));
        // The fraction of each triangle's area below d, without branches (the reciprocal of a zero
        // denominator, and a padding lane's, is only ever in a lane the selects discard).
        const Lanes lo = at - v0, hi = v2 - at;
        Lanes f = at < v1 ? lo * lo * vl : one - hi * hi * vh;
        f = at > v0 ? f : Lanes{};
        f = at < v2 ? f : (at > v0 ? one : Lanes{});
        b[q] += va * f;
        c[q] += vw * f;
      }
    }
    sb = lane_sum(halves(b));
    sc = 0.0f - lane_sum(halves(c));
  }
  /// The sums of lanes l and l + 8 of a block's kLanes per-lane sums s (kChunks vectors of Chunk lanes).
  template <class Lanes, size_t N>
  static Lanes8 halves(const Lanes (&s)[N]) {
    if constexpr (N == 2) {
      return s[0] + s[1];
    } else {
      Lanes8 lo, hi;
      std::memcpy(&lo, &s[0], sizeof(Lanes8));
      std::memcpy(&hi, reinterpret_cast<const float*>(&s[0]) + 8, sizeof(Lanes8));
      return lo + hi;
    }
  }
  /// The sum of v's lanes, pairwise: lanes l and l + 4, then l and l + 2, then the two (the same order in
  /// every vector width, so the same bits).
  static float lane_sum(Lanes8 v) {
    using M = int32_t __attribute__((vector_size(8 * sizeof(int32_t))));
    v += __builtin_shuffle(v, M{4, 5, 6, 7, 0, 1, 2, 3});
    v += __builtin_shuffle(v, M{2, 3, 0, 1, 6, 7, 4, 5});
    return v[0] + v[1];
  }
  static constexpr size_t kLanes = 16, kFields = 7;

  std::array<std::vector<float>, kInFields> in_;  ///< the triangles, field by field
  size_t count_ = 0, padded_ = 0;                 ///< triangles, and rounded up to kLanes
  mutable std::vector<float> block_low_;          ///< each block of kLanes triangles' lowest h0 along dir_
  mutable std::vector<float> heights_;  ///< prepare's fields for dir_, field by field (padded_ each)
  mutable vec3 dir_{0.0f};
  mutable bool prepared_ = false;
  mutable float lowest_ = kInf, highest_ = -kInf;  ///< the extent along dir_
  float total_ = 0.0f;
  float tol_ = 0.0f;  ///< rounding band of a vertex's distance from a plane (as ConvexCell::part)
};

}  // namespace ab
