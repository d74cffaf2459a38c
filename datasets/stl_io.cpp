#include "datasets/stl_io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <vector>

#include "datasets/io_util.h"

namespace ab {
namespace {

/// Binary STL: 80-byte header, u32 count, then per triangle 12 floats (normal, v0, v1, v2) and a
/// u16 attribute. Every triangle gets three new vertices (nothing is merged or dropped).
Mesh read_stl_binary(const std::string& path, std::istream& in, uint32_t count) {
  Mesh mesh;
  mesh.vertices.reserve(3ull * count);
  mesh.triangles.reserve(count);
  std::vector<char> chunk(50 * 4096);
  for (uint32_t done = 0; done < count;) {
    const uint32_t n = std::min<uint32_t>(count - done, 4096);
    read_exactly(in, chunk.data(), 50ull * n, path);
    for (uint32_t i = 0; i < n; ++i) {
      float f[12];
      std::memcpy(f, chunk.data() + 50ull * i, sizeof f);
      const uint32_t base = static_cast<uint32_t>(mesh.vertices.size());
      for (int k = 0; k < 3; ++k) mesh.vertices.emplace_back(f[3 + 3 * k], f[4 + 3 * k], f[5 + 3 * k]);
      mesh.triangles.emplace_back(base, base + 1, base + 2);
    }
    done += n;
  }
  return mesh;
}

/// ASCII STL: solid ... facet normal n n n / outer loop / vertex x y z (three) / endloop / endfacet
/// ... endsolid. Each facet gives one triangle with three new vertices.
Mesh read_stl_ascii(const std::string& path, std::istream& in) {
  Mesh mesh;
  std::string line_text, word;
  size_t line = 0, in_loop = 0;
  bool looping = false, ended = false;
  while (std::getline(in, line_text)) {
    ++line;
    std::istringstream words(line_text);
    if (!(words >> word)) continue;
    std::transform(word.begin(), word.end(), word.begin(), [](unsigned char c) { return std::tolower(c); });
    if (word == "outer") {
      looping = true;
      in_loop = 0;
    } else if (word == "vertex") {
      std::string x, y, z;
      if (!looping || !(words >> x >> y >> z))
        throw InputError(path + ":" + std::to_string(line) + ": bad vertex line");
      mesh.vertices.emplace_back(parse_float(x, path, line), parse_float(y, path, line),
                                 parse_float(z, path, line));
      ++in_loop;
    } else if (word == "endloop") {
      if (!looping || in_loop != 3)
        throw InputError(path + ":" + std::to_string(line) + ": a facet must have exactly three vertices");
      const uint32_t base = static_cast<uint32_t>(mesh.vertices.size() - 3);
      mesh.triangles.emplace_back(base, base + 1, base + 2);
      looping = false;
    } else if (word == "endsolid") {
      ended = true;
      break;
    }
  }
  if (looping || !ended) throw InputError(path + ": truncated ASCII STL (no endsolid)");
  return mesh;
}

}  // namespace

/// STL (ASCII or binary) read directly: OpenMesh's STL reader merges equal positions and drops
/// triangles whose merged vertices coincide, which would shift the ids of the triangles after them.
/// A file is binary when its size matches the count in its header (84 + 50 n bytes); otherwise it
/// is ASCII when it starts with "solid" and has no NUL byte in its first kilobyte.
Mesh read_stl(const std::string& path) {
  const uint64_t size = file_size(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open file");
  std::string head(static_cast<size_t>(std::min<uint64_t>(size, 1024)), '\0');
  read_exactly(in, head.data(), head.size(), path);
  uint32_t count = 0;
  if (size >= 84) std::memcpy(&count, head.data() + 80, 4);
  if (size >= 84 && size == 84 + 50ull * count) {
    in.seekg(84);
    return read_stl_binary(path, in, count);
  }
  const size_t start = head.find_first_not_of(" \t\r\n");
  const bool text = start != std::string::npos && head.compare(start, 5, "solid") == 0 &&
                    head.find('\0') == std::string::npos;
  if (text) {
    in.seekg(0);
    return read_stl_ascii(path, in);
  }
  if (size < 84) throw InputError(path + ": truncated binary STL (" + std::to_string(size) + " bytes)");
  throw InputError(path + ": binary STL declares " + std::to_string(count) + " triangles (" +
                   std::to_string(84 + 50ull * count) + " bytes) but the file has " + std::to_string(size) +
                   " bytes (truncated or malformed)");
}

/// Binary STL with the geometric normal of each triangle (zero for a degenerate one).
void write_stl(const Mesh& mesh, std::ostream& out) {
  char header[80] = {};
  std::snprintf(header, sizeof header, "accelbench binary STL");
  out.write(header, 80);
  std::string buffer;
  put_le32(buffer, static_cast<uint32_t>(mesh.size()));
  for (size_t i = 0; i < mesh.size(); ++i) {
    const Triangle t = mesh.triangle(i);
    const vec3 n = glm::cross(t.v1 - t.v0, t.v2 - t.v0);
    const float len = glm::length(n);
    const vec3 unit = len > 0.0f && std::isfinite(len) ? n / len : vec3(0.0f);
    for (const vec3& p : {unit, t.v0, t.v1, t.v2}) {
      put_le32(buffer, p.x);
      put_le32(buffer, p.y);
      put_le32(buffer, p.z);
    }
    buffer.push_back(0);
    buffer.push_back(0);
    if (buffer.size() >= (1 << 20)) {
      out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
      buffer.clear();
    }
  }
  out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
}

}  // namespace ab
