// The per-ray mailbox of the structures that reference a primitive from several cells (grid, octree).
#pragma once

#include <array>
#include <cstdint>

#include "accel/core/ray.h"

namespace ab {

/// A small direct-mapped per-ray mailbox (Amanatides and Woo 1987, section 4): remembers recently tested
/// ids so a primitive spanning several cells is tested once. It lives on the tracing thread's stack, so it
/// is thread-safe; a collision only costs a repeated test, never a skipped one.
class Mailbox {
 public:
  Mailbox() { slots_.fill(kInvalidId); }
  /// True when id was already tested for this ray; otherwise records it and returns false.
  bool seen(uint32_t id) {
    uint32_t& slot = slots_[id & (kSize - 1)];
    if (slot == id) return true;
    slot = id;
    return false;
  }

 private:
  static constexpr uint32_t kSize = 64;
  std::array<uint32_t, kSize> slots_;
};

}  // namespace ab
