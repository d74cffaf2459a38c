#include "accel/kdtree/kdtree.h"

#include "accel/core/registry.h"

namespace ab {
namespace {
const Registrar kRegisterKdMedian{structure_info<KdTreeMedian>(
    "kdtree-median", "k-d tree, median splits along the longest axis, conservative insertion", 30)};
const Registrar kRegisterKdSah{structure_info<KdTreeSah>(
    "kdtree-sah", "k-d tree, O(N log N) SAH build with perfect splits (Wald and Havran 2006)", 31)};
}  // namespace
}  // namespace ab
