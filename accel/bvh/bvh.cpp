// The registration of the three BVH structures (each name written here only).
#include "accel/bvh/bvh.h"

#include "accel/core/registry.h"

namespace ab {
namespace {
const Registrar kRegisterMedian{structure_info<BvhMedian>(
    "bvh-median", "BVH, object median of centroids on the longest axis (width=2|8)", 60)};
const Registrar kRegisterSah{structure_info<BvhSah>(
    "bvh-sah", "BVH, binned SAH (Wald 2007), parallel build; 8-wide (default) or binary (width=2)", 61)};
const Registrar kRegisterSweep{structure_info<BvhSweep>(
    "bvh-sweep", "BVH, full sweep SAH on all axes (quality reference; width=2|8)", 62)};
}  // namespace
}  // namespace ab
