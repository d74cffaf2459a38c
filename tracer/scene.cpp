#include "tracer/scene.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <pugixml.hpp>
#include <set>
#include <sstream>

#include "accel/core/error.h"
#include "accel/core/params.h"
#include "datasets/generators.h"
#include "datasets/mesh_io.h"

namespace ab {

namespace {

/// Reads a scene document: one pass for the declarations (meshes, materials, transforms, camera,
/// lights, settings), a second for the instances, so declarations may appear in any order.
class SceneParser {
 public:
  SceneParser(const std::string& text, std::string path, std::string base_dir)
      : text_(text), path_(std::move(path)), base_dir_(std::move(base_dir)) {}

  Scene parse() {
    pugi::xml_document doc;
    const pugi::xml_parse_result res = doc.load_buffer(text_.data(), text_.size(), pugi::parse_default);
    if (!res) fail_at(res.offset, std::string("malformed XML: ") + res.description());
    const pugi::xml_node root = doc.document_element();
    if (std::string(root.name()) != "scene")
      fail(root, "the root element must be <scene>, not <" + std::string(root.name()) + ">");
    check_attributes(root, {});
    scene_.path = path_;
    Material fallback;
    fallback.name = "default";
    scene_.materials.push_back(fallback);
    material_index_["default"] = 0;
    for (pugi::xml_node n : root.children()) declaration(n);
    for (pugi::xml_node n : root.children("instance")) instance(n);
    if (scene_.instances.empty()) fail(root, "the scene has no <instance>");
    scene_.bounds = scene_.compute_world_bounds();
    return std::move(scene_);
  }

 private:
  // ---- errors and values ----
  [[noreturn]] void fail_at(ptrdiff_t offset, const std::string& msg) const {
    const size_t end = std::min(static_cast<size_t>(std::max<ptrdiff_t>(offset, 0)), text_.size());
    const auto line = 1 + std::count(text_.begin(), text_.begin() + static_cast<ptrdiff_t>(end), '\n');
    throw InputError(path_ + ":" + std::to_string(line) + ": " + msg);
  }
  [[noreturn]] void fail(const pugi::xml_node& n, const std::string& msg) const {
    fail_at(n.offset_debug(), msg);
  }

  void check_attributes(const pugi::xml_node& n, const std::set<std::string>& allowed) const {
    for (pugi::xml_attribute a : n.attributes())
      if (!allowed.count(a.name()))
        fail(n, "unknown attribute '" + std::string(a.name()) + "' on <" + n.name() + ">");
  }
  std::string required_attribute(const pugi::xml_node& n, const char* name) const {
    const pugi::xml_attribute a = n.attribute(name);
    if (!a || std::string(a.value()).empty())
      fail(n, "<" + std::string(n.name()) + "> needs attribute '" + name + "'");
    return a.value();
  }

  /// Whitespace-separated finite numbers of element n (exactly `count` of them unless count is 0).
  std::vector<float> numbers(const pugi::xml_node& n, size_t count) const {
    std::vector<float> out;
    const std::string s = n.child_value();
    const char* p = s.data();
    const char* end = p + s.size();
    while (true) {
      while (p < end && std::isspace(static_cast<unsigned char>(*p))) ++p;
      if (p == end) break;
      const char* tok = p;
      while (p < end && !std::isspace(static_cast<unsigned char>(*p))) ++p;
      float v = 0.0f;
      const char* num = (*tok == '+') ? tok + 1 : tok;
      const auto [ptr, ec] = std::from_chars(num, p, v);
      if (ec != std::errc() || ptr != p || !std::isfinite(v))
        fail(n, "bad number '" + std::string(tok, p) + "' in <" + n.name() + ">");
      out.push_back(v);
    }
    if (count && out.size() != count)
      fail(n, "<" + std::string(n.name()) + "> needs " + std::to_string(count) + " number" +
                  (count > 1 ? "s" : "") + ", got " + std::to_string(out.size()));
    return out;
  }
  float number(const pugi::xml_node& n) const { return numbers(n, 1)[0]; }
  vec3 vector3(const pugi::xml_node& n) const {
    const auto v = numbers(n, 3);
    return {v[0], v[1], v[2]};
  }
  float number_in(const pugi::xml_node& n, float lo, float hi) const {
    const float v = number(n);
    if (v < lo || v > hi)
      fail(n, "<" + std::string(n.name()) + "> must be in [" + fmt(lo) + ", " + fmt(hi) + "], got " + fmt(v));
    return v;
  }
  int integer_in(const pugi::xml_node& n, int lo, int hi) const {
    const float v = number_in(n, float(lo), float(hi));
    if (v != std::floor(v)) fail(n, "<" + std::string(n.name()) + "> must be an integer");
    return static_cast<int>(v);
  }
  uint64_t attribute_integer(const pugi::xml_node& n, const char* name, uint64_t def, uint64_t lo,
                             uint64_t hi) const {
    const pugi::xml_attribute a = n.attribute(name);
    if (!a) return def;
    const std::string s = a.value();
    uint64_t v = 0;
    const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || ptr != s.data() + s.size() || s.empty() || v < lo || v > hi)
      fail(n, "attribute " + std::string(name) + "=\"" + s + "\" must be an integer in [" +
                  std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return v;
  }
  static std::string fmt(float v) {
    std::ostringstream os;
    os << v;
    return os.str();
  }

