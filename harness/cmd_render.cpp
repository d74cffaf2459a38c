// `accelbench render --scene F [--accel NAME] [--accel-top NAME] [--accel-bottom NAME] [--spp N]
//  [--width W] [--height H] [--max-depth D] [--seed S] [--threads T]
//  [--heatmap [--metric nodes|prims] [--scale-max V]]
//  [--param k=v ...] -o FILE.png`
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
#include "tracer/heatmap.h"
#include "tracer/integrator.h"
#include "tracer/scene.h"

namespace ab {
namespace {

struct RenderArgs {
  std::string scene;
  std::string accel;
  StructureOptions structure;
  std::string output;
  int spp = 0, width = 0, height = 0, max_depth = 0, threads = 0;
  uint64_t seed = 1;
  bool heatmap = false;
  std::string metric = "nodes";
  float scale_max = 0.0f;
};

int run_render(const RenderArgs& a) {
  const Target target = load_target("", a.scene);
  const Scene& scene = *target.scene;
  RenderOptions opt = render_options(scene);
  if (a.spp) opt.spp = a.spp;
  if (a.width) opt.width = a.width;
  if (a.height) opt.height = a.height;
  if (a.max_depth) opt.max_depth = a.max_depth;
  opt.seed = a.seed;
  opt.threads = a.threads;
  opt.progress = progress_callback("rendering " + a.output);
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
  write_png(out, a.output);
  std::printf("%s: %dx%d, %d spp, %s: build %.3f s, render %.3f s, %llu rays (%.2f Mrays/s)\n",
              a.output.c_str(), opt.width, opt.height, opt.spp, accel->name().c_str(),
              accel->stats().build_seconds, seconds, static_cast<unsigned long long>(counts.total()),
              seconds > 0 ? double(counts.total()) / seconds / 1e6 : 0.0);
  return 0;
}

const CommandRegistrar kRender{
    {"render", "render a scene with the tracer (PNG), or a heatmap of traversal work", 70,
     [](CLI::App& app) -> std::function<int()> {
       auto a = std::make_shared<RenderArgs>();
       app.add_option("--scene", a->scene, "scene file (.xml)")->required()->check(CLI::ExistingFile);
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
       app.add_option("-o,--output", a->output, "output .png file")->required();
       return [a] { return run_render(*a); };
     }}};

}  // namespace
}  // namespace ab
