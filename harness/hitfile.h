// The .rays and .hits files of the contract (little-endian, fixed-size records).
#pragma once

#include <string>
#include <vector>

#include "accel/core/aabb.h"

namespace ab {

/// The two versions of the .rays file: ABRAYS01 (32-byte records, no time) and ABRAYS02 (36 bytes, with
/// the ray's time in the shutter, for motion blur).
enum class RayFileVersion { kV1, kV2 };

/// Reads a .rays file of either version (ABRAYS01 rays get time 0); throws InputError naming the file
/// (missing, wrong magic, truncated records, trailing bytes, NaN or infinite origin/direction/tmin, NaN
/// tmax, a time that is NaN or outside [0, 1]).
std::vector<Ray> read_rays(const std::string& path);
/// Writes a .rays file whole or not at all: ABRAYS01 (the times dropped) unless version 2 is asked for.
void write_rays(const std::string& path, const std::vector<Ray>& rays,
                RayFileVersion version = RayFileVersion::kV1);
/// Bytes per ray record of a .rays file (32 for ABRAYS01, 36 for ABRAYS02), from its magic.
size_t ray_record_bytes(const std::string& path);
/// Reads a .hits file; throws InputError naming the file.
std::vector<Hit> read_hits(const std::string& path);
/// Writes a .hits file whole or not at all.
void write_hits(const std::string& path, const std::vector<Hit>& hits);

}  // namespace ab
