// Mesh I/O: the contract's id rule (file face order, fan triangulation, every face kept) for every
// format, round trips, the real meshes, and bad files.
#include "datasets/mesh_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "accel/core/error.h"
#include "datasets/generators.h"

namespace ab {
namespace {

namespace fs = std::filesystem;

/// A scratch directory removed at the end of the test.
class MeshIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("accelbench_mesh_io_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string write(const std::string& name, const std::string& content) const {
    std::ofstream(path(name), std::ios::binary) << content;
    return path(name);
  }
  fs::path dir_;
};

// The test polygon soup: a quad, a pentagon, three more faces on edge (0,1) (non-manifold), a
// duplicated face and a degenerate face (repeated vertex).
const std::vector<vec3> kVertices = {{0, 0, 0},    {1, 0, 0},       {1, 1, 0},    {0, 1, 0},
                                     {2, 0.5f, 0}, {1.5f, 2, 0.1f}, {0.5f, 1, 1}, {0.25f, -1, 0.75f}};
const std::vector<std::vector<int>> kFaces = {{0, 1, 2, 3}, {0, 1, 4, 5, 6}, {0, 1, 5}, {0, 1, 6},
                                              {0, 1, 7},    {2, 3, 4},       {2, 3, 4}, {1, 1, 2}};
const std::vector<glm::uvec3> kTriangles = {{0, 1, 2}, {0, 2, 3}, {0, 1, 4}, {0, 4, 5}, {0, 5, 6}, {0, 1, 5},
                                            {0, 1, 6}, {0, 1, 7}, {2, 3, 4}, {2, 3, 4}, {1, 1, 2}};

std::string obj_text() {
  std::ostringstream s;
  s << "# test\n";
  for (const vec3& v : kVertices) s << "v " << v.x << ' ' << v.y << ' ' << v.z << '\n';
  for (const auto& f : kFaces) {
    s << 'f';
    for (int i : f) s << ' ' << i + 1;
    s << '\n';
  }
  return s.str();
}

/// The vertex lines, then the face lines (count, then indices), as OFF and ASCII PLY write them.
std::string vertex_and_face_lines() {
  std::ostringstream s;
  for (const vec3& v : kVertices) s << v.x << ' ' << v.y << ' ' << v.z << '\n';
  for (const auto& f : kFaces) {
    s << f.size();
    for (int i : f) s << ' ' << i;
    s << '\n';
  }
  return s.str();
}

std::string off_text() {
  std::ostringstream s;
  s << "OFF\n" << kVertices.size() << ' ' << kFaces.size() << " 0\n" << vertex_and_face_lines();
  return s.str();
}

std::string ply_header(const std::string& format, size_t vertices, size_t faces) {
  return "ply\nformat " + format + " 1.0\nelement vertex " + std::to_string(vertices) +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " + std::to_string(faces) +
         "\nproperty list uchar int vertex_indices\nend_header\n";
}

std::string ply_ascii_text() {
  std::ostringstream s;
  s << ply_header("ascii", kVertices.size(), kFaces.size()) << vertex_and_face_lines();
  return s.str();
}

/// Appends 4 bytes of value in little or big endian order.
template <class T>
void put4(std::string& s, T value, bool big) {
  unsigned char b[4];
  std::memcpy(b, &value, 4);
  for (int i = 0; i < 4; ++i) s.push_back(static_cast<char>(b[big ? 3 - i : i]));
}

std::string ply_binary_text(bool big) {
  std::string s =
      ply_header(big ? "binary_big_endian" : "binary_little_endian", kVertices.size(), kFaces.size());
  for (const vec3& v : kVertices) {
    put4(s, v.x, big);
    put4(s, v.y, big);
    put4(s, v.z, big);
  }
  for (const auto& f : kFaces) {
    s.push_back(static_cast<char>(f.size()));
    for (int i : f) put4(s, i, big);
  }
  return s;
}

std::string stl_ascii_text() {
  std::ostringstream s;
  s << "solid test\n";
  for (const glm::uvec3& t : kTriangles) {
    s << "  facet normal 0 0 1\n    outer loop\n";
    for (uint32_t i : {t.x, t.y, t.z})
      s << "      vertex " << kVertices[i].x << ' ' << kVertices[i].y << ' ' << kVertices[i].z << '\n';
    s << "    endloop\n  endfacet\n";
  }
  s << "endsolid test\n";
  return s.str();
}

std::string stl_binary_text() {
  std::string s(80, ' ');
  put4(s, static_cast<uint32_t>(kTriangles.size()), false);
  for (const glm::uvec3& t : kTriangles) {
    for (int k = 0; k < 3; ++k) put4(s, 0.0f, false);
    for (uint32_t i : {t.x, t.y, t.z})
      for (int k = 0; k < 3; ++k) put4(s, kVertices[i][k], false);
    s += std::string(2, '\0');
  }
  return s;
}

/// Same indices and vertices as the test soup.
void expect_indexed(const Mesh& m) {
  ASSERT_EQ(m.vertices.size(), kVertices.size());
  for (size_t i = 0; i < kVertices.size(); ++i) EXPECT_EQ(m.vertices[i], kVertices[i]) << "vertex " << i;
  ASSERT_EQ(m.triangles.size(), kTriangles.size());
  for (size_t i = 0; i < kTriangles.size(); ++i) EXPECT_EQ(m.triangles[i], kTriangles[i]) << "triangle " << i;
}

/// Same triangle corners, in order (for STL, which has no shared vertices).
void expect_corners(const Mesh& m, const Mesh& expected) {
  ASSERT_EQ(m.size(), expected.size());
  for (size_t i = 0; i < m.size(); ++i) {
    const Triangle a = m.triangle(i), b = expected.triangle(i);
    EXPECT_TRUE(a.v0 == b.v0 && a.v1 == b.v1 && a.v2 == b.v2) << "triangle " << i;
  }
}

Mesh soup_mesh() {
  Mesh m;
  m.vertices = kVertices;
  m.triangles = kTriangles;
  return m;
}

TEST_F(MeshIoTest, ObjKeepsFaceOrderFansAndEveryFace) {
  expect_indexed(read_mesh(write("a.obj", obj_text())));
}
TEST_F(MeshIoTest, ObjCornerFormsNegativeIndicesAndRepeatedCorners) {
  // i/t/n and i//n corners, negative (relative) indices, and a quad with a repeated corner, which
  // must still give two triangles in fan order (OpenMesh's OBJ reader would merge the corners).
  const Mesh m = read_mesh(write("c.obj",
                                 "o thing\nv 0 0 0\nv 1 0 0\nvt 0 0\nvn 0 0 1\nv 1 1 0 # comment\nv 0 1 0\n"
                                 "usemtl x\nf 1/1/1 2/1/1 3/1/1\nf 1//1 3//1 4//1\nf -4 -3 -2 -1\nf 1 2 2 3\n"
                                 "s off\nl 1 2\n"));
  const std::vector<glm::uvec3> expected = {{0, 1, 2}, {0, 2, 3}, {0, 1, 2}, {0, 2, 3}, {0, 1, 1}, {0, 1, 2}};
  EXPECT_EQ(m.triangles, expected);
  EXPECT_EQ(m.vertices.size(), 4u);
}
TEST_F(MeshIoTest, OffKeepsFaceOrderFansAndEveryFace) {
  expect_indexed(read_mesh(write("a.off", off_text())));
}
TEST_F(MeshIoTest, AsciiPlyKeepsFaceOrderFansAndEveryFace) {
  expect_indexed(read_mesh(write("a.ply", ply_ascii_text())));
}
TEST_F(MeshIoTest, BinaryPlyKeepsFaceOrderFansAndEveryFace) {
  expect_indexed(read_mesh(write("le.ply", ply_binary_text(false))));
  expect_indexed(read_mesh(write("be.ply", ply_binary_text(true))));
}
TEST_F(MeshIoTest, StlKeepsEveryTriangleInOrder) {
  expect_corners(read_mesh(write("a.stl", stl_ascii_text())), soup_mesh());
  expect_corners(read_mesh(write("b.stl", stl_binary_text())), soup_mesh());
}
TEST_F(MeshIoTest, BinaryStlWhoseHeaderStartsWithSolid) {
  std::string s = stl_binary_text();
  s.replace(0, 5, "solid");
  expect_corners(read_mesh(write("c.stl", s)), soup_mesh());
}

TEST_F(MeshIoTest, RoundTripEveryFormatExactly) {
  Params p;
  const Mesh m = generate_mesh("cityscape", 700, 5, p);  // includes duplicate and zero-area triangles
  const Mesh s = generate_mesh("soup", 300, 9, p);       // arbitrary float coordinates
  for (const Mesh* mesh : {&m, &s})
    for (const char* ext : {"obj", "off", "ply", "stl"}) {
      SCOPED_TRACE(ext);
      const std::string file = path(std::string("r.") + ext);
      write_mesh(*mesh, file);
      const Mesh back = read_mesh(file);
      if (std::string(ext) == "stl") {
        expect_corners(back, *mesh);
      } else {
        EXPECT_EQ(back.vertices, mesh->vertices);
        EXPECT_EQ(back.triangles, mesh->triangles);
      }
    }
}

TEST_F(MeshIoTest, WritingIsByteDeterministicAndLeavesNoTemporaryFile) {
  Params p;
  const Mesh m = generate_mesh("sphereflake", 500, 1, p);
  for (const char* ext : {"obj", "off", "ply", "stl"}) {
    const std::string a = path(std::string("a.") + ext), b = path(std::string("b.") + ext);
    write_mesh(m, a);
    write_mesh(m, b);
    std::ifstream fa(a, std::ios::binary), fb(b, std::ios::binary);
    const std::string ca((std::istreambuf_iterator<char>(fa)), {}),
        cb((std::istreambuf_iterator<char>(fb)), {});
    EXPECT_FALSE(ca.empty());
    EXPECT_EQ(ca, cb) << ext;
  }
  size_t files = 0;
  for (const auto& e : fs::directory_iterator(dir_)) files += e.is_regular_file();
  EXPECT_EQ(files, 8u);
}

TEST_F(MeshIoTest, EmptyMeshRoundTrips) {
  for (const char* ext : {"obj", "off", "ply", "stl"}) {
    const std::string file = path(std::string("e.") + ext);
    write_mesh(Mesh{}, file);
    EXPECT_EQ(read_mesh(file).size(), 0u) << ext;
  }
}

/// Expects InputError whose message names the file and contains `what`.
void expect_input_error(const std::string& file, const std::string& what) {
  try {
    read_mesh(file);
    ADD_FAILURE() << "no error for " << file;
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(file), std::string::npos) << msg;
    EXPECT_NE(msg.find(what), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}

TEST_F(MeshIoTest, MissingFileAndUnknownExtension) {
  expect_input_error(path("missing.obj"), "no such file");
  fs::create_directories(path("folder.obj"));
  expect_input_error(path("folder.obj"), "not a regular file");
  expect_input_error(write("a.xyz", obj_text()), "unknown mesh format");
  expect_input_error(write("noext", obj_text()), "unknown mesh format");
  EXPECT_THROW(write_mesh(soup_mesh(), path("a.xyz")), InputError);
  EXPECT_FALSE(fs::exists(path("a.xyz.tmp")));
}

TEST_F(MeshIoTest, NonFiniteCoordinates) {
  expect_input_error(write("nan.obj", "v 0 0 0\nv nan 1 0\nv 0 1 0\nf 1 2 3\n"), "NaN or infinite");
  expect_input_error(write("inf.off", "OFF\n3 1 0\n0 0 0\n1 inf 0\n0 1 0\n3 0 1 2\n"), "NaN or infinite");
  std::string ply = ply_binary_text(false);
  const size_t at = ply.find("end_header\n") + 11 + 4;  // y of vertex 0
  const float nan = std::nanf("");
  std::memcpy(&ply[at], &nan, 4);
  expect_input_error(write("nan.ply", ply), "NaN or infinite");
  expect_input_error(write("nan2.ply", ply_header("ascii", 3, 1) + "0 0 0\nnan 1 0\n0 1 0\n3 0 1 2\n"),
                     "NaN or infinite");
  expect_input_error(write("nan.stl",
                           "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex nan 0 0\n"
                           "vertex 0 1 0\nendloop\nendfacet\nendsolid x\n"),
                     "NaN or infinite");
}

TEST_F(MeshIoTest, NumbersBeyondTheFloatRange) {
  // Too large for a float: refused as such (it was "not a number"); too small: the nearest float, zero.
  expect_input_error(write("big.obj", "v 0 0 0\nv 1e39 1 0\nv 0 1 0\nf 1 2 3\n"),
                     "'1e39' is beyond the range of a 32-bit float");
  expect_input_error(write("big.stl",
                           "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex -4e38 0 0\n"
                           "vertex 0 1 0\nendloop\nendfacet\nendsolid x\n"),
                     "beyond the range");
  const Mesh m = read_mesh(write("tiny.obj", "v 0 0 0\nv 1 1e-50 0\nv 0 1 -1e-400\nf 1 2 3\n"));
  ASSERT_EQ(m.vertices.size(), 3u);
  EXPECT_EQ(m.vertices[1].y, 0.0f);
  EXPECT_EQ(m.vertices[2].z, 0.0f);
  EXPECT_EQ(m.vertices[1].x, 1.0f);
}

TEST_F(MeshIoTest, IndexOutOfRange) {
  expect_input_error(write("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n"), "vertex");
  expect_input_error(write("bad.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 7\n"), "vertex");
  expect_input_error(write("bad.ply", ply_header("ascii", 3, 1) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"),
                     "vertex");
  expect_input_error(write("neg.ply", ply_header("ascii", 3, 1) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n"),
                     "vertex -1");
  std::string binary = ply_binary_text(false);
  binary[binary.size() - 1] = 0x7F;  // last corner of the last face becomes a huge index
  expect_input_error(write("bad_binary.ply", binary), "vertex");
}

TEST_F(MeshIoTest, TruncatedBinaryFiles) {
  const std::string ply = ply_binary_text(false);
  expect_input_error(write("t.ply", ply.substr(0, ply.size() - 7)), "end of file");
  const std::string stl = stl_binary_text();
  expect_input_error(write("t.stl", stl.substr(0, stl.size() - 20)), "truncated");
  expect_input_error(write("u.stl", stl.substr(0, 50)), "truncated");
  const std::string ascii = stl_ascii_text();
  expect_input_error(write("t2.stl", ascii.substr(0, ascii.size() / 2)), "truncated");
}

TEST_F(MeshIoTest, MalformedContent) {
  expect_input_error(write("m.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n"), "truncated");
  expect_input_error(write("m.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 zero\n"),
                     "not a number");
  expect_input_error(write("m.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"),
                     "end_header");
  expect_input_error(
      write("n.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n"),
      "x, y or z");
  expect_input_error(write("p.ply", ply_header("ascii", 3, 1) + "0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n"),
                     "not a number");
  expect_input_error(write("q.ply", ply_header("ascii", 3, 1) + "0 0 0\n1 0 0\n"), "truncated");
  expect_input_error(write("r.ply", "PLY?\n"), "not a PLY file");
  expect_input_error(write("m.obj", "v 0 0\n"), "three coordinates");
  expect_input_error(write("n.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n"), "fewer than three");
  expect_input_error(write("o.obj", "v 0 0 0\nv 1 0 0\nv 1 1 1\nf 1 x 3\n"), "not a vertex index");
  expect_input_error(write("n.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n"), "");
}

// ---- fuzzing findings (fuzz/regressions/; each was a hang, an abort or a huge allocation) ----

TEST_F(MeshIoTest, PlyVersionMustBeANumber) {
  // OpenMesh's header reader looped forever on a version its stream could not read.
  const std::string body =
      "\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  for (const char* version : {"x", "1e999", "", "1.0x", "nan", "1."})
    expect_input_error(write("v.ply", std::string("ply\nformat ascii ") + version + body), "version number");
  expect_input_error(write("b.ply", "ply\nformat binary_little_endian x" + body),
                     ":2: the format line needs");
  EXPECT_EQ(read_mesh(write("ok.ply", "ply\nformat ascii 1" + body)).size(), 0u);
}

TEST_F(MeshIoTest, BinaryPlyBodyMustHoldTheDeclaredElements) {
  // OpenMesh read the declared number of elements past the end of the file (minutes for 10^6).
  std::string ply = ply_binary_text(false);
  ply.replace(ply.find("vertex 8"), 8, "vertex 1000000");
  expect_input_error(write("big.ply", ply), "unexpected end of file in vertex ");
  std::string faces = ply_binary_text(true);
  faces.replace(faces.find("face 8"), 6, "face 2000000000");
  expect_input_error(write("faces.ply", faces), "unexpected end of file in face 9 of 2000000000");
  // A list as long as its int count says (2^31 - 1 entries; OpenMesh tried to read them all).
  std::string list = ply_header("binary_little_endian", 3, 1);
  list.replace(list.find("list uchar"), 10, "list int");
  for (int i = 0; i < 9; ++i) put4(list, 0.0f, false);
  for (int n : {0x7FFFFFFF, 0, 1, 2}) put4(list, n, false);
  expect_input_error(write("list.ply", list), "unexpected end of file in face 1 of 1");
  list.replace(list.size() - 16, 4, "\xff\xff\xff\xff");
  expect_input_error(write("negative.ply", list), "face 1 has a negative list length");
  std::string float_count = ply_header("ascii", 3, 1);
  float_count.replace(float_count.find("list uchar"), 10, "list float");
  expect_input_error(write("float.ply", float_count), "count type must be an integer type");
  std::string ascii_list = ply_header("ascii", 1, 0);
  ascii_list.replace(ascii_list.find("element face"), 0, "property list int float extra\n");
  expect_input_error(write("negative2.ply", ascii_list + "0 0 0 -1\n"), ":11: negative list length -1");
  expect_input_error(write("2p32.ply", ply_header("ascii", 4294967296ull, 0)), "not a number in [0, 2^31)");
}

TEST_F(MeshIoTest, PlyHeaderLinesEndWhereTheirFieldsEnd) {
  // OpenMesh reads the header token by token: "element vertex 5element" made it loop forever, writing
  // an error message each time (found by fuzz_ply, fuzz/regressions/ply/element_count_suffix_timeout.ply).
  const std::string good = ply_binary_text(false);
  const auto with = [&](const std::string& from, const std::string& to) {
    std::string s = good;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  expect_input_error(write("a.ply", with("vertex 8\n", "vertex 8element\n")), ":3: malformed element line");
  expect_input_error(write("b.ply", with("vertex 8\n", "vertex 8 9\n")), ":3: unexpected '9'");
  expect_input_error(write("c.ply", with("float x\n", "float x y\n")), ":4: unexpected 'y'");
  expect_input_error(write("d.ply", with("1.0\n", "1.0 1.0\n")), ":2: unexpected '1.0'");
  expect_input_error(write("e.ply", with("end_header\n", "end_header x\n")), "unexpected 'x'");
  expect_input_error(write("f.ply", with("vertex 8\n", "vertex\n")), "malformed element line");
  expect_input_error(write("g.ply", with("ply\n", "plyx\n")), "not a PLY file");
  // ASCII bodies are read token by token too: a value too many would shift the rest.
  const std::string header = ply_header("ascii", 3, 1);
  expect_input_error(write("h.ply", header + "0 0 0 7\n1 0 0\n0 1 0\n3 0 1 2\n"), ":10: too many values");
  expect_input_error(write("i.ply", header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2 5\n"), ":13: too many values");
  std::string int_header = header;
  int_header.replace(int_header.find("float x"), 7, "int x");
  expect_input_error(write("j.ply", int_header + "0 0 0\n1.5 0 0\n0 1 0\n3 0 1 2\n"),
                     "'1.5' is not an integer");
  EXPECT_EQ(read_mesh(write("k.ply", int_header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")).size(), 1u);
}

TEST_F(MeshIoTest, OffVariantsAndSameLineCounts) {
  const std::string tri = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  const std::vector<glm::uvec3> one = {{0, 1, 2}};
  EXPECT_EQ(read_mesh(write("s.off", "OFF 3 1 0\n" + tri)).triangles, one);
  EXPECT_EQ(read_mesh(write("c.off", "# c\nOFF\n# c\n3 1 0 # c\n" + tri)).triangles, one);
  const Mesh colour = read_mesh(write(
      "c2.off", "COFF\n3 2 0\n0 0 0 1 0 0 1\n1 0 0 0 1 0 1\n0 1 0 0 0 1 1\n3 0 1 2 255 0 0\n3 2 1 0\n"));
  EXPECT_EQ(colour.triangles, (std::vector<glm::uvec3>{{0, 1, 2}, {2, 1, 0}}));
  EXPECT_EQ(colour.vertices[1], vec3(1, 0, 0));
  EXPECT_EQ(
      read_mesh(write("n.off", "NOFF\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n")).triangles,
      one);
  EXPECT_EQ(read_mesh(write("st.off",
                            "STCNOFF\n3 1 0\n0 0 0 0 0 1 1 1 1 0 0\n1 0 0 0 0 1 1 1 1 1 0\n"
                            "0 1 0 0 0 1 1 1 1 0 1\n3 0 1 2\n"))
                .triangles,
            one);
}

TEST_F(MeshIoTest, FuzzedOffFilesAreOneLineErrors) {
  std::string binary = "OFF BINARY\n";
  for (uint32_t n : {0u, 1000000u, 0u}) put4(binary, n, false);  // hung OpenMesh for ~1000 s
  expect_input_error(write("bin.off", binary), "binary OFF is not supported");
  expect_input_error(write("coff.off", "COFF\n"), "no vertex and face counts");    // OpenMesh: random counts
  expect_input_error(write("offof.off", "OFFOF"), "unknown OFF keyword 'OFFOF'");  // OpenMesh: 16 GB
  expect_input_error(write("noff.off", "NOFF\n3 1 0\n"), "truncated: vertex 1 is missing");
  expect_input_error(write("coff2.off", "COFF\n3 1 0\n0 0 0 1 0 0 1\n1 0 0 1 0 0 1\n"),
                     "vertex 3 is missing");
  expect_input_error(write("4off.off", "4OFF\n3 1 0\n"), "not supported");
  expect_input_error(write("noff2.off", "nOFF\n4\n3 1 0\n"), "not supported");
  expect_input_error(write("same.off", "OFF 0 0\n1 4000000000\n"), "unexpected content after the last face");
  expect_input_error(write("t.off", "OFF 0 0\n1 122222222222222222222\n"), "unexpected content");
  expect_input_error(write("corners.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4000000000 0 1 2\n"),
                     ":6: expected a vertex index");
  expect_input_error(write("neg.off", "OFF\n-3 1 0\n"), ":2: expected the vertex count, got '-3'");
  expect_input_error(write("huge.off", "OFF\n99999999999999999999 1 0\n"), "expected the vertex count");
  expect_input_error(write("many.off", "OFF\n1000000000 0 0\n0 0 0\n"), "vertex 2 is missing");
  expect_input_error(write("none.off", "ply\n"), "not an OFF file");
  expect_input_error(write("stcoff.off", "STCOFF\n5 000007211644586605 5 0\n0 * 0\n"), "'*' is not a number");
}

/// Triangle count of a real mesh in ../shared/meshes, or skips when it is absent.
void expect_real_mesh(const std::string& name, size_t faces) {
  const std::string file = std::string(ACCELBENCH_SOURCE_DIR "/../shared/meshes/") + name;
  if (!fs::exists(file)) GTEST_SKIP() << file << " is absent; the real-mesh test needs it";
  const Mesh m = read_mesh(file);
  EXPECT_EQ(m.size(), faces);
  EXPECT_FALSE(m.bounds().empty());
}

TEST(MeshIoRealMeshes, StanfordBunny) {
  expect_real_mesh("stanford-bunny.obj", 69451);
}
TEST(MeshIoRealMeshes, Teapot) {
  expect_real_mesh("teapot.obj", 6320);
}

}  // namespace
}  // namespace ab
