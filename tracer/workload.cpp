#include "tracer/workload.h"

#include <cmath>

#include "accel/core/error.h"
#include "tracer/camera.h"
#include "tracer/sampling.h"

namespace ab {

const std::vector<RayKindInfo>& scene_ray_kinds() {
  static const std::vector<RayKindInfo> kinds = {
      {"primary", "scene: the camera's pinhole rays, scanline order, jittered in the pixel"},
      {"dof", "scene: thin-lens rays (the camera's aperture, or 1/64 of the focal distance when it is 0)"},
      {"shadow", "scene: from primary hits to sampled points on the area lights (point lights if none)"},
      {"glossy",
       "scene: glossy reflection (Phong lobe of the material's roughness, 0.1 if not glossy) at primary "
       "hits"},
      {"diffuse", "scene: cosine-weighted bounce at primary hits"},
      {"motion", "scene: the primary rays with a time each, uniform over the camera's shutter (ABRAYS02)"}};
  return kinds;
}

bool is_scene_ray_kind(const std::string& kind) {
  for (const auto& k : scene_ray_kinds())
    if (k.name == kind) return true;
  return false;
}

float surface_epsilon(const AABB& b) {
  const float scale =
      b.empty() ? 1.0f : glm::length(b.extent()) + glm::length(glm::max(glm::abs(b.lo), glm::abs(b.hi)));
  return 2e-5f * std::max(scale, 1e-3f);
}

namespace {

/// Camera rays over an image of about `count` pixels with the scene's aspect, in scanline order;
/// ray j falls on pixel j mod (w h), jittered by its own generator.
class CameraSweep {
 public:
  CameraSweep(const Scene& scene, uint64_t count, bool lens) : camera_(scene.camera) {
    if (lens && camera_.aperture <= 0.0f) {
      const float focal =
          camera_.focal_distance > 0 ? camera_.focal_distance : glm::length(camera_.look_at - camera_.eye);
      camera_.aperture = focal / 64.0f;
    }
    if (!lens) camera_.aperture = 0.0f;
    const double aspect = double(scene.render.width) / double(scene.render.height);
    const double n = double(std::max<uint64_t>(count, 1));
    w_ = std::max<uint64_t>(1, uint64_t(std::ceil(std::sqrt(n * aspect))));
    h_ = std::max<uint64_t>(1, uint64_t(std::ceil(n / double(w_))));
  }
  /// Ray j.
  /// Ray j; with `timed`, its time is the generator's next number (the pixel and lens ones unchanged).
  Ray ray(uint64_t j, uint64_t seed, bool timed = false) const {
    const CameraRays rays(camera_, int(w_), int(h_));
    Rng rng(seed, j);
    const uint64_t pixel = j % (w_ * h_);
    const float px = float(pixel % w_) + rng.uniform(), py = float(pixel / w_) + rng.uniform();
    const float lu = rng.uniform(), lv = rng.uniform();
    Ray r = rays.generate(px, py, lu, lv);
    if (timed) r.time = rng.uniform();
    return r;
  }

 private:
  Camera camera_;
  uint64_t w_, h_;
};

/// One secondary ray of `kind` from the hit of primary ray `ray` (rng: that ray's generator).
Ray secondary(const Scene& scene, const std::string& kind, const Ray& ray, const Hit& hit, float eps,
              Rng& rng) {
  const vec3 p = ray.org + hit.t * ray.dir;
  const vec3 d = glm::normalize(ray.dir);
  vec3 nf = glm::normalize(scene.hit_normal(hit));
  if (glm::dot(nf, d) > 0.0f) nf = -nf;
  Ray out;
  out.org = p + eps * nf;
  const float u = rng.uniform(), v = rng.uniform();
  if (kind == "shadow") {
    vec3 target;
    if (!scene.area_lights.empty()) {
      const AreaLight& l = scene.area_lights[rng.below(uint32_t(scene.area_lights.size()))];
      target = l.point(u, v);
    } else {
      target = scene.point_lights[rng.below(uint32_t(scene.point_lights.size()))].position;
    }
    out.dir = target - out.org;
    out.tmax = 1.0f - 1e-4f;
  } else if (kind == "glossy") {
    const Material& m = scene.materials[scene.instances[hit.inst].material];
    Material fallback;
    fallback.roughness = 0.1f;
    const float e = m.type == Material::Type::kGlossy ? m.phong_exponent() : fallback.phong_exponent();
    const vec3 r = d - 2.0f * glm::dot(d, nf) * nf;
    out.dir = sample_phong_lobe(r, e, u, v);
    if (glm::dot(out.dir, nf) <= 0.0f) out.dir = r;
  } else {
    out.dir = sample_cosine_hemisphere(nf, u, v);
  }
  return out;
}

}  // namespace

std::vector<Ray> make_scene_rays(const Scene& scene, const TraceFn& trace, const std::string& kind,
                                 uint64_t count, uint64_t seed) {
  if (!is_scene_ray_kind(kind)) {
    std::string known;
    for (const auto& k : scene_ray_kinds()) known += (known.empty() ? "" : ", ") + k.name;
    throw InputError("unknown scene ray kind '" + kind + "' (known: " + known + ")");
  }
  const CameraSweep sweep(scene, count, kind == "dof");
  std::vector<Ray> out;
  out.reserve(count);
  if (kind == "primary" || kind == "dof" || kind == "motion") {
    for (uint64_t j = 0; j < count; ++j) out.push_back(sweep.ray(j, seed, kind == "motion"));
    return out;
  }
  if (kind == "shadow" && scene.area_lights.empty() && scene.point_lights.empty())
    throw InputError(scene.path + ": shadow rays need a light in the scene");
  const float eps = surface_epsilon(scene.world_bounds());
  const uint64_t batch = std::max<uint64_t>(1024, count), limit = 64 * count + 4096;
  std::vector<Ray> primary;
  std::vector<Hit> hits;
  for (uint64_t start = 0; out.size() < count; start += batch) {
    if (start >= limit)
      throw InputError(scene.path + ": the camera sees too little geometry for " + kind + " rays");
    primary.resize(batch);
    hits.assign(batch, Hit{});
    for (uint64_t j = 0; j < batch; ++j) primary[j] = sweep.ray(start + j, seed);
    trace(primary, hits);
    for (uint64_t j = 0; j < batch && out.size() < count; ++j) {
      if (!hits[j].found()) continue;
      Rng rng(seed ^ 0x9E3779B97F4A7C15ULL, start + j);
      out.push_back(secondary(scene, kind, primary[j], hits[j], eps, rng));
    }
  }
  return out;
}

}  // namespace ab
