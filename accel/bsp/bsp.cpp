#include "accel/bsp/bsp.h"

#include "accel/core/registry.h"

namespace ab {
namespace {
const Registrar kRegisterBsp{structure_info<BspTree>(
    "bsp",
    "BSP tree, arbitrary planes (up to 13 fixed directions + triangles' own planes), SAH over the cell", 35)};
}  // namespace
}  // namespace ab
