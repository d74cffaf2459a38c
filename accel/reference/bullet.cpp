// Bullet's BVH triangle mesh shape as a peer, in its own translation unit (the only one that sees Bullet's
// headers, built with bullet-float64's BT_USE_DOUBLE_PRECISION).
#include "accel/reference/bullet.h"

#include <BulletCollision/NarrowPhaseCollision/btRaycastCallback.h>
#include <btBulletCollisionCommon.h>

#include <algorithm>
#include <cmath>

#include "accel/core/registry.h"
#include "accel/reference/peer.h"

namespace ab {

namespace {

/// Triangles per btIndexedMesh part: the quantized BVH packs 21 bits of triangle index (and 10 of part id).
constexpr uint32_t kPartTriangles = 1u << 21;
/// The mesh's largest extent inside Bullet (its margins and leaf sizes are absolute constants).
constexpr double kScaledExtent = 1000.0;

}  // namespace

struct BulletMesh::Shape {
  btTriangleIndexVertexArray array;
  std::unique_ptr<btBvhTriangleMeshShape> shape;
  glm::dvec3 lo{0.0}, hi{0.0};  ///< mesh bounds (unscaled)
  double scale = 1.0;           ///< Bullet's coordinates = ours x scale
};

namespace {

/// The closest hit among the triangles Bullet reports along the segment from the ray's t = start to t = end:
/// those the project's kernel confirms win (by the acceptance rule); the closest Bullet-only report at or
/// after tmin is kept for when the kernel confirms none.
class ClosestCallback final : public btTriangleRaycastCallback {
 public:
  ClosestCallback(const btVector3& from, const btVector3& to, const TrianglePrims& prims, const Ray& ray,
                  uint32_t inst, double start, double end)
      : btTriangleRaycastCallback(from, to, kF_None),
        prims_(prims),
        ray_(ray),
        inst_(inst),
        start_(start),
        end_(end) {}

  btScalar reportHit(const btVector3&, btScalar fraction, int part, int index) override {
    const uint32_t prim = uint32_t(part) * kPartTriangles + uint32_t(index);
    TriangleHit th;
    if (!intersect_triangle(ray_, prims_.triangle(prim), th)) {
      const double t = t_at(fraction);
      if (t >= ray_.tmin && t < fallback_t) fallback_t = t, fallback_prim = prim;
      return m_hitFraction;
    }
    if (is_better_hit(th.t, inst_, prim, best)) best = {th.t, prim, inst_, th.u, th.v};
    // Keep reports of nearly equal fractions coming: the kernel's t and the ids decide between them.
    return std::min(m_hitFraction, fraction * btScalar(1.0 + 1e-5));
  }
  /// The ray's t at a fraction of the segment.
  double t_at(btScalar fraction) const { return start_ + double(fraction) * (end_ - start_); }

  Hit best;                  ///< the best kernel-confirmed hit
  double fallback_t = kInf;  ///< the closest report the kernel did not confirm (inf: none)
  uint32_t fallback_prim = kInvalidId;

 private:
  const TrianglePrims& prims_;
  const Ray& ray_;
  uint32_t inst_;
  double start_, end_;
};

/// Clips [tmin, tmax] of the ray to the box [lo, hi] (slab test in double); false when nothing is left.
bool clip_to_box(const Ray& ray, const glm::dvec3& lo, const glm::dvec3& hi, double& t0, double& t1) {
  const glm::dvec3 o(ray.org), d(ray.dir);
  t0 = ray.tmin;
  t1 = ray.tmax;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) {
      if (o[a] < lo[a] || o[a] > hi[a]) return false;
      continue;
    }
    double ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t0 <= t1;
}

}  // namespace

BulletMesh::BulletMesh(std::shared_ptr<const TrianglePrims> prims, const Config&)
    : PeerMesh(std::move(prims)) {}

BulletMesh::~BulletMesh() = default;