  // ---- declarations ----
  void declaration(const pugi::xml_node& n) {
    if (n.type() != pugi::node_element) {
      if (n.type() == pugi::node_pcdata &&
          std::string(n.value()).find_first_not_of(" \t\r\n") != std::string::npos)
        fail(n, "unexpected text in <scene>");
      return;
    }
    const std::string name = n.name();
    if (name == "instance") return;
    if (name == "camera") return camera(n);
    if (name == "render") return render(n);
    if (name == "background") return void(scene_.render.background = nonnegative3(n));
    if (name == "ambient") return void(scene_.render.ambient = nonnegative3(n));
    if (name == "material") return material(n);
    if (name == "light") return light(n);
    if (name == "mesh") return mesh(n);
    if (name == "transform") return named_transform(n);
    fail(n, "unknown element <" + name + "> in <scene>");
  }

  vec3 nonnegative3(const pugi::xml_node& n) const {
    check_attributes(n, {});
    const vec3 v = vector3(n);
    if (v.x < 0 || v.y < 0 || v.z < 0) fail(n, "<" + std::string(n.name()) + "> must not be negative");
    return v;
  }

  /// Calls f(child) for each element child; an element not in `allowed` is an error.
  template <class F>
  void children(const pugi::xml_node& n, const std::set<std::string>& allowed, F&& f) const {
    std::set<std::string> seen;
    for (pugi::xml_node c : n.children()) {
      if (c.type() != pugi::node_element) continue;
      if (!allowed.count(c.name()))
        fail(c, "unknown element <" + std::string(c.name()) + "> in <" + n.name() + ">");
      if (!seen.insert(c.name()).second && std::string(c.name()) != "param")
        fail(c, "<" + std::string(c.name()) + "> given twice in <" + n.name() + ">");
      f(c, std::string(c.name()));
    }
  }

  void camera(const pugi::xml_node& n) {
    check_attributes(n, {});
    Camera& cam = scene_.camera;
    children(n, {"eye", "lookat", "up", "fov", "aperture", "focus"},
             [&](const pugi::xml_node& c, const std::string& k) {
               if (k == "eye") cam.eye = vector3(c);
               if (k == "lookat") cam.look_at = vector3(c);
               if (k == "up") cam.up = vector3(c);
               if (k == "fov") cam.fov_degrees = number_in(c, 1.0f, 179.0f);
               if (k == "aperture") cam.aperture = number_in(c, 0.0f, std::numeric_limits<float>::max());
               if (k == "focus") cam.focal_distance = number_in(c, 0.0f, std::numeric_limits<float>::max());
             });
    const vec3 f = cam.look_at - cam.eye;
    if (glm::length(f) == 0.0f) fail(n, "camera eye and lookat coincide");
    if (glm::length(glm::cross(f, cam.up)) <= 1e-6f * glm::length(f) * glm::length(cam.up))
      fail(n, "camera up is zero or parallel to the view direction");
  }

  void render(const pugi::xml_node& n) {
    check_attributes(n, {});
    RenderSettings& r = scene_.render;
    children(n, {"width", "height", "spp", "maxdepth", "diffusedepth"},
             [&](const pugi::xml_node& c, const std::string& k) {
               if (k == "width") r.width = integer_in(c, 1, 16384);
               if (k == "height") r.height = integer_in(c, 1, 16384);
               if (k == "spp") r.spp = integer_in(c, 1, 65536);
               if (k == "maxdepth") r.max_depth = integer_in(c, 1, 64);
               if (k == "diffusedepth") r.diffuse_depth = integer_in(c, 0, 64);
             });
  }

