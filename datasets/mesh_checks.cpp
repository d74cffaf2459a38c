#include "datasets/mesh_checks.h"

#include "datasets/io_util.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <vector>

namespace ab {
namespace {

const std::set<std::string> kPlyTypes = {"char",  "uchar", "short", "ushort", "int",    "uint",    "float",   "double",
                                         "int8",  "uint8", "int16", "uint16", "int32",  "uint32",  "float32", "float64"};

/// What the header check has seen of one element.
struct PlyElement {
  std::string name;
  std::set<std::string> scalars, lists;
};

std::string ply_line_error(const std::string& path, size_t line, const std::string& what) {
  return path + ":" + std::to_string(line) + ": " + what;
}

/// Checks one property line ("property TYPE NAME" or "property list COUNT_TYPE INDEX_TYPE NAME").
void check_ply_property(std::istringstream& words, PlyElement* element, const std::string& path, size_t line) {
  std::string type, count_type, index_type, name;
  if (!element) throw InputError(ply_line_error(path, line, "property before any element"));
  words >> type;
  if (type == "list") {
    if (!(words >> count_type >> index_type >> name) || !kPlyTypes.count(count_type) || !kPlyTypes.count(index_type))
      throw InputError(ply_line_error(path, line, "malformed list property"));
    element->lists.insert(name);
  } else {
    if (!(words >> name) || !kPlyTypes.count(type))
      throw InputError(ply_line_error(path, line, "malformed property (unknown type '" + type + "')"));
    element->scalars.insert(name);
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
    if (e.name == "face" && e.lists.empty()) throw InputError(path + ": the face element has no list of vertex indices");
  }
  if (!vertex) throw InputError(path + ": no vertex element in the PLY header");
}

/// Reads the next non-empty, non-comment line of an OFF file into `words`; false at the end.
bool next_off_line(std::istream& in, std::istringstream& words, size_t& line) {
  std::string text;
  while (std::getline(in, text)) {
    ++line;
    text = text.substr(0, text.find('#'));
    if (text.find_first_not_of(" \t\r") == std::string::npos) continue;
    words.clear();
    words.str(text);
    return true;
  }
  return false;
}

/// Reads a non-negative integer token, or throws.
long long off_integer(std::istringstream& words, const std::string& path, size_t line, const char* what) {
  std::string token;
  long long value = -1;
  if (words >> token) std::from_chars(token.data(), token.data() + token.size(), value);
  if (value < 0) throw InputError(path + ":" + std::to_string(line) + ": expected " + what);
  return value;
}

void check_off_vertices(std::istream& in, long long count, const std::string& path, size_t& line) {
  std::istringstream words;
  std::string token;
  for (long long v = 0; v < count; ++v) {
    if (!next_off_line(in, words, line)) throw InputError(path + ": truncated: vertex " + std::to_string(v + 1) + " is missing");
    for (int k = 0; k < 3; ++k) {
      if (!(words >> token)) throw InputError(path + ":" + std::to_string(line) + ": a vertex needs three coordinates");
      if (!std::isfinite(parse_float(token, path, line)))
        throw InputError(path + ":" + std::to_string(line) + ": vertex " + std::to_string(v + 1) +
                         " has a NaN or infinite coordinate");
    }
  }
}

void check_off_faces(std::istream& in, long long count, long long vertices, const std::string& path, size_t& line) {
  std::istringstream words;
  for (long long f = 0; f < count; ++f) {
    if (!next_off_line(in, words, line)) throw InputError(path + ": truncated: face " + std::to_string(f + 1) + " is missing");
    const long long corners = off_integer(words, path, line, "a corner count");
    if (corners < 3) throw InputError(path + ":" + std::to_string(line) + ": face has fewer than three vertices");
    for (long long k = 0; k < corners; ++k) {
      const long long i = off_integer(words, path, line, "a vertex index");
      if (i >= vertices)
        throw InputError(path + ":" + std::to_string(line) + ": face " + std::to_string(f + 1) + " refers to vertex " +
                         std::to_string(i) + ", but there are only " + std::to_string(vertices) + " vertices");
    }
  }
}

}  // namespace

void check_ply_header(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string text, keyword;
  if (!std::getline(in, text) || text.substr(0, 3) != "ply") throw InputError(path + ": not a PLY file (no 'ply' magic)");
  std::vector<PlyElement> elements;
  bool format = false;
  for (size_t line = 2; line < 100000 && std::getline(in, text); ++line) {
    if (!text.empty() && text.back() == '\r') text.pop_back();
    std::istringstream words(text);
    if (!(words >> keyword) || keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "end_header") {
      if (!format) throw InputError(path + ": the PLY header has no format line");
      check_ply_elements(elements, path);
      return;
    }
    if (keyword == "format") {
      std::string kind;
      words >> kind;
      if (kind != "ascii" && kind != "binary_little_endian" && kind != "binary_big_endian")
        throw InputError(ply_line_error(path, line, "unknown PLY format '" + kind + "'"));
      format = true;
    } else if (keyword == "element") {
      PlyElement e;
      long long count = -1;
      if (!(words >> e.name >> count) || count < 0) throw InputError(ply_line_error(path, line, "malformed element line"));
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
  std::istringstream words;
  size_t line = 0;
  std::string keyword;
  if (!next_off_line(in, words, line) || !(words >> keyword) || keyword.find("OFF") == std::string::npos)
    throw InputError(path + ": not an OFF file (no OFF keyword)");
  if (keyword != "OFF") return;  // COFF, NOFF, 4OFF, ... : left to OpenMesh
  std::vector<std::string> counts;
  for (std::string t; words >> t;) counts.push_back(t);
  if (!counts.empty() && counts[0] == "BINARY") return;
  if (counts.empty()) {
    if (!next_off_line(in, words, line)) throw InputError(path + ": truncated: no vertex and face counts");
    for (std::string t; words >> t;) counts.push_back(t);
  }
  std::istringstream count_words(counts.size() >= 2 ? counts[0] + " " + counts[1] : std::string());
  const long long vertices = off_integer(count_words, path, line, "the vertex count");
  const long long faces = off_integer(count_words, path, line, "the face count");
  check_off_vertices(in, vertices, path, line);
  check_off_faces(in, faces, vertices, path, line);
}

}  // namespace ab
