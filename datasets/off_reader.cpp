#include "datasets/off_reader.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <string_view>
#include <vector>

#include "datasets/io_util.h"

namespace ab {
namespace {

/// Line reader for OFF: skips blank lines and # comments, counts lines, and hands out tokens.
struct OffLines {
  std::istream& in;
  const std::string& path;
  size_t line = 0;
  std::string text;
  std::string_view rest;

  /// Moves to the next non-empty, non-comment line; false at the end of the file.
  bool next() {
    while (std::getline(in, text)) {
      ++line;
      rest = std::string_view(text).substr(0, text.find('#'));
      if (rest.find_first_not_of(" \t\r") != std::string_view::npos) return true;
    }
    return false;
  }
  /// True when the current line has no token left.
  bool line_done() const { return rest.find_first_not_of(" \t\r") == std::string_view::npos; }
  /// The next token of the current line ("" when there is none).
  std::string_view token() { return next_token(rest); }
  /// The next token as a non-negative integer, or throws.
  long long integer(const char* what) {
    const std::string_view t = token();
    long long value = -1;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
    if (t.empty() || ec != std::errc() || end != t.data() + t.size() || value < 0)
      throw error(std::string("expected ") + what + (t.empty() ? "" : ", got '" + std::string(t) + "'"));
    return value;
  }
  /// An error naming the file and current line.
  InputError error(const std::string& what) const {
    return InputError(path + ":" + std::to_string(line) + ": " + what);
  }
};

/// Checks the keyword: [ST][C][N]OFF (per-vertex texture coordinates, colour and normal after x y z)
/// is read; 4OFF and nOFF (other dimensions) and binary OFF are rejected by name.
void check_keyword(OffLines& off) {
  const std::string keyword(off.next() ? off.token() : std::string_view{});
  std::string_view k = keyword;
  for (std::string_view prefix : {"ST", "C", "N"})
    if (k.substr(0, prefix.size()) == prefix) k.remove_prefix(prefix.size());
  if (k == "4OFF" || k == "nOFF" || k == "4nOFF")
    throw off.error("'" + keyword + "' (a 4-dimensional or n-dimensional OFF) is not supported");
  if (k != "OFF") {
    if (keyword.find("OFF") == std::string::npos)
      throw InputError(off.path + ": not an OFF file (no OFF keyword)");
    throw off.error("unknown OFF keyword '" + keyword + "' (expected OFF, COFF, NOFF, STOFF, ...)");
  }
  const std::string_view counts = off.rest;  // the counts may follow the keyword on its line
  if (off.token() == "BINARY") throw off.error("binary OFF is not supported (write ASCII OFF or PLY)");
  off.rest = counts;
}

void read_vertices(OffLines& off, long long count, Mesh& mesh) {
  for (long long v = 0; v < count; ++v) {
    if (!off.next())
      throw InputError(off.path + ": truncated: vertex " + std::to_string(v + 1) + " is missing");
    float c[3];
    for (float& x : c) {
      const std::string_view t = off.token();
      if (t.empty()) throw off.error("a vertex needs three coordinates");
      x = parse_float(t, off.path, off.line);
      if (!std::isfinite(x))
        throw off.error("vertex " + std::to_string(v + 1) + " has a NaN or infinite coordinate");
    }
    mesh.vertices.emplace_back(c[0], c[1], c[2]);
  }
}

void read_faces(OffLines& off, long long count, Mesh& mesh) {
  const long long vertices = static_cast<long long>(mesh.vertices.size());
  std::vector<uint32_t> corners;
  for (long long f = 0; f < count; ++f) {
    if (!off.next())
      throw InputError(off.path + ": truncated: face " + std::to_string(f + 1) + " is missing");
    const long long n = off.integer("a corner count");
    if (n < 3) throw off.error("face " + std::to_string(f + 1) + " has fewer than three vertices");
    corners.clear();
    for (long long k = 0; k < n; ++k) {
      const long long i = off.integer("a vertex index");
      if (i >= vertices)
        throw off.error("face " + std::to_string(f + 1) + " refers to vertex " + std::to_string(i) +
                        ", but there are only " + std::to_string(vertices) + " vertices");
      corners.push_back(static_cast<uint32_t>(i));
    }
    for (size_t i = 2; i < corners.size(); ++i)
      mesh.triangles.emplace_back(corners[0], corners[i - 1], corners[i]);
  }
}

}  // namespace

Mesh read_off(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open file");
  OffLines off{in, path, 0, {}, {}};
  check_keyword(off);
  if (off.line_done() && !off.next()) throw InputError(path + ": truncated: no vertex and face counts");
  const long long vertices = off.integer("the vertex count");
  const long long faces = off.integer("the face count");
  if (vertices > 0xFFFFFFFFll) throw off.error("more vertices than 32-bit indices can address");
  Mesh mesh;
  read_vertices(off, vertices, mesh);
  read_faces(off, faces, mesh);
  if (off.next()) throw off.error("unexpected content after the last face (wrong counts?)");
  if (in.bad()) throw InputError(path + ": read error");
  return mesh;
}

}  // namespace ab