  void material(const pugi::xml_node& n) {
    check_attributes(n, {"name", "type"});
    Material m;
    m.name = required_attribute(n, "name");
    const std::string type = required_attribute(n, "type");
    if (type == "diffuse")
      m.type = Material::Type::kDiffuse;
    else if (type == "mirror")
      m.type = Material::Type::kMirror;
    else if (type == "glossy")
      m.type = Material::Type::kGlossy;
    else if (type == "dielectric")
      m.type = Material::Type::kDielectric;
    else
      fail(n, "unknown material type '" + type + "' (known: diffuse, mirror, glossy, dielectric)");
    if (m.type != Material::Type::kDiffuse) m.color = vec3(1.0f);
    children(n, {"color", "roughness", "ior"}, [&](const pugi::xml_node& c, const std::string& k) {
      if (k == "color") m.color = nonnegative3(c);
      if (k == "roughness") m.roughness = number_in(c, 0.0f, 1.0f);
      if (k == "ior") m.ior = number_in(c, 1.0f, 10.0f);
    });
    if (material_index_.count(m.name) && m.name != "default")
      fail(n, "material '" + m.name + "' declared twice");
    if (m.name == "default") {
      if (default_replaced_) fail(n, "material 'default' declared twice");
      default_replaced_ = true;
      scene_.materials[0] = m;
      return;
    }
    material_index_[m.name] = static_cast<uint32_t>(scene_.materials.size());
    scene_.materials.push_back(m);
  }

  void light(const pugi::xml_node& n) {
    check_attributes(n, {"type"});
    const std::string type = required_attribute(n, "type");
    if (type == "point") {
      PointLight l;
      children(n, {"position", "intensity"}, [&](const pugi::xml_node& c, const std::string& k) {
        if (k == "position") l.position = vector3(c);
        if (k == "intensity") l.intensity = nonnegative3(c);
      });
      scene_.point_lights.push_back(l);
    } else if (type == "area") {
      AreaLight l;
      children(n, {"corner", "edge1", "edge2", "radiance"},
               [&](const pugi::xml_node& c, const std::string& k) {
                 if (k == "corner") l.corner = vector3(c);
                 if (k == "edge1") l.edge1 = vector3(c);
                 if (k == "edge2") l.edge2 = vector3(c);
                 if (k == "radiance") l.radiance = nonnegative3(c);
               });
      const float a = glm::length(l.edge1), b = glm::length(l.edge2);
      if (a == 0.0f || b == 0.0f) fail(n, "area light edges must be non-zero");
      if (std::fabs(glm::dot(l.edge1, l.edge2)) > 1e-4f * a * b)
        fail(n, "area light edges must be perpendicular");
      scene_.area_lights.push_back(l);
    } else {
      fail(n, "unknown light type '" + type + "' (known: point, area)");
    }
  }

  // ---- meshes ----
  void mesh(const pugi::xml_node& n) {
    check_attributes(n, {"name", "file", "generator", "triangles", "seed"});
    SceneMesh m;
    m.name = required_attribute(n, "name");
    if (mesh_index_.count(m.name)) fail(n, "mesh '" + m.name + "' declared twice");
    const bool file = n.attribute("file"), gen = n.attribute("generator");
    if (file && gen) fail(n, "<mesh> takes either file or generator, not both");
    if (!gen && (n.attribute("triangles") || n.attribute("seed")))
      fail(n, "triangles and seed apply only to a generator mesh");
    if (file) {
      if (n.first_child()) fail(n, "a <mesh> with a file has no children");
      m.mesh = std::make_shared<Mesh>(load_mesh_file(n, required_attribute(n, "file")));
      m.source = std::string("file ") + n.attribute("file").value();
    } else if (gen) {
      m.mesh = std::make_shared<Mesh>(generated_mesh(n));
      m.source = std::string("generator ") + n.attribute("generator").value();
    } else {
      m.mesh = std::make_shared<Mesh>(inline_mesh(n));
      m.source = "inline";
    }
    mesh_index_[m.name] = static_cast<uint32_t>(scene_.meshes.size());
    scene_.meshes.push_back(std::move(m));
  }

