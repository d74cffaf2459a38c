// The registration of bvh-sbvh (its name written here only).
#include "accel/bvh/bvh.h"
#include "accel/core/registry.h"

namespace ab {
namespace {
const Registrar kRegisterSbvh{structure_info<BvhSbvh>(
    "bvh-sbvh",
    "BVH, binned SAH with spatial splits (Stich, Friedrich and Dietrich 2009), reference budget; 8-wide "
    "(default) or binary (width=2)",
    63)};
}  // namespace
}  // namespace ab
