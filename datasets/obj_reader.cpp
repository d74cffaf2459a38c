#include "datasets/obj_reader.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <string_view>
#include <vector>

#include "datasets/io_util.h"

namespace ab {
namespace {

/// Where we are, for error messages.
struct Where {
  const std::string& path;
  size_t line;
  std::string at() const { return path + ":" + std::to_string(line) + ": "; }
};

void read_vertex(std::string_view rest, Mesh& mesh, const Where& w) {
  float c[3];
  for (float& x : c) {
    const std::string_view token = next_token(rest);
    if (token.empty()) throw InputError(w.at() + "a vertex needs three coordinates");
    x = parse_float(token, w.path, w.line);
  }
  if (!std::isfinite(c[0]) || !std::isfinite(c[1]) || !std::isfinite(c[2]))
    throw InputError(w.at() + "vertex " + std::to_string(mesh.vertices.size() + 1) +
                     " has a NaN or infinite coordinate");
  mesh.vertices.emplace_back(c[0], c[1], c[2]);
}

/// The vertex index of one face corner (i, i/t, i//n, i/t/n), 0-based; negative indices count back
/// from the last vertex read so far.
uint32_t corner_index(std::string_view token, size_t vertices, size_t face, const Where& w) {
  const std::string_view number = token.substr(0, token.find('/'));
  long long i = 0;
  const auto [end, ec] = std::from_chars(number.data(), number.data() + number.size(), i);
  if (number.empty() || ec != std::errc() || end != number.data() + number.size())
    throw InputError(w.at() + "'" + std::string(token) + "' is not a vertex index");
  const long long resolved = i < 0 ? static_cast<long long>(vertices) + i : i - 1;
  if (i == 0 || resolved < 0 || resolved >= static_cast<long long>(vertices) || resolved > 0xFFFFFFFEll)
    throw InputError(w.at() + "face " + std::to_string(face) + " refers to vertex " + std::to_string(i) +
                     ", but there are only " + std::to_string(vertices) + " vertices");
  return static_cast<uint32_t>(resolved);
}

void read_face(std::string_view rest, Mesh& mesh, size_t face, std::vector<uint32_t>& corners,
               const Where& w) {
  corners.clear();
  for (std::string_view token = next_token(rest); !token.empty(); token = next_token(rest))
    corners.push_back(corner_index(token, mesh.vertices.size(), face, w));
  if (corners.size() < 3)
    throw InputError(w.at() + "face " + std::to_string(face) + " has fewer than three vertices");
  for (size_t i = 2; i < corners.size(); ++i)
    mesh.triangles.emplace_back(corners[0], corners[i - 1], corners[i]);
}

}  // namespace

Mesh read_obj(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open file");
  Mesh mesh;
  std::string text;
  std::vector<uint32_t> corners;
  size_t faces = 0;
  for (Where w{path, 1}; std::getline(in, text); ++w.line) {
    std::string_view rest(text);
    rest = rest.substr(0, rest.find('#'));
    const std::string_view keyword = next_token(rest);
    if (keyword == "v")
      read_vertex(rest, mesh, w);
    else if (keyword == "f")
      read_face(rest, mesh, ++faces, corners, w);
  }
  if (in.bad()) throw InputError(path + ": read error");
  return mesh;
}

}  // namespace ab
