// Tracing a batch of rays on TBB: the same hits for every thread count (each ray is independent).
#pragma once

#include <span>

#include "accel/core/accelerator.h"

namespace ab {

/// Closest hit of every ray on `threads` threads (0: all hardware threads), in chunks of rays.
void trace_closest(const Accelerator& accel, std::span<const Ray> rays, std::span<Hit> hits, int threads);
/// Any hit of every ray on `threads` threads.
void trace_occluded(const Accelerator& accel, std::span<const Ray> rays, std::span<uint8_t> out, int threads);
/// Closest hit with counters (the counting pass), summed over all rays.
RayCounters trace_closest_counted(const Accelerator& accel, std::span<const Ray> rays, std::span<Hit> hits,
                                  int threads);

}  // namespace ab
