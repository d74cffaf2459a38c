// `accelbench flatten --scene F -o FILE.obj`: the scene's instanced geometry as one world-space mesh.
#include <memory>

#include "datasets/mesh_io.h"
#include "harness/cli.h"
#include "tracer/scene.h"

namespace ab {
namespace {

struct FlattenArgs {
  std::string scene;
  std::string output;
};

const CommandRegistrar kFlatten{
    {"flatten", "write a scene as one world-space mesh (instances in document order)", 80,
     [](CLI::App& app) -> std::function<int()> {
       auto a = std::make_shared<FlattenArgs>();
       app.add_option("--scene", a->scene, "scene file (.xml)")->required()->check(CLI::ExistingFile);
       app.add_option("-o,--output", a->output, "output mesh (.obj, .ply, .off, .stl)")->required();
       return [a] {
         write_mesh(flatten_scene(load_scene(a->scene)), a->output);
         return 0;
       };
     }}};

}  // namespace
}  // namespace ab
