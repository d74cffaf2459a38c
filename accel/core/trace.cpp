#include "accel/core/trace.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

namespace ab {

namespace {
constexpr size_t kChunk = 256;

template <class F>
void run_chunks(size_t n, int threads, F&& body) {
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kChunk),
                      [&](const tbb::blocked_range<size_t>& r) { body(r.begin(), r.end() - r.begin()); });
  });
}
}  // namespace

void trace_closest(const Accelerator& accel, std::span<const Ray> rays, std::span<Hit> hits, int threads) {
  run_chunks(rays.size(), threads, [&](size_t begin, size_t count) {
    accel.intersect(rays.subspan(begin, count), hits.subspan(begin, count));
  });
}

void trace_occluded(const Accelerator& accel, std::span<const Ray> rays, std::span<uint8_t> out,
                    int threads) {
  run_chunks(rays.size(), threads, [&](size_t begin, size_t count) {
    accel.occluded(rays.subspan(begin, count), out.subspan(begin, count));
  });
}

RayCounters trace_closest_counted(const Accelerator& accel, std::span<const Ray> rays, std::span<Hit> hits,
                                  int threads) {
  tbb::combinable<RayCounters> partial;
  run_chunks(rays.size(), threads, [&](size_t begin, size_t count) {
    accel.intersect_counted(rays.subspan(begin, count), hits.subspan(begin, count), partial.local());
  });
  RayCounters total;
  partial.combine_each([&](const RayCounters& c) { total += c; });
  return total;
}

}  // namespace ab
