// The .rays and .hits files of the contract (little-endian, fixed-size records).
#pragma once

#include <string>
#include <vector>

#include "accel/core/aabb.h"

namespace ab {

/// Reads a .rays file; throws InputError naming the file (missing, wrong magic, truncated records,
/// trailing bytes, NaN or infinite origin/direction/tmin, NaN tmax).
std::vector<Ray> read_rays(const std::string& path);
/// Writes a .rays file whole or not at all.
void write_rays(const std::string& path, const std::vector<Ray>& rays);
/// Reads a .hits file; throws InputError naming the file.
std::vector<Hit> read_hits(const std::string& path);
/// Writes a .hits file whole or not at all.
void write_hits(const std::string& path, const std::vector<Hit>& hits);

}  // namespace ab
