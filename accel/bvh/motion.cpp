// The registration of bvh-motion (its name written here only).
#include "accel/bvh/motion.h"

#include "accel/core/registry.h"

namespace ab {
namespace {
const Registrar kRegisterMotion{structure_info<BvhMotion>(
    "bvh-motion",
    "motion BVH: linear bounds per node at the ray's time, temporal splits (Woop et al. 2017, STBVH)", 66)};
}  // namespace
}  // namespace ab
