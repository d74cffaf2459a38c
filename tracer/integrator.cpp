#include "tracer/integrator.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <mutex>
#include <numbers>

#include "tracer/camera.h"
#include "tracer/sampling.h"
#include "tracer/workload.h"

namespace ab {

namespace {

constexpr int kTile = 16;
/// The first few 2D sample dimensions of each camera sample are stratified (pixel, lens, then the
/// light and bounce samples of the first hit); deeper ones are plain random.
constexpr int kStratifiedDims = 6;
constexpr float kInvPi = std::numbers::inv_pi_v<float>;

/// The samples of one pixel: stratified dimensions shared by its camera samples, matched by permutation.
class PixelSampler {
 public:
  PixelSampler(uint64_t seed, uint64_t pixel, uint32_t spp) : rng_(seed, pixel) {
    dims_.reserve(kStratifiedDims);
    for (int d = 0; d < kStratifiedDims; ++d) dims_.emplace_back(spp, rng_);
  }
  /// Starts camera sample i.
  void start(uint32_t i) {
    sample_ = i;
    dim_ = 0;
  }
  /// The next 2D sample of the current camera sample.
  glm::vec2 next2() {
    if (dim_ < kStratifiedDims) return dims_[size_t(dim_++)].get(sample_, rng_);
    return {rng_.uniform(), rng_.uniform()};
  }
  /// A 1D random number.
  float next1() { return rng_.uniform(); }

 private:
  Rng rng_;
  std::vector<Stratified2D> dims_;
  uint32_t sample_ = 0;
  int dim_ = 0;
};

/// Scatters rays through the scene; one per render.
class Tracer {
 public:
  Tracer(const Scene& scene, const Accelerator& accel, const RenderOptions& opt)
      : scene_(scene), accel_(accel), opt_(opt), eps_(surface_epsilon(accel.bounds())) {}

  /// Radiance arriving along ray. `see_lights`: whether area lights seen directly count (not after a
  /// diffuse bounce, whose light is sampled explicitly).
  vec3 radiance(const Ray& ray, int depth, int diffuse_left, bool see_lights, PixelSampler& s,
                RenderCounts& n) const {
    Hit hit;
    accel_.intersect_one(ray, hit, kInvalidId, nullptr);
    vec3 emitted(0.0f);
    if (see_lights && emitted_before(ray, hit.t, emitted)) return emitted;
    if (!hit.found()) return scene_.render.background;
    const vec3 p = ray.org + hit.t * ray.dir;
    const vec3 ng = glm::normalize(scene_.hit_normal(hit));
    const vec3 d = glm::normalize(ray.dir);
    const bool front = glm::dot(ng, d) < 0.0f;
    const vec3 nf = front ? ng : -ng;
    const Material& m = scene_.materials[scene_.instances[hit.inst].material];
    if (m.type == Material::Type::kDiffuse) return diffuse(p, nf, m, depth, diffuse_left, ray.time, s, n);
    if (depth >= opt_.max_depth) return vec3(0.0f);
    Ray next;
    next.tmin = 0.0f;
    next.time = ray.time;
    const vec3 r = d - 2.0f * glm::dot(d, nf) * nf;
    next.org = p + eps_ * nf;
    next.dir = r;
    if (m.type == Material::Type::kGlossy) {
      const glm::vec2 u = s.next2();
      const vec3 g = sample_phong_lobe(r, m.phong_exponent(), u.x, u.y);
      if (glm::dot(g, nf) > 0.0f) next.dir = g;
    } else if (m.type == Material::Type::kDielectric) {
      refract_or_reflect(p, d, nf, front ? 1.0f / m.ior : m.ior, s.next1(), next);
    }
    ++n.secondary_rays;
    return m.color * radiance(next, depth + 1, diffuse_left, see_lights, s, n);
  }

 private:
  /// True when an area light is hit before distance t_hit (emitted: its radiance, black from behind).
  bool emitted_before(const Ray& ray, float t_hit, vec3& emitted) const {
    float best = t_hit;
    bool found = false;
    for (const AreaLight& l : scene_.area_lights) {
      const float t = l.intersect(ray);
      if (t < best) {
        best = t;
        found = true;
        emitted = glm::dot(ray.dir, l.normal_area()) < 0.0f ? l.radiance : vec3(0.0f);
      }
    }
    return found;
  }

