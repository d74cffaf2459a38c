#include "datasets/rays.h"

#include <algorithm>
#include <cmath>
#include <functional>

#include "accel/core/error.h"
#include "datasets/random.h"

namespace ab {
namespace {

constexpr float kPi = 3.14159265358979323846f;
/// Primary rays traced per batch when looking for surface points.
constexpr size_t kTraceBatch = size_t{1} << 20;
/// Rounds of fresh primary rays for surface points whose first primary ray missed.
constexpr int kSurfaceRounds = 4;

/// The box rays are made for: the target's bounds, or the unit box when they are empty.
struct Frame {
  AABB box;
  vec3 center;
  float diag;  ///< length of the box diagonal (1 for a single point)
};

Frame frame_of(const AABB& bounds) {
  Frame f;
  f.box = bounds.empty() ? AABB{vec3(0.0f), vec3(1.0f)} : bounds;
  f.center = f.box.center();
  f.diag = glm::length(f.box.extent());
  if (!(f.diag > 0.0f) || !std::isfinite(f.diag)) f.diag = 1.0f;
  return f;
}

/// The default camera's viewing direction (view 0 of every `views` count).
vec3 default_forward() {
  return glm::normalize(vec3(-0.55f, -0.45f, -0.7f));
}

/// Viewing direction of view v of `views`: the default direction turned about the vertical (y) axis by
/// 2 pi v / views, so the cameras stand evenly around the bounds at the default camera's elevation (Aila
/// and Laine 2009 measure each scene from several such viewpoints).
vec3 view_forward(uint32_t v, uint32_t views) {
  const vec3 f = default_forward();
  if (v == 0) return f;
  const double a = 2.0 * 3.14159265358979323846 * double(v) / double(views);
  const float c = float(std::cos(a)), s = float(std::sin(a));
  return glm::normalize(vec3(c * f.x + s * f.z, f.y, c * f.z - s * f.x));
}

/// A pinhole camera looking at the box centre from direction `forward`, just far enough back that
/// all eight box corners fit the 45 degree field of view, with a width x height pixel grid.
struct Camera {
  vec3 eye, forward, right, up;
  float tan_half;
  uint64_t width, height;

