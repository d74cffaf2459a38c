#include "harness/options.h"

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

Params params_from(const std::vector<std::string>& kvs) {
  Params p;
  for (const auto& kv : kvs) p.add(kv);
  return p;
}

}  // namespace ab
