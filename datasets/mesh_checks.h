// Checks run on PLY files before OpenMesh's reader sees them. That reader assumes well-formed input: a
// PLY header without end_header or with a version that is not a number makes it loop forever, a binary
// body shorter than the header declares is read past its end, and an unparsable ASCII number silently
// shifts everything after it. These checks turn such files into one-line InputErrors naming the file
// (and line). (OFF is read by datasets/off_reader.h.)
#pragma once

#include <string>

namespace ab {

/// Validates a PLY file: the header (magic, a known format, element and property lines with known
/// types, a vertex element with x, y, z, a list property on the face element, end_header) and, for
/// ASCII PLY, the body (numbers, finite coordinates, face indices in range, no missing lines); for
/// binary PLY, that the body is long enough for the declared elements.
void check_ply(const std::string& path);

}  // namespace ab
