#include "datasets/mesh_checks.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <vector>

#include "datasets/io_util.h"

namespace ab {
namespace {

/// A PLY scalar type: its bytes in a binary body and how to read it as a list count.
struct PlyType {
  int bytes;
  bool is_signed;
  bool is_float;
};

const std::map<std::string, PlyType> kPlyTypes = {
    {"char", {1, true, false}},   {"uchar", {1, false, false}},  {"int8", {1, true, false}},
    {"uint8", {1, false, false}}, {"short", {2, true, false}},   {"ushort", {2, false, false}},
    {"int16", {2, true, false}},  {"uint16", {2, false, false}}, {"int", {4, true, false}},
    {"uint", {4, false, false}},  {"int32", {4, true, false}},   {"uint32", {4, false, false}},
    {"float", {4, true, true}},   {"float32", {4, true, true}},  {"double", {8, true, true}},
    {"float64", {8, true, true}}};

/// One property's layout in a binary body: a scalar of `bytes`, or a list of `bytes`-sized entries
/// after a count of type `count`.
struct PlyLayout {
  bool list = false;
  int bytes = 0;
  PlyType count{0, false, false};
  bool integer = false;  ///< the scalar (or the list's entries) has an integer type
};

/// What the header check has seen of one element.
struct PlyElement {
  std::string name;
  long long count = 0;
  std::vector<std::pair<std::string, bool>> properties;  ///< (name, is a list) in file order
  std::vector<PlyLayout> layout;                         ///< the same properties' binary layout
  std::set<std::string> scalars, lists;
  uint64_t min_bytes = 0;  ///< of one instance in a binary body (each list counted as empty)
};

std::string ply_line_error(const std::string& path, size_t line, const std::string& what) {
  return path + ":" + std::to_string(line) + ": " + what;
}

/// OpenMesh reads the header token by token and loops forever once its stream fails, which a token
/// left over on a line (read as the next keyword or count) makes it do: every line must end where its
/// keyword's fields end.
void expect_line_end(std::istringstream& words, const std::string& path, size_t line) {
  std::string extra;
  if (words >> extra)
    throw InputError(ply_line_error(path, line, "unexpected '" + extra + "' at the end of the header line"));
}

/// Parses the count of an element line: a whole non-negative number below 2^31 (what OpenMesh reads).
long long ply_element_count(std::istringstream& words, const std::string& path, size_t line) {
  std::string token;
  words >> token;
  long long count = -1;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), count);
  if (token.empty() || ec != std::errc() || end != token.data() + token.size() || count < 0 ||
      count > 0x7FFFFFFF)
    throw InputError(ply_line_error(
        path, line, "malformed element line (the count '" + token + "' is not a number in [0, 2^31))"));
  return count;
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
    if (kPlyTypes.at(count_type).is_float)
      throw InputError(
          ply_line_error(path, line, "a list's count type must be an integer type, not " + count_type));
    element->lists.insert(name);
    element->properties.emplace_back(name, true);
    element->layout.push_back(
        {true, kPlyTypes.at(index_type).bytes, kPlyTypes.at(count_type), !kPlyTypes.at(index_type).is_float});
    element->min_bytes += uint64_t(kPlyTypes.at(count_type).bytes);
  } else {
    if (!(words >> name) || !kPlyTypes.count(type))
      throw InputError(ply_line_error(path, line, "malformed property (unknown type '" + type + "')"));
    element->scalars.insert(name);
    element->properties.emplace_back(name, false);
    element->layout.push_back({false, kPlyTypes.at(type).bytes, {}, !kPlyTypes.at(type).is_float});
    element->min_bytes += uint64_t(kPlyTypes.at(type).bytes);
  }
  expect_line_end(words, path, line);
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
  const auto number = [&](std::string_view token, bool integer) {
    return integer ? double(ply_integer(token, path, line)) : double(parse_float(token, path, line));
  };
  for (size_t p = 0; p < e.properties.size(); ++p) {
    const auto& [name, list] = e.properties[p];
    const bool integer = e.layout[p].integer;
    if (list && e.name == "face" && (name == "vertex_indices" || name == "vertex_index")) {
      check_ply_face_list(rest, vertices, index + 1, path, line);
    } else if (list) {
      const long long n = ply_integer(next_token(rest), path, line);
      if (n < 0) throw InputError(ply_line_error(path, line, "negative list length " + std::to_string(n)));
      for (long long k = 0; k < n; ++k) number(next_token(rest), integer);
    } else {
      const std::string_view token = next_token(rest);
      if (token.empty()) throw InputError(ply_line_error(path, line, "too few values for element " + e.name));
      const double f = number(token, integer);
      if (e.name == "vertex" && (name == "x" || name == "y" || name == "z") && !std::isfinite(float(f)))
        throw InputError(ply_line_error(
            path, line, "vertex " + std::to_string(index + 1) + " has a NaN or infinite coordinate"));
    }
  }
  // OpenMesh reads the body token by token: a value too many would shift every value after it.
  if (!next_token(rest).empty())
    throw InputError(ply_line_error(path, line, "too many values for element " + e.name));
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

/// Checks the format line ("format KIND VERSION") and returns KIND. OpenMesh's header reader loops
/// forever once its stream fails, which a version that is not a plain number (1e999, nan, 1.0x) does.
std::string check_ply_format(std::istringstream& words, const std::string& path, size_t line) {
  std::string kind, version;
  words >> kind >> version;
  if (kind != "ascii" && kind != "binary_little_endian" && kind != "binary_big_endian")
    throw InputError(ply_line_error(path, line, "unknown PLY format '" + kind + "'"));
  const size_t digits = version.find_first_not_of("0123456789");
  const bool number = digits != 0 && !version.empty() &&
                      (digits == std::string::npos ||
                       (version[digits] == '.' && digits + 1 < version.size() &&
                        version.find_first_not_of("0123456789", digits + 1) == std::string::npos));
  if (!number || version.size() > 16)
    throw InputError(ply_line_error(
        path, line, "the format line needs a version number such as 1.0, got '" + version + "'"));
  expect_line_end(words, path, line);
  return kind;
}

