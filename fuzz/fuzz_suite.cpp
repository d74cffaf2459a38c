// read_suite(): a suite file as `accelbench run` reads it (JSON with comments, then parse_suite). Only
// ab::InputError may escape. validate_suite is not called: it creates structures and generates meshes,
// which are not parsing (and need the structures this build leaves out).
#include <cstdint>

#include "accel/core/error.h"
#include "fuzz_common.h"
#include "harness/suite.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& path = fuzz::write_input(data, size, "json");
  try {
    const ab::Suite suite = ab::read_suite(path);
    FUZZ_CHECK(!suite.scenes.empty() && !suite.accelerators.empty());
    FUZZ_CHECK(suite.build_only || !suite.rays.empty());
  } catch (const ab::InputError&) {
  }
  return 0;
}
