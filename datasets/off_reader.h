// Object File Format (Geomview OFF), read directly: OpenMesh's OFF reader uses uninitialized counts
// when they cannot be read, reads binary bodies past the end of the file and hangs on huge counts, so
// ASCII OFF is read here like OBJ and STL, and the variants it cannot read safely are rejected.
#pragma once

#include <string>

#include "accel/core/mesh.h"

namespace ab {

/// Reads an ASCII OFF file: the keyword (OFF, or a variant with per-vertex extras: [ST][C][N]OFF),
/// the vertex and face counts (on the keyword line or the next), one vertex per line (x y z first;
/// the variant's extras after them are ignored) and one face per line (n i0 ... i(n-1); a colour after
/// the indices is ignored). Blank lines and # comments are skipped. Faces keep their file order and
/// are fan-triangulated, every face kept. Throws InputError naming the file (and line) for a missing
/// or unsupported keyword (binary OFF, 4OFF, nOFF), bad or missing counts, unparsable numbers, NaN or
/// infinite coordinates, faces of fewer than three corners, out-of-range indices and missing lines.
Mesh read_off(const std::string& path);

}  // namespace ab
