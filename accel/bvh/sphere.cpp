// The registration of bvh-sphere (its name written here only).
#include "accel/bvh/sphere.h"

#include "accel/core/registry.h"

namespace ab {
namespace {
const Registrar kRegisterSphere{structure_info<BvhSphere>(
    "bvh-sphere", "bounding-sphere hierarchy: bvh-sah's binary tree with a sphere per node (Ritter 1990)",
    63)};
}  // namespace
}  // namespace ab