  Mesh load_mesh_file(const pugi::xml_node& n, const std::string& file) const {
    namespace fs = std::filesystem;
    const fs::path p = fs::path(file).is_absolute() ? fs::path(file) : fs::path(base_dir_) / file;
    try {
      return read_mesh(p.string());
    } catch (const InputError& e) {
      fail(n, e.what());
    }
  }

  Mesh generated_mesh(const pugi::xml_node& n) const {
    const std::string gen = required_attribute(n, "generator");
    const uint64_t tris = attribute_integer(n, "triangles", 1000, 1, 100'000'000);
    const uint64_t seed = attribute_integer(n, "seed", 1, 0, std::numeric_limits<uint64_t>::max());
    Params params;
    children(n, {"param"}, [&](const pugi::xml_node& c, const std::string&) {
      check_attributes(c, {});
      try {
        params.add(c.child_value());
      } catch (const InputError& e) {
        fail(c, e.what());
      }
    });
    try {
      return generate_mesh(gen, tris, seed, params);
    } catch (const InputError& e) {
      fail(n, e.what());
    }
  }

  Mesh inline_mesh(const pugi::xml_node& n) const {
    Mesh mesh;
    pugi::xml_node tri_node;
    children(n, {"vertices", "triangles"}, [&](const pugi::xml_node& c, const std::string& k) {
      check_attributes(c, {});
      const std::vector<float> v = numbers(c, 0);
      if (v.size() % 3) fail(c, "<" + k + "> needs a multiple of 3 numbers, got " + std::to_string(v.size()));
      if (k == "vertices")
        for (size_t i = 0; i < v.size(); i += 3) mesh.vertices.emplace_back(v[i], v[i + 1], v[i + 2]);
      else
        tri_node = c;
    });
    if (!tri_node) fail(n, "an inline <mesh> needs <vertices> and <triangles> (or give file= or generator=)");
    const std::vector<float> idx = numbers(tri_node, 0);
    for (float f : idx)
      if (f < 0 || f != std::floor(f) || f >= float(mesh.vertices.size()))
        fail(tri_node, "vertex index " + fmt(f) + " out of range (" + std::to_string(mesh.vertices.size()) +
                           " vertices)");
    for (size_t i = 0; i < idx.size(); i += 3)
      mesh.triangles.emplace_back(uint32_t(idx[i]), uint32_t(idx[i + 1]), uint32_t(idx[i + 2]));
    return mesh;
  }

  // ---- transforms and instances ----
  /// Appends one transform element (translate, rotate, scale, matrix) of parent to x.
  void transform_element(const pugi::xml_node& parent, const pugi::xml_node& c, Transform& x) const {
    const std::string k = c.name();
    if (k == "translate") {
      check_attributes(c, {});
      x.then(translate_matrix(vector3(c)));
    } else if (k == "scale") {
      check_attributes(c, {});
      const std::vector<float> v = numbers(c, 0);
      if (v.size() != 1 && v.size() != 3)
        fail(c, "<scale> needs 1 or 3 numbers, got " + std::to_string(v.size()));
      x.then(scale_matrix(v.size() == 1 ? vec3(v[0]) : vec3(v[0], v[1], v[2])));
    } else if (k == "rotate") {
      check_attributes(c, {"axis"});
      x.then(rotate_matrix(rotation_axis(c), number(c)));
    } else if (k == "matrix") {
      check_attributes(c, {});
      const std::vector<float> v = numbers(c, 16);
      glm::mat4 m;
      for (int r = 0; r < 4; ++r)
        for (int col = 0; col < 4; ++col) m[col][r] = v[size_t(r * 4 + col)];  // rows in the file
      x.then(m);
    } else {
      fail(c, "unknown element <" + k + "> in <" + parent.name() + ">");
    }
  }

  /// Appends every element child of n, in document order; an unnamed <transform> child (only when
  /// `nested` is true) contributes its own elements at its place.
  void transform_elements(const pugi::xml_node& n, Transform& x, bool nested) const {
    for (pugi::xml_node c : n.children()) {
      if (c.type() == pugi::node_pcdata &&
          std::string(c.value()).find_first_not_of(" \t\r\n") != std::string::npos)
        fail(c, "unexpected text in <" + std::string(n.name()) + ">");
      if (c.type() != pugi::node_element) continue;
      if (nested && std::string(c.name()) == "transform") {
        check_attributes(c, {});
        transform_elements(c, x, false);
      } else {
        transform_element(n, c, x);
      }
    }
  }