  Camera(const Frame& f, uint64_t count, vec3 view = default_forward()) {
    forward = view;
    tan_half = std::tan(22.5f * kPi / 180.0f);
    right = glm::normalize(glm::cross(forward, vec3(0.0f, 1.0f, 0.0f)));
    up = glm::cross(right, forward);
    // Distance d such that every corner c satisfies |x|, |y| <= tan_half * (d + z) in camera space.
    float distance = 0.0f;
    for (int i = 0; i < 8; ++i) {
      const vec3 c((i & 1) ? f.box.hi.x : f.box.lo.x, (i & 2) ? f.box.hi.y : f.box.lo.y,
                   (i & 4) ? f.box.hi.z : f.box.lo.z);
      const vec3 r = c - f.center;
      const float z = glm::dot(r, forward);
      const float reach = std::max(std::fabs(glm::dot(r, right)), std::fabs(glm::dot(r, up)));
      distance = std::max(distance, reach / tan_half - z);
    }
    distance = std::max(distance * 1.02f, 1e-3f * f.diag);
    eye = f.center - forward * distance;
    width = std::max<uint64_t>(1, static_cast<uint64_t>(std::ceil(std::sqrt(static_cast<double>(count)))));
    height = std::max<uint64_t>(1, (count + width - 1) / width);
  }
  /// A ray through pixel `pixel` (row-major), jittered within it.
  Ray ray(uint64_t pixel, Rng& rng) const {
    const float sx = (static_cast<float>(pixel % width) + rng.uniform()) / static_cast<float>(width);
    const float sy = (static_cast<float>(pixel / width) + rng.uniform()) / static_cast<float>(height);
    const vec3 d = forward + tan_half * ((2.0f * sx - 1.0f) * right + (1.0f - 2.0f * sy) * up);
    return Ray{eye, glm::normalize(d), 0.0f, kInf, 0.0f};
  }
};

/// Random generator of ray `index` of a kind: independent per ray, so rays do not depend on the
/// order they are made in.
Rng ray_rng(uint64_t seed, uint64_t kind, uint64_t index, uint64_t round = 0) {
  return Rng(seed, hash_seed(kind, index, round));
}

/// A point on the surface with its unit normal facing the ray that found it.
struct SurfacePoint {
  vec3 pos;
  vec3 normal;
};

/// The surface point of a primary ray's hit (normal from the target, turned towards the ray).
SurfacePoint surface_at(const RayTarget& target, const Ray& ray, const Hit& hit) {
  SurfacePoint s{ray.org + hit.t * ray.dir, target.normal ? target.normal(hit) : vec3(0.0f)};
  const float len = glm::length(s.normal);
  s.normal = len > 0.0f && std::isfinite(len) ? s.normal / len : -ray.dir;
  if (glm::dot(s.normal, ray.dir) > 0.0f) s.normal = -s.normal;
  return s;
}

/// Fallback for a slot whose primary rays all missed: the point of the ray nearest the box centre,
/// facing back along the ray.
SurfacePoint fallback_point(const Frame& f, const Ray& ray) {
  return {ray.org + glm::dot(f.center - ray.org, ray.dir) * ray.dir, -ray.dir};
}

/// Which surface points a kind can use (shadow: those facing the light); empty accepts all.
using Accept = std::function<bool(const SurfacePoint&)>;

/// `count` surface points seen from the primary camera: slot i uses primary ray i; slots whose
/// ray misses (or whose point `accept` rejects) retry with fresh random pixels for a few rounds,
/// then fall back to fallback_point.
std::vector<SurfacePoint> surface_points(const RayTarget& target, const Frame& f, uint64_t count,
                                         uint64_t seed, const Accept& accept) {
  const Camera camera(f, count);
  std::vector<SurfacePoint> points(count);
  std::vector<uint64_t> pending(count);
  for (uint64_t i = 0; i < count; ++i) pending[i] = i;
  std::vector<Ray> rays;
  std::vector<Hit> hits;
  for (int round = 0; round <= kSurfaceRounds && !pending.empty(); ++round) {
    rays.resize(pending.size());
    for (size_t k = 0; k < pending.size(); ++k) {
      Rng rng = ray_rng(seed, 100, pending[k], static_cast<uint64_t>(round));
      const uint64_t pixel = round == 0 ? pending[k] : rng.below(camera.width * camera.height);
      rays[k] = camera.ray(pixel, rng);
    }
    const bool last = round == kSurfaceRounds || target.bounds.empty() || !target.trace;
    hits.assign(rays.size(), Hit{});
    for (size_t start = 0; !last && start < rays.size(); start += kTraceBatch) {
      const size_t n = std::min(kTraceBatch, rays.size() - start);
      target.trace(std::span<const Ray>(rays.data() + start, n), std::span<Hit>(hits.data() + start, n));
    }
    size_t kept = 0;
    for (size_t k = 0; k < pending.size(); ++k) {
      const SurfacePoint s = hits[k].found() ? surface_at(target, rays[k], hits[k]) : SurfacePoint{};
      if (hits[k].found() && (!accept || accept(s) || last))
        points[pending[k]] = s;
      else if (last)
        points[pending[k]] = fallback_point(f, rays[k]);
      else
        pending[kept++] = pending[k];
    }
    pending.resize(last ? 0 : kept);
  }
  return points;
}

/// Offset of a secondary ray's origin along the normal: well above the float spacing at the point
/// (1e-4 of its largest coordinate) and at least 1e-7 of the box diagonal.
float offset_at(const Frame& f, const vec3& p) {
  const float magnitude = std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z), 1e-3f * f.diag});
  return 1e-4f * magnitude;
}

/// Direction `local` (z = up) expressed around the unit normal n.
vec3 around(const vec3& n, const vec3& local) {
  const vec3 helper = std::fabs(n.x) < 0.9f ? vec3(1.0f, 0.0f, 0.0f) : vec3(0.0f, 1.0f, 0.0f);
  const vec3 t = glm::normalize(glm::cross(helper, n));
  const vec3 b = glm::cross(n, t);
  return glm::normalize(local.x * t + local.y * b + local.z * n);
}

// Malley's method (Pharr, Jakob and Humphreys, PBR 4th ed., 13.6.3): a uniform point on the disk
// projected up to the hemisphere gives a cosine-weighted direction.
vec3 cosine_direction(Rng& rng) {
  const float u1 = rng.uniform();
  const float phi = 2.0f * kPi * rng.uniform();
  const float r = std::sqrt(u1);
  return {r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0f, 1.0f - u1))};
}

/// Uniform direction over the hemisphere (z uniform in [0, 1]).
vec3 hemisphere_direction(Rng& rng) {
  const float z = rng.uniform();
  const float phi = 2.0f * kPi * rng.uniform();
  const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
  return {r * std::cos(phi), r * std::sin(phi), z};
}

