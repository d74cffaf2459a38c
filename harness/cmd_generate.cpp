// `accelbench generate GEN --triangles N [--seed S] [--param k=v ...] -o FILE`
#include <memory>

#include "datasets/generators.h"
#include "datasets/mesh_io.h"
#include "harness/cli.h"
#include "harness/options.h"

namespace ab {
namespace {

struct GenerateArgs {
  std::string generator;
  uint64_t triangles = 0;
  uint64_t seed = 1;
  std::vector<std::string> params;
  std::string output;
};

CLI::Validator generator_name() {
  return CLI::Validator(
      [](std::string& v) -> std::string {
        std::string known;
        for (const auto& g : generators()) {
          if (g.name == v) return {};
          known += (known.empty() ? "" : ", ") + g.name;
        }
        return "unknown generator '" + v + "' (known: " + known + ")";
      },
      "GEN");
}

const CommandRegistrar kGenerate{
    {"generate", "write a generated mesh (.obj, .ply, .off or .stl by extension)", 20,
     [](CLI::App& app) -> std::function<int()> {
       auto a = std::make_shared<GenerateArgs>();
       app.add_option("GEN", a->generator, "generator name (see list)")->required()->check(generator_name());
       app.add_option("--triangles", a->triangles, "about this many triangles")
           ->required()
           ->check(CLI::Range(uint64_t{1}, uint64_t{100'000'000}));
       app.add_option("--seed", a->seed, "random seed");
       app.add_option("--param", a->params, "generator parameter k=v (repeatable)");
       app.add_option("-o,--output", a->output, "output mesh file")->required();
       return [a] {
         const Mesh mesh = generate_mesh(a->generator, a->triangles, a->seed, params_from(a->params));
         write_mesh(mesh, a->output);
         return 0;
       };
     }}};

}  // namespace
}  // namespace ab
