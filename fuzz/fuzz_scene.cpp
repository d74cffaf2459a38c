// parse_scene() on in-memory XML (the scene reader's own entry point; no temporary file). base_dir
// is a folder that does not exist, so relative file= meshes fail (the mesh readers have targets of their
// own). Generator meshes are real work, not parsing: inputs asking for more than kMaxTriangles in all
// are skipped, since a 10^8-triangle request (or fifty of 20k) is a legitimate (slow) scene.
#include <algorithm>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <pugixml.hpp>
#include <string>

#include "accel/core/error.h"
#include "fuzz_common.h"
#include "tracer/scene.h"

namespace {

constexpr uint64_t kMaxTriangles = 20000;

/// True when the elements together ask for more than kMaxTriangles generated triangles.
bool asks_for_big_generator(const std::string& text) {
  if (text.find("triangles") == std::string::npos) return false;
  pugi::xml_document doc;
  if (!doc.load_buffer(text.data(), text.size(), pugi::parse_default)) return false;
  uint64_t total = 0;
  for (const pugi::xpath_node& n : doc.select_nodes("//*[@triangles]")) {
    const std::string v = n.node().attribute("triangles").value();
    uint64_t count = 0;
    const auto [ptr, ec] = std::from_chars(v.data(), v.data() + v.size(), count);
    if (ec == std::errc()) total += std::min<uint64_t>(count, kMaxTriangles + 1);
    if (total > kMaxTriangles) return true;
  }
  return false;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  if (asks_for_big_generator(text)) return 0;
  try {
    const ab::Scene scene = ab::parse_scene(text, "fuzz.xml", "/nonexistent-fuzz-dir");
    FUZZ_CHECK(!scene.instances.empty());
    for (const auto& inst : scene.instances) {
      FUZZ_CHECK(inst.mesh < scene.meshes.size() && inst.material < scene.materials.size());
      const ab::Mesh& m = *scene.meshes[inst.mesh].mesh;
      const size_t n = m.vertices.size();
      for (const auto& t : m.triangles) FUZZ_CHECK(t.x < n && t.y < n && t.z < n);
    }
  } catch (const ab::InputError&) {
  }
  return 0;
}
