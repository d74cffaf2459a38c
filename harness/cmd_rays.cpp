// `accelbench rays (--mesh F | --scene F) --kind KIND --count N [--seed S] [--views V] -o FILE.rays`
#include <memory>

#include "datasets/rays.h"
#include "harness/cli.h"
#include "harness/hitfile.h"
#include "harness/options.h"
#include "harness/target.h"

namespace ab {
namespace {

struct RaysArgs {
  TargetOptions target;
  std::string kind;
  uint64_t count = 0;
  uint64_t seed = 1;
  uint32_t views = 1;
  std::string output;
};

const CommandRegistrar kRays{
    {"rays", "write a ray set (.rays)", 30, [](CLI::App& app) -> std::function<int()> {
       auto a = std::make_shared<RaysArgs>();
       a->target.add(app);
       app.add_option("--kind", a->kind, "ray kind (see list)")->required();
       app.add_option("--count", a->count, "number of rays")
           ->required()
           ->check(CLI::Range(uint64_t{0}, uint64_t{1'000'000'000}));
       app.add_option("--seed", a->seed, "random seed");
       app.add_option("--views", a->views, "primary rays from V cameras placed around the bounds (default 1)")
           ->check(CLI::Range(uint32_t{1}, uint32_t{4096}));
       app.add_option("-o,--output", a->output, "output .rays file")->required();
       return [a] {
         const Target target =
             load_target(a->target.mesh, a->target.scene, a->target.frame.normalized_time());
         // Scenes: the tracer's own kinds (camera and lights of the scene).
         const std::vector<Ray> rays = make_target_rays(target, a->kind, a->count, a->seed, a->views);
         write_rays(a->output, rays, a->kind == "motion" ? RayFileVersion::kV2 : RayFileVersion::kV1);
         return 0;
       };
     }}};

}  // namespace
}  // namespace ab
