#include "accel/octree/octree.h"

#include "accel/core/registry.h"

namespace ab {
namespace {
const Registrar kRegisterOctree{structure_info<Octree>(
    "octree", "adaptive octree, exact triangle/box insertion, parametric front-to-back traversal", 20)};
}  // namespace
}  // namespace ab