  // Snell's law with the unpolarized Fresnel reflectance; the two branches are chosen at random by
  // the reflectance (one ray per sample, as in Cook's distribution of rays).
  void refract_or_reflect(const vec3& p, const vec3& d, const vec3& nf, float eta, float u, Ray& next) const {
    const float cosi = -glm::dot(d, nf);
    const float sin2t = eta * eta * std::max(0.0f, 1.0f - cosi * cosi);
    if (sin2t >= 1.0f) return;  // total internal reflection: keep the mirror ray
    const float cost = std::sqrt(1.0f - sin2t);
    const float rs = (eta * cosi - cost) / (eta * cosi + cost);
    const float rp = (eta * cost - cosi) / (eta * cost + cosi);
    const float fresnel = 0.5f * (rs * rs + rp * rp);
    if (u < fresnel) return;
    next.org = p - eps_ * nf;
    next.dir = eta * d + (eta * cosi - cost) * nf;
  }

  /// Diffuse shading at p, every ray it casts at the camera ray's `time` (motion blur).
  vec3 diffuse(const vec3& p, const vec3& nf, const Material& m, int depth, int diffuse_left, float time,
               PixelSampler& s, RenderCounts& n) const {
    vec3 l = scene_.render.ambient + direct(p, nf, time, s, n) * kInvPi;
    if (diffuse_left > 0 && depth < opt_.max_depth) {
      const glm::vec2 u = s.next2();
      Ray next;
      next.time = time;
      next.org = p + eps_ * nf;
      next.dir = sample_cosine_hemisphere(nf, u.x, u.y);
      ++n.secondary_rays;
      l += radiance(next, depth + 1, diffuse_left - 1, false, s, n);  // cosine pdf cancels cos / pi
    }
    return m.color * l;
  }

  /// Irradiance from the lights (point lights exactly, area lights by one sample each).
  vec3 direct(const vec3& p, const vec3& nf, float time, PixelSampler& s, RenderCounts& n) const {
    vec3 e(0.0f);
    const vec3 org = p + eps_ * nf;
    for (const PointLight& l : scene_.point_lights) {
      const vec3 w = l.position - org;
      const float d2 = glm::dot(w, w);
      const float c = glm::dot(nf, w);
      if (c > 0.0f && visible(org, w, time, n)) e += l.intensity * (c / std::sqrt(d2)) / d2;
    }
    for (const AreaLight& l : scene_.area_lights) {
      const glm::vec2 u = s.next2();
      const vec3 w = l.point(u.x, u.y) - org;
      const float d2 = glm::dot(w, w);
      const float cs = glm::dot(nf, w);
      const float cl = -glm::dot(w, l.normal_area());  // |w| * cos_l * area
      if (cs > 0.0f && cl > 0.0f && visible(org, w, time, n)) e += l.radiance * (cs * cl / (d2 * d2));
    }
    return e;
  }

  bool visible(const vec3& org, const vec3& w, float time, RenderCounts& n) const {
    ++n.shadow_rays;
    Ray r;
    r.time = time;
    r.org = org;
    r.dir = w;
    r.tmin = 0.0f;
    r.tmax = 1.0f - 1e-4f;
    return !accel_.occluded_one(r, nullptr);
  }

  const Scene& scene_;
  const Accelerator& accel_;
  const RenderOptions& opt_;
  float eps_;
};

/// Calls f(x, y) for every pixel, over 16x16 tiles on TBB; reports progress per tile.
template <class F>
void for_each_pixel(const RenderOptions& opt, F&& f) {
  const int tx = (opt.width + kTile - 1) / kTile, ty = (opt.height + kTile - 1) / kTile;
  const size_t tiles = size_t(tx) * size_t(ty);
  std::mutex progress_mutex;
  size_t done = 0;
  tbb::task_arena arena(opt.threads > 0 ? opt.threads : tbb::task_arena::automatic);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, tiles, 1), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t t = r.begin(); t != r.end(); ++t) {
        const int x0 = int(t % size_t(tx)) * kTile, y0 = int(t / size_t(tx)) * kTile;
        for (int y = y0; y < std::min(y0 + kTile, opt.height); ++y)
          for (int x = x0; x < std::min(x0 + kTile, opt.width); ++x) f(x, y);
        if (opt.progress) {
          std::lock_guard<std::mutex> lock(progress_mutex);
          opt.progress(++done, tiles);
        }
      }
    });
  });
}