void BulletMesh::do_build() {
  shape_ = std::make_unique<Shape>();
  const Mesh& mesh = prims_->mesh();
  if (mesh.size() == 0) return;  // no shape: every ray misses
  const AABB b = prims_->bounds();
  shape_->lo = glm::dvec3(b.lo);
  shape_->hi = glm::dvec3(b.hi);
  // No copy: Bullet reads the float vertices and 32-bit indices in place.
  for (uint32_t first = 0; first < mesh.size(); first += kPartTriangles) {
    btIndexedMesh part;
    part.m_numTriangles = int(std::min<size_t>(kPartTriangles, mesh.size() - first));
    part.m_triangleIndexBase = reinterpret_cast<const unsigned char*>(&mesh.triangles[first]);
    part.m_triangleIndexStride = sizeof(glm::uvec3);
    part.m_numVertices = int(mesh.vertices.size());
    part.m_vertexBase = reinterpret_cast<const unsigned char*>(mesh.vertices.data());
    part.m_vertexStride = sizeof(vec3);
    part.m_vertexType = PHY_FLOAT;
    shape_->array.addIndexedMesh(part, PHY_INTEGER);
  }
  const glm::dvec3 e = shape_->hi - shape_->lo;
  const double extent = std::max({e.x, e.y, e.z});
  if (extent > 0.0) shape_->scale = kScaledExtent / extent;
  const btScalar s(shape_->scale);
  shape_->array.setScaling(btVector3(s, s, s));
  shape_->shape = std::make_unique<btBvhTriangleMeshShape>(&shape_->array, true, true);
}

void BulletMesh::gather_stats(BuildStats& stats) const {
  stats.primitives = prims_->size();
  stats.references = prims_->size();
  if (!shape_ || !shape_->shape) return;
  btOptimizedBvh* bvh = shape_->shape->getOptimizedBvh();
  const QuantizedNodeArray& nodes = bvh->getQuantizedNodeArray();
  stats.nodes = uint64_t(nodes.size());
  for (int i = 0; i < nodes.size(); ++i) stats.leaves += nodes[i].isLeafNode();  // one triangle each
  stats.bytes = bvh->calculateSerializeBufferSize();
  stats.extra["note"] =
      "bytes: the quantized BVH's serialized size (nodes and subtree headers), as Bullet reports it";
  stats.extra["scale"] = shape_->scale;
  stats.extra["version"] = btGetVersion();
}

void BulletMesh::closest(const Ray& ray, Hit& best, uint32_t inst) const {
  if (!shape_ || !shape_->shape) return;
  double t0, t1;
  if (!clip_to_box(ray, shape_->lo, shape_->hi, t0, t1)) return;
  // Bullet reports neither a hit at the segment's far end (fraction < 1) nor one at its start (a start on
  // the plane does not cross it): both ends are pushed out a little, and tmin, tmax enforced by the kernel
  // (and for Bullet-only reports by the callback and peer_hit).
  const double pad = 1e-3 * (t1 - t0) + 1e-7 * std::max(1.0, std::fabs(t1));
  const double start = t0 - pad, end = t1 + pad;
  const glm::dvec3 o(ray.org), d(ray.dir);
  const glm::dvec3 a = (o + start * d) * shape_->scale, b = (o + end * d) * shape_->scale;
  const btVector3 from(a.x, a.y, a.z), to(b.x, b.y, b.z);
  ClosestCallback cb(from, to, *prims_, ray, inst, start, end);
  shape_->shape->performRaycast(&cb, from, to);
  Hit h = cb.best;
  if (!h.found() && cb.fallback_prim != kInvalidId)
    h = peer_hit(ray, prims_->triangle(cb.fallback_prim), cb.fallback_prim, inst, o + cb.fallback_t * d);
  if (h.found() && is_better_hit(h.t, inst, h.prim, best)) best = h;
}

bool BulletMesh::any(const Ray& ray) const {
  Hit h;
  closest(ray, h, kInvalidId);
  return h.found();
}

namespace {
const Registrar kRegisterBullet{peer_info<BulletMesh>(
    "bullet", "Bullet 3.24 btBvhTriangleMeshShape, quantized BVH (an outside peer, a reference)", 3)};
}  // namespace

}  // namespace ab
