// `accelbench render --scene F [--accel NAME] [--accel-top NAME] [--accel-bottom NAME] [--spp N]
//  [--width W] [--height H] [--max-depth D] [--seed S] [--threads T]
//  [--heatmap [--metric nodes|prims] [--scale-max V]]
//  [--param k=v ...] [--time T | --frame F --frames N | --frames A-B] -o FILE.png`
#include <chrono>
#include <cstdio>
#include <memory>

#include "accel/core/error.h"
#include "accel/reference/embree_device.h"
#include "harness/cli.h"
#include "harness/options.h"
#include "harness/selection.h"
#include "harness/target.h"
#include "harness/terminal.h"
#include "harness/timing.h"
#include "tracer/animation.h"
#include "tracer/heatmap.h"
#include "tracer/integrator.h"
#include "tracer/scene.h"

namespace ab {
namespace {

struct RenderArgs {
  std::string scene;
  FrameOptions frame;
  std::string accel;
  StructureOptions structure;
  std::string output;
  int spp = 0, width = 0, height = 0, max_depth = 0, threads = 0;
  uint64_t seed = 1;
  bool heatmap = false;
  std::string metric = "nodes";
  float scale_max = 0.0f;
};

/// Renders one frame (the target's scene) to `output`; prints one summary line.
void render_frame(const Target& target, const RenderArgs& a, const std::string& output) {
  const Scene& scene = *target.scene;
  RenderOptions opt = render_options(scene);
  if (a.spp) opt.spp = a.spp;
  if (a.width) opt.width = a.width;
  if (a.height) opt.height = a.height;
  if (a.max_depth) opt.max_depth = a.max_depth;
  opt.seed = a.seed;
  opt.threads = a.threads;
  opt.progress = progress_callback("rendering " + output);
  const std::string name = a.accel.empty() ? default_structure() : a.accel;
  std::unique_ptr<Accelerator> accel = make_target_accelerator(target, name, params_from(a.structure.params),
                                                               a.structure.top, a.structure.bottom);
  accel->build();
  const auto start = std::chrono::steady_clock::now();
  RenderCounts counts;
  Image8 out;
  if (a.heatmap) {
    if (accel->name() == kEmbreeName) throw InputError("--heatmap: embree has no traversal counters");
    const HeatmapMetric m = a.metric == "prims" ? HeatmapMetric::kPrims : HeatmapMetric::kNodes;
    const std::vector<float> work = render_work(scene, *accel, opt, m);
    out = heatmap_image(work, opt.width, opt.height,
                        accel->name() + (m == HeatmapMetric::kNodes ? " nodes/ray" : " prims/ray"),
                        a.scale_max);
    counts.camera_rays = uint64_t(opt.width) * uint64_t(opt.height) * uint64_t(opt.spp);
  } else {
    out = to_srgb8(render(scene, *accel, opt, &counts));
  }
  const double seconds = seconds_since(start);
  write_png(out, output);
  std::printf("%s: %dx%d, %d spp, %s: build %.3f s, render %.3f s, %llu rays (%.2f Mrays/s)\n",
              output.c_str(), opt.width, opt.height, opt.spp, accel->name().c_str(),
              accel->stats().build_seconds, seconds, static_cast<unsigned long long>(counts.total()),
              seconds > 0 ? double(counts.total()) / seconds / 1e6 : 0.0);
}

/// `--frames A-B`: frames A..B of the scene's `<render><frames>` count, one PNG each, named by the
/// output pattern (one %d or %0Nd). Every frame uses the same seed, so the images do not depend on threads.
int render_animation(const RenderArgs& a, uint64_t first, uint64_t last) {
  std::string probe;
  if (!frame_file_name(a.output, first, probe))
    throw InputError("-o " + a.output + ": --frames A-B needs an output pattern with one %d or %0Nd");
  const Scene scene = load_scene(a.scene);
  const auto count = uint64_t(scene.render.frames);
  if (last >= count)
    throw InputError("--frames " + a.frame.frames + ": out of range, " + a.scene + " has " +
                     std::to_string(count) + " frames (0.." + std::to_string(count - 1) + ")");
  for (uint64_t f = first; f <= last; ++f) {
    std::string output;
    frame_file_name(a.output, f, output);
    auto at = std::make_shared<const Scene>(scene_at(scene, frame_time(f, count)));
    render_frame(scene_target(std::move(at), a.scene), a, output);
  }
  return 0;
}

int run_render(const RenderArgs& a) {
  uint64_t first = 0, last = 0;
  if (a.frame.range(first, last)) {
    a.frame.normalized_time(true);  // the other combinations' checks
    return render_animation(a, first, last);
  }
  render_frame(load_target("", a.scene, a.frame.normalized_time()), a, a.output);
  return 0;
}

const CommandRegistrar kRender{
    {"render", "render a scene with the tracer (PNG), or a heatmap of traversal work", 70,
     [](CLI::App& app) -> std::function<int()> {
       auto a = std::make_shared<RenderArgs>();
       app.add_option("--scene", a->scene, "scene file (.xml, .gltf, .glb)")
           ->required()
           ->check(CLI::ExistingFile);
       a->frame.add(app);
       app.add_option("--accel", a->accel, "accelerator at both levels (default bvh-sah)")
           ->check(accelerator_name_validator());
       a->structure.add(app);
       app.add_option("--spp", a->spp, "samples per pixel (default: the scene's)")
           ->check(CLI::Range(1, 65536));
       app.add_option("--width", a->width, "image width")->check(CLI::Range(1, 16384));
       app.add_option("--height", a->height, "image height")->check(CLI::Range(1, 16384));
       app.add_option("--max-depth", a->max_depth, "recursion limit")->check(CLI::Range(1, 64));
       app.add_option("--seed", a->seed, "random seed");
       add_threads_option(app, a->threads);
       app.add_flag("--heatmap", a->heatmap, "false-colour traversal work per pixel");
       app.add_option("--metric", a->metric, "heatmap metric")->check(CLI::IsMember({"nodes", "prims"}));
       app.add_option("--scale-max", a->scale_max,
                      "heatmap: value at the top of the colour scale (default: the image's maximum)")
           ->check(CLI::PositiveNumber);
       app.add_option("-o,--output", a->output,
                      "output .png file (with --frames A-B: a pattern, name_%04d.png)")
           ->required();
       return [a] { return run_render(*a); };
     }}};

}  // namespace
}  // namespace ab
