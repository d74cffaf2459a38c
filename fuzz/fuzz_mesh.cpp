// read_mesh() on one format (FUZZ_MESH_EXT: obj, ply, off or stl): the whole path a mesh file takes
// (checks, OpenMesh for PLY, finiteness). Anything but ab::InputError escaping is a finding, and so is
// an accepted mesh with an out-of-range index or a non-finite vertex.
#include <sanitizer/lsan_interface.h>

#include <cmath>
#include <cstdint>
#include <cstring>

#include "accel/core/error.h"
#include "datasets/mesh_io.h"
#include "fuzz_common.h"

// One PLY read before fuzzing, with LeakSanitizer off: OpenMesh's singletons (IOManager, omerr and
// the capture stream mesh_io.cpp connects to it once) are created here, outside any input.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const char* ply =
      "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
      "end_header\n";
  const std::string path = fuzz::write_input(reinterpret_cast<const uint8_t*>(ply), std::strlen(ply), "ply");
  __lsan_disable();
  try {
    ab::read_mesh(path);
  } catch (const ab::InputError&) {
  }
  __lsan_enable();
  std::remove(path.c_str());
  fuzz::input_path().clear();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& path = fuzz::write_input(data, size, FUZZ_MESH_EXT);
  try {
    const ab::Mesh mesh = ab::read_mesh(path);
    const size_t n = mesh.vertices.size();
    for (const auto& t : mesh.triangles) FUZZ_CHECK(t.x < n && t.y < n && t.z < n);
    for (const auto& v : mesh.vertices)
      FUZZ_CHECK(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z));
  } catch (const ab::InputError&) {
  }
  return 0;
}
