#include "datasets/mesh_checks.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <vector>

#include "datasets/io_util.h"

namespace ab {
namespace {

const std::set<std::string> kPlyTypes = {"char",  "uchar",  "short",   "ushort", "int",   "uint",
                                         "float", "double", "int8",    "uint8",  "int16", "uint16",
                                         "int32", "uint32", "float32", "float64"};

/// What the header check has seen of one element.
struct PlyElement {
  std::string name;
  long long count = 0;
  std::vector<std::pair<std::string, bool>> properties;  ///< (name, is a list) in file order
  std::set<std::string> scalars, lists;
};

std::string ply_line_error(const std::string& path, size_t line, const std::string& what) {
  return path + ":" + std::to_string(line) + ": " + what;
}

/// Checks one property line ("property TYPE NAME" or "property list COUNT_TYPE INDEX_TYPE NAME").
void check_ply_property(std::istringstream& words, PlyElement* element, const std::string& path,
                        size_t line) {
  std::string type, count_type, index_type, name;
  if (!element) throw InputError(ply_line_error(path, line, "property before any element"));
  words >> type;
  if (type == "list") {
    if (!(words >> count_type >> index_type >> name) || !kPlyTypes.count(count_type) ||
        !kPlyTypes.count(index_type))
      throw InputError(ply_line_error(path, line, "malformed list property"));
    element->lists.insert(name);
    element->properties.emplace_back(name, true);
  } else {
    if (!(words >> name) || !kPlyTypes.count(type))
      throw InputError(ply_line_error(path, line, "malformed property (unknown type '" + type + "')"));
    element->scalars.insert(name);
    element->properties.emplace_back(name, false);
  }
}

/// Checks what the elements declare: a vertex element with x, y, z and a list on the face element.
void check_ply_elements(const std::vector<PlyElement>& elements, const std::string& path) {
  bool vertex = false;
  for (const PlyElement& e : elements) {
    if (e.name == "vertex") {
      vertex = true;
      if (!e.scalars.count("x") || !e.scalars.count("y") || !e.scalars.count("z"))
        throw InputError(path + ": the vertex element lacks an x, y or z property");
    }
    if (e.name == "face" && e.lists.empty())
      throw InputError(path + ": the face element has no list of vertex indices");
  }
  if (!vertex) throw InputError(path + ": no vertex element in the PLY header");
}

/// Parses an integer token of an ASCII PLY body, or throws naming the line.
long long ply_integer(std::string_view token, const std::string& path, size_t line) {
  long long value = 0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (token.empty() || ec != std::errc() || end != token.data() + token.size())
    throw InputError(ply_line_error(path, line, "'" + std::string(token) + "' is not an integer"));
  return value;
}

/// Checks one face list: at least three corners, each an index of an existing vertex.
void check_ply_face_list(std::string_view& rest, long long vertices, long long face, const std::string& path,
                         size_t line) {
  const long long corners = ply_integer(next_token(rest), path, line);
  if (corners < 3)
    throw InputError(
        ply_line_error(path, line, "face " + std::to_string(face) + " has fewer than three vertices"));
  for (long long k = 0; k < corners; ++k) {
    const long long i = ply_integer(next_token(rest), path, line);
    if (i < 0 || i >= vertices)
      throw InputError(ply_line_error(path, line,
                                      "face " + std::to_string(face) + " refers to vertex " +
                                          std::to_string(i) + ", but there are only " +
                                          std::to_string(vertices) + " vertices"));
  }
}

/// Checks one element line of an ASCII PLY body against the element's properties.
void check_ply_ascii_line(std::string_view rest, const PlyElement& e, long long index, long long vertices,
                          const std::string& path, size_t line) {
  for (const auto& [name, list] : e.properties) {
    if (list && e.name == "face" && (name == "vertex_indices" || name == "vertex_index")) {
      check_ply_face_list(rest, vertices, index + 1, path, line);
    } else if (list) {
      const long long n = ply_integer(next_token(rest), path, line);
      for (long long k = 0; k < n; ++k) parse_float(next_token(rest), path, line);
    } else {
      const std::string_view token = next_token(rest);
      if (token.empty()) throw InputError(ply_line_error(path, line, "too few values for element " + e.name));
      const float f = parse_float(token, path, line);
      if (e.name == "vertex" && (name == "x" || name == "y" || name == "z") && !std::isfinite(f))
        throw InputError(ply_line_error(
            path, line, "vertex " + std::to_string(index + 1) + " has a NaN or infinite coordinate"));
    }
  }
}

/// OpenMesh's ASCII PLY reader turns an unparsable number into silent garbage, so the body is
/// checked first: one line per element instance, numbers that parse, finite x/y/z, faces of at
/// least three in-range indices, and no missing lines.
void check_ply_ascii_body(std::istream& in, const std::vector<PlyElement>& elements, const std::string& path,
                          size_t line) {
  long long vertices = 0;
  std::string text;
  for (const PlyElement& e : elements) {
    if (e.name == "vertex") vertices = e.count;
    for (long long k = 0; k < e.count;) {
      if (!std::getline(in, text))
        throw InputError(path + ": truncated: " + e.name + " " + std::to_string(k + 1) + " of " +
                         std::to_string(e.count) + " is missing");
      ++line;
      if (text.find_first_not_of(" \t\r") == std::string::npos) continue;
      check_ply_ascii_line(text, e, k++, vertices, path, line);
    }
  }
}

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
  /// The next token of the current line ("" when there is none).
  std::string_view token() { return next_token(rest); }
  /// The next token as a non-negative integer, or throws.
  long long integer(const char* what) {
    const std::string_view t = token();
    long long value = -1;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
    if (t.empty() || ec != std::errc() || end != t.data() + t.size() || value < 0)
      throw error(std::string("expected ") + what);
    return value;
  }
  /// An error naming the file and current line.
  InputError error(const std::string& what) const {
    return InputError(path + ":" + std::to_string(line) + ": " + what);
  }
};

void check_off_vertices(OffLines& off, long long count) {
  for (long long v = 0; v < count; ++v) {
    if (!off.next())
      throw InputError(off.path + ": truncated: vertex " + std::to_string(v + 1) + " is missing");
    for (int k = 0; k < 3; ++k) {
      const std::string_view t = off.token();
      if (t.empty()) throw off.error("a vertex needs three coordinates");
      if (!std::isfinite(parse_float(t, off.path, off.line)))
        throw off.error("vertex " + std::to_string(v + 1) + " has a NaN or infinite coordinate");
    }
  }
}

void check_off_faces(OffLines& off, long long count, long long vertices) {
  for (long long f = 0; f < count; ++f) {
    if (!off.next())
      throw InputError(off.path + ": truncated: face " + std::to_string(f + 1) + " is missing");
    const long long corners = off.integer("a corner count");
    if (corners < 3) throw off.error("face " + std::to_string(f + 1) + " has fewer than three vertices");
    for (long long k = 0; k < corners; ++k) {
      const long long i = off.integer("a vertex index");
      if (i >= vertices)
        throw off.error("face " + std::to_string(f + 1) + " refers to vertex " + std::to_string(i) +
                        ", but there are only " + std::to_string(vertices) + " vertices");
    }
  }
}

}  // namespace