/// The camera ray's time of sample i of spp in pixel `pixel`: stratified over the shutter, stratum i rotated
/// by a per-pixel offset (Cranley and Patterson 1976) and jittered, from a generator of its own (the pixel
/// sampler's stream is left as it is), so the same on any thread count; 0 when the shutter is closed.
float sample_time(const Scene& scene, uint64_t seed, uint64_t pixel, int i, int spp) {
  if (!scene.camera.has_shutter()) return 0.0f;
  Rng rotation(seed ^ 0x5DEECE66DULL, pixel);
  const uint64_t offset = rotation.below(uint32_t(spp));
  Rng jitter(seed ^ 0x2545F4914F6CDD1DULL, pixel * 65537ULL + uint64_t(i));
  return std::min((float((uint64_t(i) + offset) % uint64_t(spp)) + jitter.uniform()) / float(spp), 1.0f);
}

/// A camera ray at a time.
Ray timed(Ray r, float time) {
  r.time = time;
  return r;
}

}  // namespace

RenderOptions render_options(const Scene& scene) {
  RenderOptions o;
  o.width = scene.render.width;
  o.height = scene.render.height;
  o.spp = scene.render.spp;
  o.max_depth = scene.render.max_depth;
  o.diffuse_depth = scene.render.diffuse_depth;
  return o;
}

Image render(const Scene& scene, const Accelerator& accel, const RenderOptions& opt, RenderCounts* counts) {
  Image image(opt.width, opt.height);
  const CameraRays camera(scene.camera, opt.width, opt.height);
  const Tracer tracer(scene, accel, opt);
  std::mutex counts_mutex;
  RenderCounts total;
  for_each_pixel(opt, [&](int x, int y) {
    PixelSampler s(opt.seed, uint64_t(y) * uint64_t(opt.width) + uint64_t(x), uint32_t(opt.spp));
    RenderCounts n;
    vec3 sum(0.0f);
    for (int i = 0; i < opt.spp; ++i) {
      s.start(uint32_t(i));
      const glm::vec2 px = s.next2();
      const glm::vec2 lens = s.next2();
      ++n.camera_rays;
      const float time =
          sample_time(scene, opt.seed, uint64_t(y) * uint64_t(opt.width) + uint64_t(x), i, opt.spp);
      sum += tracer.radiance(timed(camera.generate(float(x) + px.x, float(y) + px.y, lens.x, lens.y), time),
                             0, opt.diffuse_depth, true, s, n);
    }
    image.at(x, y) = sum / float(opt.spp);
    std::lock_guard<std::mutex> lock(counts_mutex);
    total.camera_rays += n.camera_rays;
    total.secondary_rays += n.secondary_rays;
    total.shadow_rays += n.shadow_rays;
  });
  if (counts) *counts = total;
  return image;
}

std::vector<float> render_work(const Scene& scene, const Accelerator& accel, const RenderOptions& opt,
                               HeatmapMetric metric) {
  std::vector<float> work(size_t(opt.width) * size_t(opt.height), 0.0f);
  const CameraRays camera(scene.camera, opt.width, opt.height);
  for_each_pixel(opt, [&](int x, int y) {
    PixelSampler s(opt.seed, uint64_t(y) * uint64_t(opt.width) + uint64_t(x), uint32_t(opt.spp));
    RayCounters c;
    for (int i = 0; i < opt.spp; ++i) {
      s.start(uint32_t(i));
      const glm::vec2 px = s.next2();
      const glm::vec2 lens = s.next2();
      Hit hit;
      const float time =
          sample_time(scene, opt.seed, uint64_t(y) * uint64_t(opt.width) + uint64_t(x), i, opt.spp);
      accel.intersect_one(timed(camera.generate(float(x) + px.x, float(y) + px.y, lens.x, lens.y), time), hit,
                          kInvalidId, &c);
    }
    const uint64_t v = metric == HeatmapMetric::kNodes ? c.nodes : c.prims;
    work[size_t(y) * size_t(opt.width) + size_t(x)] = float(double(v) / double(opt.spp));
  });
  return work;
}

}  // namespace ab
