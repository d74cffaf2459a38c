#include "accel/reference/brute.h"

#include "accel/core/registry.h"

namespace ab {
namespace {
const Registrar kRegisterBrute{[] {
  AcceleratorInfo info = structure_info<Brute>("brute", "tests every triangle; the ground truth", 0);
  info.is_reference = true;
  return info;
}()};
}  // namespace
}  // namespace ab
