// CGAL's AABB tree as a peer. Kept in this one translation unit: CGAL's headers take about 12 s to compile
// and want -frounding-math, which CMake gives this file alone.
#include "accel/reference/cgal.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/version_macros.h>

#include <vector>

#include "accel/core/registry.h"
#include "accel/reference/peer.h"

namespace ab {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;

/// A primitive that is only the triangle id: the datum (CGAL's triangle) is made on the fly from the shared
/// triangle set, as CGAL's AABB_tree manual describes for primitives with shared data.
struct TrianglePrimitive {
  using Id = uint32_t;
  using Point = Kernel::Point_3;
  using Datum = Kernel::Triangle_3;
  using Shared_data = const TrianglePrims*;

  TrianglePrimitive() = default;
  template <class It>
  TrianglePrimitive(It it, Shared_data) : id_(*it) {}

  Id id() const { return id_; }
  static Point point(const vec3& p) { return Point(p.x, p.y, p.z); }
  Datum datum(Shared_data prims) const {
    const Triangle& t = prims->triangle(id_);
    return Datum(point(t.v0), point(t.v1), point(t.v2));
  }
  Point reference_point(Shared_data prims) const { return point(prims->triangle(id_).v0); }
  static Shared_data construct_shared_data(Shared_data prims) { return prims; }

  Id id_ = 0;
};

using Traits = CGAL::AABB_traits<Kernel, TrianglePrimitive>;
using AabbTree = CGAL::AABB_tree<Traits>;

/// Triangles CGAL reported as lying in the ray's plane (a Segment_3), skipped when it shoots again.
struct CoplanarSkip {
  static constexpr int kMax = 8;
  uint32_t ids[kMax];
  int count = 0;
  bool operator()(uint32_t id) const {
    for (int k = 0; k < count; ++k)
      if (ids[k] == id) return true;
    return false;
  }
};

/// The point at distance s along the ray, in double (one rounding per coordinate).
Point point_at(const Ray& ray, double s) {
  const glm::dvec3 p = glm::dvec3(ray.org) + s * glm::dvec3(ray.dir);
  return Point(p.x, p.y, p.z);
}

bool zero_direction(const Ray& ray) {
  return ray.dir.x == 0.0f && ray.dir.y == 0.0f && ray.dir.z == 0.0f;
}

}  // namespace

struct CgalMesh::Tree {
  AabbTree tree;
};

CgalMesh::CgalMesh(std::shared_ptr<const TrianglePrims> prims, const Config&) : PeerMesh(std::move(prims)) {}

CgalMesh::~CgalMesh() = default;

void CgalMesh::do_build() {
  tree_ = std::make_unique<Tree>();
  std::vector<uint32_t> ids;
  ids.reserve(prims_->size());
  skipped_ = 0;
  for (uint32_t i = 0; i < prims_->size(); ++i) {
    const Triangle& t = prims_->triangle(i);
    const Point a = TrianglePrimitive::point(t.v0), b = TrianglePrimitive::point(t.v1),
                c = TrianglePrimitive::point(t.v2);
    if (CGAL::collinear(a, b, c)) {  // exact under Epick; a zero-area triangle never hits
      ++skipped_;
      continue;
    }
    ids.push_back(i);
  }
  tree_->tree.insert(ids.begin(), ids.end(), prims_.get());
  tree_->tree.build();  // now, not lazily at the first query (which would take a lock)
}

void CgalMesh::gather_stats(BuildStats& stats) const {
  const uint64_t n = tree_ ? tree_->tree.size() : 0;
  stats.primitives = prims_->size();
  stats.references = n;
  stats.nodes = n > 1 ? n - 1 : 0;  // CGAL's tree: n - 1 nodes over n primitives, two children each
  stats.leaves = n;
  stats.bytes = n * sizeof(TrianglePrimitive) + stats.nodes * sizeof(CGAL::AABB_node<Traits>);
  stats.extra["note"] =
      "bytes computed (CGAL does not expose its memory): nodes x sizeof(AABB_node) + primitives x "
      "sizeof(primitive id)";
  stats.extra["collinear_skipped"] = skipped_;
  stats.extra["version"] = CGAL_VERSION_STR;
}

// Ray shooting as in CGAL's AABB_tree manual (first_intersection); the ray starts at tmin (the origin moved
// there) and hits beyond tmax are dropped by peer_hit.
void CgalMesh::closest(const Ray& ray, Hit& best, uint32_t inst) const {
  if (zero_direction(ray) || !tree_ || tree_->tree.empty()) return;
  const Kernel::Ray_3 query(point_at(ray, ray.tmin), Kernel::Vector_3(ray.dir.x, ray.dir.y, ray.dir.z));
  // A ray lying in a triangle's plane gets a Segment_3; the project's kernel never hits in-plane rays, so
  // such triangles are skipped and the ray shot again (rare: it needs exact coplanarity). Still in-plane
  // after kMax of them (or when CGAL ignores the skip, as its one-primitive tree does): no hit.
  CoplanarSkip skip;
  auto res = tree_->tree.first_intersection(query, skip);
  while (res && boost::get<Kernel::Segment_3>(&res->first)) {
    if (skip.count == CoplanarSkip::kMax || skip(res->second)) return;
    skip.ids[skip.count++] = res->second;
    res = tree_->tree.first_intersection(query, skip);
  }
  if (!res) return;
  const uint32_t prim = res->second;
  const Point& p = *boost::get<Point>(&res->first);
  const Hit h = peer_hit(ray, prims_->triangle(prim), prim, inst, glm::dvec3(p.x(), p.y(), p.z()));
  if (h.found() && is_better_hit(h.t, inst, h.prim, best)) best = h;
}

bool CgalMesh::any(const Ray& ray) const {
  if (zero_direction(ray) || !(ray.tmin <= ray.tmax) || !tree_ || tree_->tree.empty()) return false;
  const Point source = point_at(ray, ray.tmin);
  if (std::isinf(ray.tmax))
    return tree_->tree.do_intersect(Kernel::Ray_3(source, Kernel::Vector_3(ray.dir.x, ray.dir.y, ray.dir.z)));
  const Point target = point_at(ray, ray.tmax);
  if (target == source) {  // a degenerate segment is a precondition violation in CGAL
    Hit h;
    closest(ray, h, kInvalidId);
    return h.found();
  }
  return tree_->tree.do_intersect(Kernel::Segment_3(source, target));
}

namespace {
const Registrar kRegisterCgal{
    peer_info<CgalMesh>("cgal", "CGAL 5.5 AABB_tree, Epick kernel (an outside peer, a reference)", 2)};
}  // namespace

}  // namespace ab
