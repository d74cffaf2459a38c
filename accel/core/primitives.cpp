#include "accel/core/primitives.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

namespace ab {

TrianglePrims::TrianglePrims(std::shared_ptr<const Mesh> mesh) : mesh_(std::move(mesh)) {
  tris_.resize(mesh_->size());
  // Fixed chunks joined in order (parallel_deterministic_reduce): glm::min/max keep the earlier operand on
  // ties and never take a NaN second operand, so the bounds are bit for bit the serial fold's (signed zeros
  // included) on any thread count.
  constexpr size_t kGrain = 16384;
  bounds_ = tbb::parallel_deterministic_reduce(
      tbb::blocked_range<size_t>(0, tris_.size(), kGrain), AABB{},
      [&](const tbb::blocked_range<size_t>& r, AABB b) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
          tris_[i] = mesh_->triangle(i);
          b.extend(tris_[i].bounds());
        }
        return b;
      },
      [](AABB a, const AABB& b) {
        a.extend(b);
        return a;
      });
}

}  // namespace ab
