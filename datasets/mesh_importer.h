// An OpenMesh importer that stores what a reader sends, in file order, into ab::Mesh: no halfedge
// structure, so non-manifold, duplicate and degenerate faces are all kept and ids never shift.
#pragma once

#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <algorithm>
#include <string>

#include "accel/core/error.h"
#include "accel/core/mesh.h"

namespace ab {

/// Receives vertices and faces from OpenMesh's format readers (OBJ, PLY, OFF) and fan-triangulates
/// each face (v0 v1 v2), (v0 v2 v3), ... into the mesh. Errors (an index out of range, a face of
/// fewer than three vertices) are recorded and thrown by check(), since readers are not written to
/// be unwound by exceptions.
class MeshImporter : public OpenMesh::IO::BaseImporter {
 public:
  using VertexHandle = OpenMesh::VertexHandle;
  using FaceHandle = OpenMesh::FaceHandle;
  using HalfedgeHandle = OpenMesh::HalfedgeHandle;
  using EdgeHandle = OpenMesh::EdgeHandle;
  using StatusInfo = OpenMesh::Attributes::StatusInfo;

  /// Appends to `mesh`.
  explicit MeshImporter(Mesh& mesh) : mesh_(mesh) {}

  /// Throws InputError naming `path` for the first problem seen, if any.
  void check(const std::string& path) const {
    if (!error_.empty()) throw InputError(path + ": " + error_);
  }
  /// Faces received (polygons, before triangulation).
  size_t faces() const { return faces_; }

  /// Appends a vertex; its handle is its index.
  VertexHandle add_vertex(const OpenMesh::Vec3f& p) override {
    mesh_.vertices.emplace_back(p[0], p[1], p[2]);
    return VertexHandle(static_cast<int>(mesh_.vertices.size() - 1));
  }
  /// Appends a vertex given in double precision (rounded to float).
  VertexHandle add_vertex(const OpenMesh::Vec3d& p) override {
    return add_vertex(
        OpenMesh::Vec3f(static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2])));
  }
  /// Appends a vertex at the origin (set later by set_point).
  VertexHandle add_vertex() override { return add_vertex(OpenMesh::Vec3f(0.0f, 0.0f, 0.0f)); }
  /// Moves an existing vertex.
  void set_point(VertexHandle vh, const OpenMesh::Vec3f& p) override {
    if (vh.is_valid() && static_cast<size_t>(vh.idx()) < mesh_.vertices.size())
      mesh_.vertices[static_cast<size_t>(vh.idx())] = {p[0], p[1], p[2]};
  }

  /// Fan-triangulates a face in file order, or records why it cannot.
  FaceHandle add_face(const VHandles& indices) override {
    const size_t face = faces_++;
    for (const VertexHandle& vh : indices)
      if (!vh.is_valid() || static_cast<size_t>(vh.idx()) >= mesh_.vertices.size()) {
        fail("face " + std::to_string(face + 1) + " refers to vertex " + std::to_string(vh.idx()) +
             " (0-based), but there are only " + std::to_string(mesh_.vertices.size()) + " vertices");
        return FaceHandle(static_cast<int>(face));
      }
    if (indices.size() < 3) fail("face " + std::to_string(face + 1) + " has fewer than three vertices");
    for (size_t i = 2; i < indices.size(); ++i)
      mesh_.triangles.emplace_back(indices[0].idx(), indices[i - 1].idx(), indices[i].idx());
    return FaceHandle(static_cast<int>(face));
  }
  /// Not used by the format readers; recorded as an error.
  FaceHandle add_face(HalfedgeHandle) override {
    fail("halfedge-based faces are not supported");
    return FaceHandle();
  }
  /// No halfedges are kept.
  HalfedgeHandle add_edge(VertexHandle, VertexHandle) override { return HalfedgeHandle(); }

  /// Attributes the benchmark does not use (normals, colours, texture coordinates, status): accepted and
  /// dropped.
  void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<OpenMesh::Vec2f>&) override {}
  void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<OpenMesh::Vec3f>&) override {}
  void set_face_texindex(FaceHandle, int) override {}
  void set_halfedge(VertexHandle, HalfedgeHandle) override {}
  void set_normal(VertexHandle, const OpenMesh::Vec3f&) override {}
  void set_normal(VertexHandle, const OpenMesh::Vec3d&) override {}
  void set_color(VertexHandle, const OpenMesh::Vec3uc&) override {}
  void set_color(VertexHandle, const OpenMesh::Vec4uc&) override {}
  void set_color(VertexHandle, const OpenMesh::Vec3f&) override {}
  void set_color(VertexHandle, const OpenMesh::Vec4f&) override {}
  void set_texcoord(VertexHandle, const OpenMesh::Vec2f&) override {}
  void set_status(VertexHandle, const StatusInfo&) override {}
  void set_next(HalfedgeHandle, HalfedgeHandle) override {}
  void set_face(HalfedgeHandle, FaceHandle) override {}
  void request_face_texcoords2D() override {}
  void set_texcoord(HalfedgeHandle, const OpenMesh::Vec2f&) override {}
  void set_texcoord(VertexHandle, const OpenMesh::Vec3f&) override {}
  void set_texcoord(HalfedgeHandle, const OpenMesh::Vec3f&) override {}
  void set_status(HalfedgeHandle, const StatusInfo&) override {}
  void set_color(EdgeHandle, const OpenMesh::Vec3uc&) override {}
  void set_color(EdgeHandle, const OpenMesh::Vec4uc&) override {}
  void set_color(EdgeHandle, const OpenMesh::Vec3f&) override {}
  void set_color(EdgeHandle, const OpenMesh::Vec4f&) override {}
  void set_status(EdgeHandle, const StatusInfo&) override {}
  void set_normal(FaceHandle, const OpenMesh::Vec3f&) override {}
  void set_normal(FaceHandle, const OpenMesh::Vec3d&) override {}
  void set_color(FaceHandle, const OpenMesh::Vec3uc&) override {}
  void set_color(FaceHandle, const OpenMesh::Vec4uc&) override {}
  void set_color(FaceHandle, const OpenMesh::Vec3f&) override {}
  void set_color(FaceHandle, const OpenMesh::Vec4f&) override {}
  void set_status(FaceHandle, const StatusInfo&) override {}
  void add_texture_information(int, std::string) override {}

  /// Reserves room for the counts a header declares (capped).
  void reserve(unsigned int vertices, unsigned int, unsigned int faces) override {
    // Header counts are untrusted: reserve at most 2^26 up front, grow beyond that as data arrives.
    mesh_.vertices.reserve(std::min(vertices, 1u << 26));
    mesh_.triangles.reserve(std::min(faces, 1u << 26));
  }
  /// Vertices so far.
  size_t n_vertices() const override { return mesh_.vertices.size(); }
  /// Faces so far (before triangulation).
  size_t n_faces() const override { return faces_; }
  /// Always 0 (no edges are kept).
  size_t n_edges() const override { return 0; }

 private:
  void fail(const std::string& message) {
    if (error_.empty()) error_ = message;
  }

  Mesh& mesh_;
  size_t faces_ = 0;
  std::string error_;
};

}  // namespace ab
