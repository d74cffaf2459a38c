// `accelbench flatten --scene F [--time T | --frame F --frames N] -o FILE.obj`: the scene's instanced
// geometry as one world-space mesh.
#include <memory>

#include "datasets/mesh_io.h"
#include "harness/cli.h"
#include "harness/options.h"
#include "tracer/scene.h"

namespace ab {
namespace {

struct FlattenArgs {
  std::string scene;
  FrameOptions frame;
  std::string output;
};

const CommandRegistrar kFlatten{
    {"flatten", "write a scene as one world-space mesh (instances in document order)", 80,
     [](CLI::App& app) -> std::function<int()> {
       auto a = std::make_shared<FlattenArgs>();
       app.add_option("--scene", a->scene, "scene file (.xml, .gltf, .glb)")
           ->required()
           ->check(CLI::ExistingFile);
       a->frame.add(app);
       app.add_option("-o,--output", a->output, "output mesh (.obj, .ply, .off, .stl)")->required();
       return [a] {
         const float time = a->frame.normalized_time();
         const Scene scene = load_scene(a->scene);
         write_mesh(flatten_scene(scene.animated() && time != 0.0f ? scene_at(scene, time) : scene),
                    a->output);
         return 0;
       };
     }}};

}  // namespace
}  // namespace ab
