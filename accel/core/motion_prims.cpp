#include "accel/core/motion_prims.h"

#include <cstring>

namespace ab {

MotionTrianglePrims::MotionTrianglePrims(std::vector<std::shared_ptr<const Mesh>> steps)
    : meshes_(std::move(steps)), steps_(static_cast<uint32_t>(meshes_.size())) {
  if (steps_ < 2) throw std::invalid_argument("a moving mesh needs at least two time steps");
  const Mesh& first = *meshes_.front();
  for (const auto& m : meshes_)
    if (m->triangles != first.triangles)
      throw std::invalid_argument("the time steps of a moving mesh must share one triangle list");
  const size_t n = first.size();
  tris_.resize(n * steps_);
  moves_.resize(n);
  swept_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    Triangle* t = &tris_[i * steps_];
    for (uint32_t k = 0; k < steps_; ++k) {
      t[k] = meshes_[k]->triangle(i);
      swept_[i].extend(t[k].bounds());
      if (std::memcmp(&t[k], &t[0], sizeof(Triangle)) != 0) moves_[i] = 1;
    }
    bounds_.extend(swept_[i]);
  }
}

}  // namespace ab
