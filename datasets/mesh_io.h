// Mesh files: OBJ, PLY (ASCII and binary), OFF (ASCII) and STL with the contract's id rule (face order
// kept, polygons fan-triangulated, every face kept): PLY through OpenMesh's reader after checks of our
// own, OBJ, OFF and STL by readers of our own.
#pragma once

#include <string>

#include "accel/core/mesh.h"

namespace ab {

/// Reads a mesh; the format is chosen by extension. Throws InputError naming the file (missing,
/// unknown extension, malformed, NaN or infinite coordinates, out-of-range indices).
Mesh read_mesh(const std::string& path);

/// Writes a mesh in the format of the extension (.obj, .ply, .off, .stl), whole or not at all.
/// Same mesh, same bytes. Throws InputError.
void write_mesh(const Mesh& mesh, const std::string& path);

}  // namespace ab
