// A thin-lens camera (Cook, Porter and Carpenter 1984, "Distributed ray tracing": depth of field by
// distributing rays over the lens). With aperture 0 it is a pinhole camera.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>

#include "accel/core/aabb.h"

namespace ab {

/// Camera as written in the scene file.
struct Camera {
  vec3 eye{0.0f, 0.0f, 5.0f};
  vec3 look_at{0.0f};
  vec3 up{0.0f, 1.0f, 0.0f};
  float fov_degrees = 45.0f;    ///< vertical field of view
  float aperture = 0.0f;        ///< lens radius in world units (0: pinhole)
  float focal_distance = 0.0f;  ///< distance to the plane in focus (0: distance from eye to look_at)
  float shutter_open = 0.0f;    ///< scene time (keys' units) the shutter opens, relative to the frame's time
  float shutter_close = 0.0f;   ///< ... and closes (== shutter_open: closed, no motion blur)
  uint32_t motion_steps = 3;    ///< time steps the motion is sampled at over the shutter (>= 2)

  /// True when the shutter spans an interval (motion blur).
  bool has_shutter() const { return shutter_close > shutter_open; }
};

/// The camera prepared for an image of a given aspect: generates primary rays.
class CameraRays {
 public:
  /// Prepares the frame for width x height pixels.
  CameraRays(const Camera& camera, int width, int height);

  /// Ray through image position (px, py) in pixels (0,0 = top-left corner of the image), from lens
  /// position (lu, lv) in [0,1)^2 (ignored for a pinhole). Direction: normalized.
  Ray generate(float px, float py, float lu, float lv) const;
  /// True when the camera has a lens (aperture > 0).
  bool has_lens() const { return aperture_ > 0.0f; }

 private:
  vec3 eye_, forward_, right_, up_;
  float half_w_, half_h_;
  float width_, height_;
  float aperture_, focal_;
};

}  // namespace ab
