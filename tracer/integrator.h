// Distribution ray tracing after Cook, Porter and Carpenter 1984 ("Distributed ray tracing"):
// stratified, jittered pixel samples; area lights sampled for soft shadows; thin-lens depth of field;
// glossy reflection; mirror reflection and dielectric refraction (Snell's law, Fresnel); a recursion limit.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "accel/core/accelerator.h"
#include "tracer/image.h"
#include "tracer/scene.h"

namespace ab {

/// How to render (the scene's <render> settings, possibly overridden on the command line).
struct RenderOptions {
  int width = 256;
  int height = 256;
  int spp = 16;
  int max_depth = 6;
  int diffuse_depth = 1;
  uint64_t seed = 1;
  int threads = 0;  ///< 0: all hardware threads
  /// Called after each finished tile with (tiles done, tiles in all); may be empty. Calls are serialized.
  std::function<void(size_t, size_t)> progress;
};

/// The scene's own render settings as options.
RenderOptions render_options(const Scene& scene);

/// What a render cast.
struct RenderCounts {
  uint64_t camera_rays = 0;
  uint64_t secondary_rays = 0;  ///< reflection, refraction, glossy and diffuse bounces
  uint64_t shadow_rays = 0;
  /// Every ray cast.
  uint64_t total() const { return camera_rays + secondary_rays + shadow_rays; }
};

/// Renders the scene with accel (built over the same scene). The image is the same for any thread
/// count: each pixel draws its samples from its own generator seeded by (seed, pixel).
Image render(const Scene& scene, const Accelerator& accel, const RenderOptions& options,
             RenderCounts* counts = nullptr);

/// What a heatmap counts per camera ray.
enum class HeatmapMetric { kNodes, kPrims };

/// Mean count per camera ray (nodes visited or primitives tested, from the counting entry point) of
/// each pixel's options.spp camera rays; width x height values, row-major.
std::vector<float> render_work(const Scene& scene, const Accelerator& accel, const RenderOptions& options,
                               HeatmapMetric metric);

}  // namespace ab
