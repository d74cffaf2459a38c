// STL files, read and written directly (not through OpenMesh): OpenMesh's STL reader merges equal
// positions and drops triangles whose merged corners coincide, which would shift triangle ids.
#pragma once

#include <ostream>
#include <string>

#include "accel/core/mesh.h"

namespace ab {

/// Reads ASCII or binary STL; every facet becomes one triangle with three new vertices, in file
/// order (degenerate and duplicate facets included). Throws InputError naming the file.
Mesh read_stl(const std::string& path);
/// Writes binary STL (80-byte header, count, 50 bytes per triangle with its unit normal).
void write_stl(const Mesh& mesh, std::ostream& out);

}  // namespace ab
