// `accelbench export --scene F -o FILE.glb|FILE.gltf`: a scene (its meshes, instances and rigid keyframes)
// as glTF 2.0, so the project makes its own animated glTF scenes.
#include <memory>

#include "harness/cli.h"
#include "tracer/gltf.h"
#include "tracer/scene.h"

namespace ab {
namespace {

struct ExportArgs {
  std::string scene;
  std::string output;
};

const CommandRegistrar kExport{
    {"export", "write a scene as glTF 2.0 (.glb, or .gltf with an embedded buffer)", 85,
     [](CLI::App& app) -> std::function<int()> {
       auto a = std::make_shared<ExportArgs>();
       app.add_option("--scene", a->scene, "scene file (.xml, .gltf, .glb)")
           ->required()
           ->check(CLI::ExistingFile);
       app.add_option("-o,--output", a->output, "output .glb or .gltf file")->required();
       return [a] {
         write_gltf_scene(load_scene(a->scene), a->output);
         return 0;
       };
     }}};

}  // namespace
}  // namespace ab
