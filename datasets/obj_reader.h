// Wavefront OBJ, read directly: OpenMesh's OBJ reader removes repeated corners from a face and drops
// faces left with fewer than three (and skips vertex lines it cannot parse), which shifts ids.
#pragma once

#include <string>

#include "accel/core/mesh.h"

namespace ab {

/// Reads the v and f statements of an OBJ file in order (other statements are ignored): each face
/// v0 v1 ... vk, written as i, i/t, i//n or i/t/n with 1-based or negative (relative) indices,
/// becomes (v0,v1,v2), (v0,v2,v3), ... and every face is kept. Throws InputError naming the file and
/// line for unparsable numbers, NaN or infinite coordinates, out-of-range indices and faces with
/// fewer than three corners.
Mesh read_obj(const std::string& path);

}  // namespace ab
