// Brute force: tests every primitive. The ground truth for every structure of the project.
#pragma once

#include <memory>

#include "accel/core/accelerator.h"
#include "accel/core/params.h"

namespace ab {

/// Tests every primitive for every ray, in id order.
template <class P>
class Brute final : public AcceleratorBase<Brute<P>> {
 public:
  using Prims = P;
  /// Brute force has no parameters.
  struct Config {
    /// Reads nothing.
    static Config read(Params&) { return {}; }
  };

  /// Over prims; the build only records the counts.
  Brute(std::shared_ptr<const P> prims, const Config&) : prims_(std::move(prims)) {}

  AABB bounds() const override { return prims_->bounds(); }

  /// Closest hit over all primitives.
  template <bool kCount>
  void intersect_ray(const Ray& ray, Hit& best, uint32_t inst, RayCounters& c) const {
    const size_t n = prims_->size();
    for (size_t i = 0; i < n; ++i) prims_->template intersect<kCount>(i, ray, best, inst, c);
  }
  /// First hit in id order.
  template <bool kCount>
  bool occluded_ray(const Ray& ray, RayCounters& c) const {
    const size_t n = prims_->size();
    for (size_t i = 0; i < n; ++i)
      if (prims_->template occluded<kCount>(i, ray, c)) return true;
    return false;
  }

 protected:
  void do_build() override {}
  void gather_stats(BuildStats& stats) const override {
    stats.primitives = prims_->size();
    stats.references = prims_->size();
  }

 private:
  std::shared_ptr<const P> prims_;
};

}  // namespace ab
