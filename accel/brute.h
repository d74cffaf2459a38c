// Brute force: tests every primitive. The ground truth for every structure of the project.
#pragma once

#include "accel/accelerator.h"
#include "accel/params.h"

#include <memory>

namespace ab {

/// Tests every primitive for every ray, in id order.
template <class P>
class Brute final : public AcceleratorBase<Brute<P>> {
 public:
  /// Brute force has no parameters.
  Brute(std::shared_ptr<const P> prims, Params& params) : prims_(std::move(prims)), config_(params.effective()) {}

  std::string name() const override { return "brute"; }
  nlohmann::json config() const override { return config_; }
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
  void do_build() override {
    this->stats_ = BuildStats{};
    this->stats_.primitives = prims_->size();
    this->stats_.references = prims_->size();
  }

 private:
  std::shared_ptr<const P> prims_;
  nlohmann::json config_;
};

}  // namespace ab
