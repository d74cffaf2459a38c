// `accelbench trace (--mesh F | --scene F) --accel NAME --rays FILE.rays -o FILE.hits [--threads T]
//  [--stats FILE.json] [--param k=v ...] [--accel-top NAME] [--accel-bottom NAME]`
#include <chrono>
#include <memory>

#include "accel/core/trace.h"
#include "datasets/atomic_file.h"
#include "harness/cli.h"
#include "harness/hitfile.h"
#include "harness/options.h"
#include "harness/target.h"
#include "harness/timing.h"

namespace ab {
namespace {

struct TraceArgs {
  TargetOptions target;
  std::string accel;
  StructureOptions structure;
  std::string rays;
  std::string output;
  int threads = 0;
  std::string stats;
};

int run_trace(const TraceArgs& a) {
  const Target target = load_target(a.target.mesh, a.target.scene, a.target.frame.normalized_time());
  const std::vector<Ray> rays = read_rays(a.rays);
  std::unique_ptr<Accelerator> accel = make_target_accelerator(
      target, a.accel, params_from(a.structure.params), a.structure.top, a.structure.bottom);
  accel->build();
  std::vector<Hit> hits(rays.size());
  const auto start = std::chrono::steady_clock::now();
  trace_closest(*accel, rays, hits, a.threads);
  const double seconds = seconds_since(start);
  if (!a.stats.empty()) {
    // The counting pass is separate, so counters never slow the timed pass above.
    std::vector<Hit> counted(rays.size());
    const RayCounters counters = trace_closest_counted(*accel, rays, counted, a.threads);
    accel->measure_quality();
    nlohmann::json j = {{"accelerator", accel->name()},
                        {"requested", a.accel},
                        {"params", accel->config()},
                        {"input", target.path},
                        {"triangles", target.triangles},
                        {"rays", rays.size()},
                        {"threads", a.threads},
                        {"build_seconds", accel->stats().build_seconds},
                        {"trace_seconds", seconds},
                        {"rays_per_second", seconds > 0 ? double(rays.size()) / seconds : 0.0},
                        {"per_ray", to_json(counters, rays.size())},
                        {"build", to_json(accel->stats())}};
    write_file_atomically(
        a.stats, [&](std::ostream& out) { out << j.dump(2) << "\n"; }, false);
  }
  write_hits(a.output, hits);
  return 0;
}

const CommandRegistrar kTrace{
    {"trace", "closest hit for every ray (.hits)", 40, [](CLI::App& app) -> std::function<int()> {
       auto a = std::make_shared<TraceArgs>();
       a->target.add(app);
       app.add_option("--accel", a->accel, "accelerator (see list)")
           ->required()
           ->check(accelerator_name_validator());
       a->structure.add(app);
       app.add_option("--rays", a->rays, "input .rays file")->required()->check(CLI::ExistingFile);
       app.add_option("-o,--output", a->output, "output .hits file")->required();
       add_threads_option(app, a->threads);
       app.add_option("--stats", a->stats, "write build and traversal statistics (JSON)");
       return [a] { return run_trace(*a); };
     }}};

}  // namespace
}  // namespace ab
