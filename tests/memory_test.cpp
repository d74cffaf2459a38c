// Peak memory of each build (issue 11, point 3): the heap accounting of accel/core/memory.h sees a scope's
// high-water mark, and every structure's build reports a peak that holds at least the structure it built.
#include "accel/core/memory.h"

#include <gtest/gtest.h>

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "accel/core/registry.h"
#include "structure_test_helpers.h"

namespace ab {
namespace {

TEST(HeapPeak, SeesTheHighWaterMarkOfAScope) {
  if (!heap_accounting_enabled()) GTEST_SKIP() << "sanitizer build: operator new is not counted";
  const uint64_t before = heap_bytes_in_use();
  const HeapPeak peak;
  {
    std::vector<char> big(10 << 20, 1);
    auto aligned = std::make_unique<std::array<double, 4096>>();  // any form of new is counted
    EXPECT_GE(heap_bytes_in_use(), before + (10u << 20));
  }
  EXPECT_GE(peak.bytes(), 10u << 20);
  EXPECT_LT(peak.bytes(), 11u << 20);
  EXPECT_LT(heap_bytes_in_use(), before + (1u << 20));  // freed again
  const HeapPeak later;                                 // a new scope starts from what is held now
  EXPECT_LT(later.bytes(), 1u << 20);
}

TEST(HeapPeak, EveryBuildReportsAPeakHoldingItsStructure) {
  if (!heap_accounting_enabled()) GTEST_SKIP() << "sanitizer build: operator new is not counted";
  auto prims = std::make_shared<const TrianglePrims>(
      std::make_shared<const Mesh>(testing::random_soup(20000, 3, 0.02f)));
  for (const AcceleratorInfo& info : accelerators()) {
    // The project's structures, and Embree (its monitor's peak plus the heap's); brute builds nothing and
    // the outside peers allocate partly outside operator new; test-only structures are left out.
    if ((info.is_reference && info.name != "embree") || info.name.rfind("test-", 0) == 0) continue;
    auto accel = make_accelerator(info.name, prims, Params());
    accel->build();
    const BuildStats& s = accel->stats();
    EXPECT_GT(s.peak_bytes, 0u) << info.name;
    EXPECT_GE(s.peak_bytes, s.bytes) << info.name;
    EXPECT_EQ(to_json(s)["peak_bytes"], s.peak_bytes) << info.name;
  }
}

}  // namespace
}  // namespace ab
