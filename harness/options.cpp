#include "harness/options.h"

#include "harness/cli.h"

namespace ab {

void TargetOptions::add(CLI::App& app) {
  auto* m = app.add_option("--mesh", mesh, "mesh file (.obj, .ply, .off, .stl)")->check(CLI::ExistingFile);
  auto* s = app.add_option("--scene", scene, "scene file (.xml)")->check(CLI::ExistingFile);
  m->excludes(s);
  s->excludes(m);
  app.callback([&app, this] {
    if (mesh.empty() && scene.empty()) throw CLI::RequiredError("--mesh or --scene");
    (void)app;
  });
}

void StructureOptions::add(CLI::App& app) {
  app.add_option("--accel-top", top, "scenes: top-level accelerator")->check(accelerator_name_validator());
  app.add_option("--accel-bottom", bottom, "scenes: per-mesh accelerator")
      ->check(accelerator_name_validator());
  app.add_option("--param", params, "accelerator parameter k=v (repeatable)");
}

void add_threads_option(CLI::App& app, int& threads) {
  app.add_option("--threads", threads, "threads (0: all cores)")->check(CLI::Range(0, 1024));
}

Params params_from(const std::vector<std::string>& kvs) {
  Params p;
  for (const auto& kv : kvs) p.add(kv);
  return p;
}

}  // namespace ab