void check_ply(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string text, keyword;
  if (!std::getline(in, text) || text.substr(0, 3) != "ply")
    throw InputError(path + ": not a PLY file (no 'ply' magic)");
  std::vector<PlyElement> elements;
  bool format = false, ascii = false;
  for (size_t line = 2; line < 100000 && std::getline(in, text); ++line) {
    if (!text.empty() && text.back() == '\r') text.pop_back();
    std::istringstream words(text);
    if (!(words >> keyword) || keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "end_header") {
      if (!format) throw InputError(path + ": the PLY header has no format line");
      check_ply_elements(elements, path);
      if (ascii) check_ply_ascii_body(in, elements, path, line);
      return;
    }
    if (keyword == "format") {
      std::string kind;
      words >> kind;
      if (kind != "ascii" && kind != "binary_little_endian" && kind != "binary_big_endian")
        throw InputError(ply_line_error(path, line, "unknown PLY format '" + kind + "'"));
      format = true;
      ascii = kind == "ascii";
    } else if (keyword == "element") {
      PlyElement e;
      e.count = -1;
      if (!(words >> e.name >> e.count) || e.count < 0)
        throw InputError(ply_line_error(path, line, "malformed element line"));
      elements.push_back(e);
    } else if (keyword == "property") {
      check_ply_property(words, elements.empty() ? nullptr : &elements.back(), path, line);
    } else {
      throw InputError(ply_line_error(path, line, "unexpected '" + keyword + "' in the PLY header"));
    }
  }
  throw InputError(path + ": truncated PLY header (no end_header)");
}

void check_ascii_off(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  OffLines off{in, path, 0, {}, {}};
  const std::string_view keyword = off.next() ? off.token() : std::string_view{};
  if (keyword.find("OFF") == std::string_view::npos)
    throw InputError(path + ": not an OFF file (no OFF keyword)");
  if (keyword != "OFF") return;  // COFF, NOFF, 4OFF, ... : left to OpenMesh
  if (off.rest.find_first_not_of(" \t\r") == std::string_view::npos && !off.next())
    throw InputError(path + ": truncated: no vertex and face counts");
  if (off.rest.find("BINARY") != std::string_view::npos) return;  // binary OFF: left to OpenMesh
  const long long vertices = off.integer("the vertex count");
  const long long faces = off.integer("the face count");
  check_off_vertices(off, vertices);
  check_off_faces(off, faces, vertices);
}

}  // namespace ab
