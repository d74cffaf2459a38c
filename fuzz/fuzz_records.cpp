// read_rays() / read_hits() (FUZZ_RECORDS = 0 for .rays, 1 for .hits): magic, count, size and
// finiteness checks of the fixed-record binary files. An accepted file must be exactly its records.
#include <cmath>
#include <cstdint>

#include "accel/core/error.h"
#include "fuzz_common.h"
#include "harness/hitfile.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
#if FUZZ_RECORDS == 0
  const std::string& path = fuzz::write_input(data, size, "rays");
  try {
    const auto rays = ab::read_rays(path);
    FUZZ_CHECK(size == 16 + ab::ray_record_bytes(path) * rays.size());  // ABRAYS01: 32, ABRAYS02: 36
    for (const auto& r : rays) {
      for (float f : {r.org.x, r.org.y, r.org.z, r.dir.x, r.dir.y, r.dir.z, r.tmin})
        FUZZ_CHECK(std::isfinite(f));
      FUZZ_CHECK(!std::isnan(r.tmax));
      FUZZ_CHECK(r.time >= 0.0f && r.time <= 1.0f);
    }
  } catch (const ab::InputError&) {
  }
#else
  const std::string& path = fuzz::write_input(data, size, "hits");
  try {
    const auto hits = ab::read_hits(path);
    FUZZ_CHECK(size == 16 + 20 * hits.size());
  } catch (const ab::InputError&) {
  }
#endif
  return 0;
}
