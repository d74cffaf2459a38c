// Checks run on PLY and OFF files before OpenMesh's readers see them. Those readers assume
// well-formed input: a PLY header without end_header makes the PLY reader loop forever, and an
// unparsable OFF number silently shifts everything after it. These checks turn such files into
// one-line InputErrors naming the file (and line).
#pragma once

#include <string>

namespace ab {

/// Validates a PLY file: the header (magic, a known format, element and property lines with known
/// types, a vertex element with x, y, z, a list property on the face element, end_header) and, for
/// ASCII PLY, the body (numbers, finite coordinates, face indices in range, no missing lines).
void check_ply(const std::string& path);

/// Validates a plain ASCII OFF file ("OFF" keyword; variants and binary OFF are left to OpenMesh):
/// counts, three finite coordinates per vertex, faces of at least three in-range indices, and no
/// missing lines.
void check_ascii_off(const std::string& path);

}  // namespace ab