/// Primary rays from `views` cameras around the bounds: view v makes rays [v count / views, (v + 1) count /
/// views), one per pixel of its own grid; ray i's jitter depends on (seed, i) alone.
std::vector<Ray> primary_rays(const Frame& f, uint64_t count, uint64_t seed, uint32_t views) {
  std::vector<Ray> rays(count);
  for (uint32_t v = 0; v < views; ++v) {
    const uint64_t begin = count * v / views, end = count * (v + 1) / views;
    if (begin == end) continue;
    const Camera camera(f, end - begin, view_forward(v, views));
    for (uint64_t i = begin; i < end; ++i) {
      Rng rng = ray_rng(seed, 1, i);
      rays[i] = camera.ray(i - begin, rng);
    }
  }
  return rays;
}

std::vector<Ray> incoherent_rays(const Frame& f, uint64_t count, uint64_t seed) {
  std::vector<Ray> rays(count);
  const vec3 extent = f.box.extent();
  for (uint64_t i = 0; i < count; ++i) {
    Rng rng = ray_rng(seed, 2, i);
    const vec3 org = f.box.lo + extent * rng.unit_cube();
    rays[i] = Ray{org, rng.unit_sphere(), 0.0f, kInf, 0.0f};
  }
  return rays;
}

/// Secondary rays from surface points; `make` turns (point, its rng) into the direction and tmax.
template <class Make>
std::vector<Ray> secondary_rays(const RayTarget& target, const Frame& f, uint64_t count, uint64_t seed,
                                uint64_t kind, const Accept& accept, Make make) {
  const std::vector<SurfacePoint> points = surface_points(target, f, count, seed, accept);
  std::vector<Ray> rays(count);
  for (uint64_t i = 0; i < count; ++i) {
    Rng rng = ray_rng(seed, kind, i);
    const SurfacePoint& s = points[i];
    const float eps = offset_at(f, s.pos);
    Ray r;
    r.org = s.pos + eps * s.normal;
    r.tmin = 0.5f * eps;
    make(s, rng, r);
    rays[i] = r;
  }
  return rays;
}

}  // namespace

const std::vector<RayKindInfo>& ray_kinds() {
  static const std::vector<RayKindInfo> kinds = {
      {"primary",
       "pinhole camera framing the bounds, one jittered ray per pixel (views=V: V cameras around it)"},
      {"incoherent", "random origin inside the bounds, uniform random direction"},
      {"shadow", "from primary hit points to a point light above the bounds (finite tmax)"},
      {"diffuse", "cosine-weighted bounce from primary hit points"},
      {"ao",
       "short ambient-occlusion rays over the hemisphere at primary hit points (tmax 10% of the diagonal)"},
  };
  return kinds;
}

std::vector<Ray> make_rays(const std::string& kind, const RayTarget& target, uint64_t count, uint64_t seed,
                           uint32_t views) {
  if (views == 0) throw InputError("views must be at least 1");
  if (views != 1 && kind != "primary") throw InputError("views applies to the primary ray kind only");
  const Frame f = frame_of(target.bounds);
  if (kind == "primary") return primary_rays(f, count, seed, views);
  if (kind == "incoherent") return incoherent_rays(f, count, seed);
  if (kind == "shadow") {
    const vec3 light(f.center.x + 0.2f * f.diag, f.box.hi.y + 0.5f * f.diag, f.center.z + 0.1f * f.diag);
    // Like a renderer, only points lit from their front get shadow rays (a ray through the surface
    // it starts on would end at once); the others are replaced by retries.
    const Accept faces_light = [&](const SurfacePoint& s) {
      return glm::dot(s.normal, light - s.pos) > 0.0f;
    };
    return secondary_rays(target, f, count, seed, 3, faces_light, [&](const SurfacePoint&, Rng&, Ray& r) {
      const vec3 to_light = light - r.org;
      const float distance = glm::length(to_light);
      r.dir = distance > 0.0f ? to_light / distance : vec3(0.0f, 1.0f, 0.0f);
      r.tmax = std::max(distance, r.tmin);
    });
  }
  if (kind == "diffuse")
    return secondary_rays(target, f, count, seed, 4, Accept(), [](const SurfacePoint& s, Rng& rng, Ray& r) {
      r.dir = around(s.normal, cosine_direction(rng));
      r.tmax = kInf;
    });
  if (kind == "ao") {
    const float reach = 0.1f * f.diag;
    return secondary_rays(target, f, count, seed, 5, Accept(), [&](const SurfacePoint& s, Rng& rng, Ray& r) {
      r.dir = around(s.normal, hemisphere_direction(rng));
      r.tmax = reach;
    });
  }
  std::string known;
  for (const RayKindInfo& k : ray_kinds()) known += (known.empty() ? "" : ", ") + k.name;
  throw InputError("unknown ray kind '" + kind + "' (known: " + known + ")");
}

}  // namespace ab
