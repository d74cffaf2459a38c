#include "tracer/camera.h"

#include <cmath>

#include "tracer/sampling.h"

namespace ab {

CameraRays::CameraRays(const Camera& c, int width, int height)
    : eye_(c.eye), width_(float(width)), height_(float(height)), aperture_(c.aperture) {
  forward_ = glm::normalize(c.look_at - c.eye);
  right_ = glm::normalize(glm::cross(forward_, c.up));
  up_ = glm::cross(right_, forward_);
  half_h_ = std::tan(glm::radians(c.fov_degrees) * 0.5f);
  half_w_ = half_h_ * width_ / height_;
  focal_ = c.focal_distance > 0.0f ? c.focal_distance : glm::length(c.look_at - c.eye);
}

Ray CameraRays::generate(float px, float py, float lu, float lv) const {
  const float sx = (2.0f * px / width_ - 1.0f) * half_w_;
  const float sy = (1.0f - 2.0f * py / height_) * half_h_;
  const vec3 dir = forward_ + sx * right_ + sy * up_;
  Ray ray;
  if (aperture_ <= 0.0f) {
    ray.org = eye_;
    ray.dir = glm::normalize(dir);
    return ray;
  }
  // Thin lens: every ray through the lens point meets the pinhole ray on the focal plane.
  const vec3 focus = eye_ + dir * focal_;
  const glm::vec2 d = sample_disk(lu, lv) * aperture_;
  ray.org = eye_ + d.x * right_ + d.y * up_;
  ray.dir = glm::normalize(focus - ray.org);
  return ray;
}

}  // namespace ab
