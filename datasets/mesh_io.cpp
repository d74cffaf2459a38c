#include "datasets/mesh_io.h"

#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/System/omstream.hh>
#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>

#include "accel/core/error.h"
#include "datasets/atomic_file.h"
#include "datasets/io_util.h"
#include "datasets/mesh_checks.h"
#include "datasets/mesh_importer.h"
#include "datasets/obj_reader.h"
#include "datasets/off_reader.h"
#include "datasets/stl_io.h"

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
  // OpenMesh's mostream::disconnect() drops a target without deleting it (32 bytes leaked per call),
  // so the capture stream is connected once, for the life of the process, instead of once per read.
  static std::ostringstream& messages = *[] {
    auto* stream = new std::ostringstream;
    ::omerr().disconnect(std::cerr);
    ::omerr().connect(*stream);
    ::omlog().disable();
    ::omout().disable();
    return stream;
  }();
  messages.str("");
  OpenMesh::IO::Options options;
  const bool ok = OpenMesh::IO::IOManager().read(path, importer, options);
  ::omerr().flush();
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
  for (const glm::uvec3& t : mesh.triangles)
    out << "f " << t.x + 1 << ' ' << t.y + 1 << ' ' << t.z + 1 << '\n';
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

/// Binary little-endian PLY: float vertices, faces as uchar count + uint indices.
void write_ply(const Mesh& mesh, std::ostream& out) {
  out << "ply\nformat binary_little_endian 1.0\ncomment accelbench mesh\nelement vertex "
      << mesh.vertices.size() << "\nproperty float x\nproperty float y\nproperty float z\nelement face "
      << mesh.size() << "\nproperty list uchar uint vertex_indices\nend_header\n";
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

/// Element counts a PLY header declares (-1 where unknown).
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

/// OpenMesh's PLY reader stops quietly at the end of a truncated file; comparing what arrived with
/// the counts the header declares turns that into an error.
void check_declared_counts(const std::string& path, const MeshImporter& importer, const Mesh& mesh) {
  std::ifstream in(path, std::ios::binary);
  const DeclaredCounts d = declared_ply(in);
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
  if (!std::filesystem::exists(path, ec)) throw InputError(path + ": no such file");
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path + ": not a regular file");
  std::ifstream probe(path, std::ios::binary);
  if (!probe) throw InputError(path + ": cannot open file");
  probe.close();
  Mesh mesh;
  if (ext == "stl") {
    mesh = read_stl(path);
  } else if (ext == "obj") {
    mesh = read_obj(path);
  } else if (ext == "off") {
    mesh = read_off(path);
  } else {
    check_ply(path);
    MeshImporter importer(mesh);
    read_through_openmesh(path, importer);
    check_declared_counts(path, importer, mesh);
  }
  check_finite(mesh, path);
  return mesh;
}

void write_mesh(const Mesh& mesh, const std::string& path) {
  const std::string ext = extension_of(path);
  std::function<void(std::ostream&)> writer;
  if (ext == "obj")
    writer = [&](std::ostream& out) { write_obj(mesh, out); };
  else if (ext == "off")
    writer = [&](std::ostream& out) { write_off(mesh, out); };
  else if (ext == "ply")
    writer = [&](std::ostream& out) { write_ply(mesh, out); };
  else if (ext == "stl")
    writer = [&](std::ostream& out) { write_stl(mesh, out); };
  else
    throw InputError(path + ": unknown mesh format '" + ext + "' (expected .obj, .ply, .off or .stl)");
  write_file_atomically(path, writer, true);
}

}  // namespace ab
