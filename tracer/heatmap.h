// False-colour images of per-pixel traversal work, with a colour scale bar, so structures can be
// compared by eye.
#pragma once

#include <string>
#include <vector>

#include "tracer/image.h"

namespace ab {

/// Viridis colour map (van der Walt and Smith 2015), t in [0,1], as 8-bit RGB.
void viridis(float t, uint8_t rgb[3]);

/// Maps values (width x height, row-major) linearly from 0 to `scale_max` (0: their maximum; larger
/// values saturate) onto viridis and adds a scale bar below the image, labelled with 0, the midpoint
/// and the maximum, and `label`.
Image8 heatmap_image(const std::vector<float>& values, int width, int height, const std::string& label,
                     float scale_max = 0.0f);

}  // namespace ab