  vec3 rotation_axis(const pugi::xml_node& c) const {
    const std::string a = required_attribute(c, "axis");
    if (a == "X" || a == "x") return {1, 0, 0};
    if (a == "Y" || a == "y") return {0, 1, 0};
    if (a == "Z" || a == "z") return {0, 0, 1};
    std::istringstream is(a);
    vec3 v;
    std::string rest;
    if (!(is >> v.x >> v.y >> v.z) || (is >> rest) || !std::isfinite(glm::dot(v, v)) ||
        glm::dot(v, v) == 0.0f)
      fail(c, "rotate axis '" + a + "' must be X, Y, Z or three numbers (not all zero)");
    return v;
  }

  Transform finished(const pugi::xml_node& n, Transform x) const {
    if (!x.finish()) fail(n, "the transform is singular (zero scale?) or not finite");
    return x;
  }

  void named_transform(const pugi::xml_node& n) {
    check_attributes(n, {"name"});
    const std::string name = required_attribute(n, "name");
    if (transforms_.count(name)) fail(n, "transform '" + name + "' declared twice");
    Transform x;
    transform_elements(n, x, false);
    transforms_[name] = finished(n, x);
  }

  void instance(const pugi::xml_node& n) {
    check_attributes(n, {"mesh", "material", "transform"});
    SceneInstance inst;
    const std::string mesh = required_attribute(n, "mesh");
    if (!mesh_index_.count(mesh)) fail(n, "instance of unknown mesh '" + mesh + "'");
    inst.mesh = mesh_index_.at(mesh);
    if (n.attribute("material")) {
      const std::string mat = required_attribute(n, "material");
      if (!material_index_.count(mat)) fail(n, "unknown material '" + mat + "'");
      inst.material = material_index_.at(mat);
    }
    Transform x;
    if (n.attribute("transform")) {
      const std::string name = required_attribute(n, "transform");
      if (!transforms_.count(name)) fail(n, "unknown transform '" + name + "'");
      x = transforms_.at(name);
    }
    // Inline elements (directly or in an unnamed <transform>) follow the named one in document order.
    transform_elements(n, x, true);
    inst.transform = finished(n, x);
    scene_.instances.push_back(inst);
  }

  const std::string& text_;
  std::string path_, base_dir_;
  Scene scene_;
  std::map<std::string, uint32_t> mesh_index_, material_index_;
  std::map<std::string, Transform> transforms_;
  bool default_replaced_ = false;
};

}  // namespace

Scene parse_scene(const std::string& text, const std::string& path, const std::string& base_dir) {
  return SceneParser(text, path, base_dir).parse();
}

Scene load_scene(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open scene file");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw InputError(path + ": cannot read scene file");
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  return parse_scene(ss.str(), path, parent.empty() ? "." : parent.string());
}

uint64_t Scene::triangle_count() const {
  uint64_t n = 0;
  for (const SceneInstance& inst : instances) n += meshes[inst.mesh].mesh->size();
  return n;
}

AABB Scene::world_bounds() const {
  return bounds.empty() ? compute_world_bounds() : bounds;
}

AABB Scene::compute_world_bounds() const {
  AABB b;
  for (const SceneInstance& inst : instances) {
    const Mesh& m = *meshes[inst.mesh].mesh;
    for (const glm::uvec3& t : m.triangles)
      for (int k = 0; k < 3; ++k) b.extend(inst.transform.point(m.vertices[t[k]]));
  }
  return b;
}

vec3 Scene::hit_normal(const Hit& hit) const {
  const SceneInstance& inst = instances.at(hit.inst);
  const Triangle tri = meshes[inst.mesh].mesh->triangle(hit.prim);
  return inst.transform.normal(glm::cross(tri.v1 - tri.v0, tri.v2 - tri.v0));
}

Mesh flatten_scene(const Scene& scene) {
  Mesh out;
  for (const SceneInstance& inst : scene.instances) {
    const Mesh& m = *scene.meshes[inst.mesh].mesh;
    const auto base = static_cast<uint32_t>(out.vertices.size());
    for (const vec3& v : m.vertices) out.vertices.push_back(inst.transform.point(v));
    for (const glm::uvec3& t : m.triangles) out.triangles.push_back(t + glm::uvec3(base));
  }
  return out;
}

}  // namespace ab
