// --param k=v: the input is NUL-separated "k=v" strings given to Params::add, as the CLI does for each
// --param; then a structure-like reader asks for fixed keys with every getter and with Params::read
// into typed fields (as a Config does), and finish() rejects the rest. Only ab::InputError may escape,
// and a value that was accepted must lie in its range.
#include <cstdint>
#include <limits>
#include <string>

#include "accel/core/error.h"
#include "accel/core/params.h"
#include "fuzz_common.h"

namespace {

enum class Split { kSah, kMedian, kSweep };

/// Reads what a structure's Config would, round 0 with tight ranges and round 1 with the widest.
void read_config(ab::Params& p, int round) {
  constexpr long long kMin = std::numeric_limits<long long>::min(),
                      kMax = std::numeric_limits<long long>::max();
  const long long i = round ? p.get_int("i", 0, kMin, kMax) : p.get_int("i", 4, 1, 64);
  FUZZ_CHECK(round || (i >= 1 && i <= 64));
  const double f = round ? p.get_float("f", 0.5, -1e300, 1e300) : p.get_float("f", 0.5, 0.0, 1.0);
  FUZZ_CHECK(round || (f >= 0.0 && f <= 1.0));
  p.get_bool("b", false);
  const std::string c = p.get_choice("c", "sah", {"sah", "median", "sweep"});
  FUZZ_CHECK(c == "sah" || c == "median" || c == "sweep");
  uint32_t leaf = 4;
  p.read("leaf", leaf, 1u, 1024u);
  FUZZ_CHECK(leaf >= 1 && leaf <= 1024);
  float cost = 1.0f;
  p.read("cost", cost, 0.0, 1e6);
  FUZZ_CHECK(cost >= 0.0f && cost <= 1e6f);
  bool flag = true;
  p.read("flag", flag);
  Split split = Split::kSah;
  p.read("split", split, {{"sah", Split::kSah}, {"median", Split::kMedian}, {"sweep", Split::kSweep}});
  p.finish("fuzz");
  (void)p.effective().dump();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string all(reinterpret_cast<const char*>(data), size);
  ab::Params params;
  try {
    for (size_t start = 0; start <= all.size();) {
      size_t end = all.find('\0', start);
      if (end == std::string::npos) end = all.size();
      params.add(all.substr(start, end - start));
      start = end + 1;
    }
  } catch (const ab::InputError&) {
  }
  for (int round = 0; round < 2; ++round) {
    ab::Params p(params.values());
    try {
      read_config(p, round);
    } catch (const ab::InputError&) {
    }
  }
  return 0;
}
