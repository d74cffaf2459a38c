#include "accel/bsp/bsp.h"

#include "accel/core/registry.h"

namespace ab {
namespace {
const Registrar kRegisterBsp{structure_info<BspTree>(
    "bsp", "BSP tree, arbitrary planes (13 directions + triangles' own planes), SAH over the cell", 35)};
}  // namespace
}  // namespace ab
