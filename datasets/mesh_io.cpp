#include "datasets/mesh_io.h"

#include "accel/error.h"
#include "datasets/atomic_file.h"
#include "datasets/mesh_importer.h"

#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <algorithm>
#include <bit>
#include <cstring>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>

namespace ab {
namespace {

/// Lower-case extension without the dot ("" when there is none).
std::string extension_of(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  if (!ext.empty()) ext.erase(0, 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

/// First line of OpenMesh's diagnostics (empty when there were none).
std::string first_line(const std::string& text) {
  std::string line;
  std::istringstream in(text);
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) return line;
  return "";
}

/// Runs OpenMesh's reader for the file's format with our importer. OpenMesh's readers keep state in
/// singletons and report through the global omerr stream, so reads are serialized and the stream is
/// captured (to name the problem in our own error) instead of printed.
void read_through_openmesh(const std::string& path, MeshImporter& importer) {
  static std::mutex mutex;
  std::lock_guard<std::mutex> lock(mutex);
  std::ostringstream messages;
  ::omerr().disconnect(std::cerr);
  ::omerr().connect(messages);
  ::omlog().disable();
  ::omout().disable();
  bool ok = false;
  try {
    OpenMesh::IO::Options options;
    ok = OpenMesh::IO::IOManager().read(path, importer, options);
  } catch (...) {
    ::omerr().disconnect(messages);
    ::omerr().connect(std::cerr);
    throw;
  }
  ::omerr().flush();
  ::omerr().disconnect(messages);
  ::omerr().connect(std::cerr);
  importer.check(path);
  if (!ok) {
    const std::string why = first_line(messages.str());
    throw InputError(path + ": cannot read mesh" + (why.empty() ? std::string() : " (" + why + ")"));
  }
}

/// Rejects NaN and infinite coordinates.
void check_finite(const Mesh& mesh, const std::string& path) {
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const vec3& p = mesh.vertices[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw InputError(path + ": vertex " + std::to_string(i + 1) + " has a NaN or infinite coordinate");
  }
}

/// Formats a float with 9 significant digits (enough for an exact round trip).
void put_float(std::ostream& out, float f) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.9g", static_cast<double>(f));
  out << buffer;
}

void write_obj(const Mesh& mesh, std::ostream& out) {
  out << "# accelbench mesh: " << mesh.vertices.size() << " vertices, " << mesh.size() << " triangles\n";
  for (const vec3& p : mesh.vertices) {
    out << "v ";
    put_float(out, p.x);
    out << ' ';
    put_float(out, p.y);
    out << ' ';
    put_float(out, p.z);
    out << '\n';
  }
  for (const glm::uvec3& t : mesh.triangles) out << "f " << t.x + 1 << ' ' << t.y + 1 << ' ' << t.z + 1 << '\n';
}

void write_off(const Mesh& mesh, std::ostream& out) {
  out << "OFF\n" << mesh.vertices.size() << ' ' << mesh.size() << " 0\n";
  for (const vec3& p : mesh.vertices) {
    put_float(out, p.x);
    out << ' ';
    put_float(out, p.y);
    out << ' ';
    put_float(out, p.z);
    out << '\n';
  }
  for (const glm::uvec3& t : mesh.triangles) out << "3 " << t.x << ' ' << t.y << ' ' << t.z << '\n';
}

/// Appends a little-endian 32-bit value.
template <class T>
void put_le32(std::string& buffer, T value) {
  static_assert(sizeof(T) == 4);
  uint32_t bits;
  std::memcpy(&bits, &value, 4);
  for (int i = 0; i < 4; ++i) buffer.push_back(static_cast<char>((bits >> (8 * i)) & 0xFF));
}

/// Binary little-endian PLY: float vertices, faces as uchar count + uint indices.
void write_ply(const Mesh& mesh, std::ostream& out) {
  out << "ply\nformat binary_little_endian 1.0\ncomment accelbench mesh\nelement vertex " << mesh.vertices.size()
      << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << mesh.size()
      << "\nproperty list uchar uint vertex_indices\nend_header\n";
  std::string buffer;
  buffer.reserve(1 << 20);
  auto flush = [&](bool force) {
    if (force || buffer.size() >= (1 << 20) - 64) {
      out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
      buffer.clear();
    }
  };
  for (const vec3& p : mesh.vertices) {
    put_le32(buffer, p.x);
    put_le32(buffer, p.y);
    put_le32(buffer, p.z);
    flush(false);
  }
  for (const glm::uvec3& t : mesh.triangles) {
    buffer.push_back(3);
    put_le32(buffer, t.x);
    put_le32(buffer, t.y);
    put_le32(buffer, t.z);
    flush(false);
  }
  flush(true);
}


static_assert(std::endian::native == std::endian::little, "binary mesh I/O assumes a little-endian host");

/// Size of a file in bytes.
uint64_t file_size(const std::string& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(path + ": cannot read file size: " + ec.message());
  return size;
}

/// Reads exactly n bytes or throws naming the file.
void read_exactly(std::istream& in, char* data, size_t n, const std::string& path) {
  in.read(data, static_cast<std::streamsize>(n));
  if (static_cast<size_t>(in.gcount()) != n) throw InputError(path + ": unexpected end of file");
}

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

/// Parses one float token of an ASCII file, or throws naming the file and line.
float parse_float(const std::string& token, const std::string& path, size_t line) {
  char* end = nullptr;
  const float f = std::strtof(token.c_str(), &end);
  if (token.empty() || *end != '\0')
    throw InputError(path + ":" + std::to_string(line) + ": '" + token + "' is not a number");
  return f;
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
      if (!looping || !(words >> x >> y >> z)) throw InputError(path + ":" + std::to_string(line) + ": bad vertex line");
      mesh.vertices.emplace_back(parse_float(x, path, line), parse_float(y, path, line), parse_float(z, path, line));
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

/// Element counts a PLY header or an ASCII OFF header declares (-1 where unknown).
struct DeclaredCounts {
  long long vertices = -1;
  long long faces = -1;
};

DeclaredCounts declared_ply(std::istream& in) {
  DeclaredCounts d;
  std::string line;
  for (int n = 0; n < 10000 && std::getline(in, line); ++n) {
    std::istringstream words(line);
    std::string a, b;
    long long count = -1;
    words >> a;
    if (a == "end_header") break;
    if (a == "element" && (words >> b >> count)) {
      if (b == "vertex") d.vertices = count;
      if (b == "face") d.faces = count;
    }
  }
  return d;
}

DeclaredCounts declared_off(std::istream& in) {
  DeclaredCounts d;
  std::string word;
  if (!(in >> word) || word != "OFF") return d;  // variants (COFF, NOFF, binary ...) are not checked
  std::string line;
  while (in >> word) {
    if (word[0] == '#') {
      std::getline(in, line);
      continue;
    }
    d.vertices = std::strtoll(word.c_str(), nullptr, 10);
    if (!(in >> d.faces)) d.faces = -1;
    break;
  }
  return d;
}

/// OpenMesh's PLY and OFF readers stop quietly at the end of a truncated file; comparing what
/// arrived with the counts the header declares turns that into an error.
void check_declared_counts(const std::string& path, const std::string& ext, const MeshImporter& importer,
                           const Mesh& mesh) {
  if (ext != "ply" && ext != "off") return;
  std::ifstream in(path, std::ios::binary);
  const DeclaredCounts d = ext == "ply" ? declared_ply(in) : declared_off(in);
  if (d.vertices >= 0 && static_cast<size_t>(d.vertices) != mesh.vertices.size())
    throw InputError(path + ": the header declares " + std::to_string(d.vertices) + " vertices but " +
                     std::to_string(mesh.vertices.size()) + " could be read (truncated or malformed)");
  if (d.faces >= 0 && static_cast<size_t>(d.faces) != importer.faces())
    throw InputError(path + ": the header declares " + std::to_string(d.faces) + " faces but " +
                     std::to_string(importer.faces()) + " could be read (truncated or malformed)");
}
}  // namespace

Mesh read_mesh(const std::string& path) {
  const std::string ext = extension_of(path);
  if (ext != "obj" && ext != "ply" && ext != "off" && ext != "stl")
    throw InputError(path + ": unknown mesh format '" + ext + "' (expected .obj, .ply, .off or .stl)");
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path + ": no such file");
  std::ifstream probe(path, std::ios::binary);
  if (!probe) throw InputError(path + ": cannot open file");
  probe.close();
  Mesh mesh;
  if (ext == "stl") {
    mesh = read_stl(path);
  } else {
    MeshImporter importer(mesh);
    read_through_openmesh(path, importer);
    check_declared_counts(path, ext, importer, mesh);
  }
  check_finite(mesh, path);
  return mesh;
}

void write_mesh(const Mesh& mesh, const std::string& path) {
  const std::string ext = extension_of(path);
  std::function<void(std::ostream&)> writer;
  if (ext == "obj") writer = [&](std::ostream& out) { write_obj(mesh, out); };
  else if (ext == "off") writer = [&](std::ostream& out) { write_off(mesh, out); };
  else if (ext == "ply") writer = [&](std::ostream& out) { write_ply(mesh, out); };
  else if (ext == "stl") writer = [&](std::ostream& out) { write_stl(mesh, out); };
  else throw InputError(path + ": unknown mesh format '" + ext + "' (expected .obj, .ply, .off or .stl)");
  write_file_atomically(path, writer, true);
}

}  // namespace ab