/// Buffered reads of a binary PLY body, counting the bytes left in the file.
class PlyBody {
 public:
  PlyBody(std::istream& in, uint64_t left) : in_(in), left_(left) {}
  /// Skips n bytes; false when the file ends first.
  bool skip(uint64_t n) {
    if (n > left_) return false;
    left_ -= n;
    const uint64_t buffered = std::min<uint64_t>(n, size_ - at_);
    at_ += buffered;
    if (buffered < n) {
      in_.seekg(static_cast<std::streamoff>(n - buffered), std::ios::cur);
      at_ = size_ = 0;
    }
    return true;
  }
  /// Reads n (at most 8) bytes; false when the file ends first.
  bool read(unsigned char* out, int n) {
    if (uint64_t(n) > left_) return false;
    for (int i = 0; i < n; ++i) {
      if (at_ == size_) {
        in_.read(buffer_, sizeof buffer_);
        size_ = static_cast<size_t>(in_.gcount());
        at_ = 0;
        if (size_ == 0) return false;
      }
      out[i] = static_cast<unsigned char>(buffer_[at_++]);
    }
    left_ -= uint64_t(n);
    return true;
  }
  /// Bytes left in the file.
  uint64_t left() const { return left_; }

 private:
  std::istream& in_;
  uint64_t left_;
  char buffer_[1 << 16];
  size_t at_ = 0, size_ = 0;
};

/// Reads one list count of type t (in the body's byte order); -1 at the end of the file.
long long ply_list_count(PlyBody& body, const PlyType& t, bool big_endian) {
  unsigned char b[8] = {};
  if (!body.read(b, t.bytes)) return -1;
  uint64_t bits = 0;
  for (int i = 0; i < t.bytes; ++i) bits |= uint64_t(b[big_endian ? t.bytes - 1 - i : i]) << (8 * i);
  if (t.is_signed && (bits >> (8 * t.bytes - 1)) & 1) return -2;  // negative
  return static_cast<long long>(bits);
}

/// OpenMesh's binary PLY reader reads as many elements and list entries as the file declares, past the
/// end of the file (minutes for a large count, gigabytes for a large list): the body is walked first,
/// elements of scalars at once, elements with lists one list count at a time.
void check_ply_binary_body(std::istream& in, const std::vector<PlyElement>& elements, bool big_endian,
                           const std::string& path) {
  const std::streamoff at = in.tellg();
  const uint64_t size = file_size(path);
  PlyBody body(in, at < 0 ? 0 : size - std::min<uint64_t>(uint64_t(at), size));
  const auto truncated = [&](const PlyElement& e, long long k) {
    return InputError(path + ": unexpected end of file in " + e.name + " " + std::to_string(k + 1) + " of " +
                      std::to_string(e.count) + " (truncated, or the header declares too much)");
  };
  for (const PlyElement& e : elements) {
    if (e.lists.empty()) {
      if (uint64_t(e.count) > body.left() / std::max<uint64_t>(e.min_bytes, 1))
        throw truncated(e, static_cast<long long>(body.left() / std::max<uint64_t>(e.min_bytes, 1)));
      body.skip(uint64_t(e.count) * e.min_bytes);
      continue;
    }
    for (long long k = 0; k < e.count; ++k)
      for (const PlyLayout& p : e.layout) {
        const long long n = p.list ? ply_list_count(body, p.count, big_endian) : 1;
        if (n == -2)
          throw InputError(path + ": " + e.name + " " + std::to_string(k + 1) +
                           " has a negative list length");
        if (n < 0 || !body.skip(uint64_t(n) * uint64_t(p.bytes))) throw truncated(e, k);
      }
  }
}

}  // namespace

void check_ply(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string text, keyword;
  if (!std::getline(in, text) || (text != "ply" && text != "ply\r"))
    throw InputError(path + ": not a PLY file (no 'ply' magic)");
  std::vector<PlyElement> elements;
  bool format = false, ascii = false, big_endian = false;
  for (size_t line = 2; line < 100000 && std::getline(in, text); ++line) {
    if (!text.empty() && text.back() == '\r') text.pop_back();
    std::istringstream words(text);
    if (!(words >> keyword) || keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "end_header") {
      expect_line_end(words, path, line);
      if (!format) throw InputError(path + ": the PLY header has no format line");
      check_ply_elements(elements, path);
      if (ascii)
        check_ply_ascii_body(in, elements, path, line);
      else
        check_ply_binary_body(in, elements, big_endian, path);
      return;
    }
    if (keyword == "format") {
      const std::string kind = check_ply_format(words, path, line);
      ascii = kind == "ascii";
      big_endian = kind == "binary_big_endian";
      format = true;
    } else if (keyword == "element") {
      PlyElement e;
      if (!(words >> e.name))
        throw InputError(ply_line_error(path, line, "malformed element line (no name)"));
      e.count = ply_element_count(words, path, line);
      expect_line_end(words, path, line);
      elements.push_back(e);
    } else if (keyword == "property") {
      check_ply_property(words, elements.empty() ? nullptr : &elements.back(), path, line);
    } else {
      throw InputError(ply_line_error(path, line, "unexpected '" + keyword + "' in the PLY header"));
    }
  }
  throw InputError(path + ": truncated PLY header (no end_header)");
}

}  // namespace ab
