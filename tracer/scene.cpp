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
#include "tracer/gltf.h"

namespace ab {

namespace {

void set_time_range(Scene& scene);

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
    set_time_range(scene_);
    return scene_at(scene_, 0.0f);
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
  /// A finite number given as attribute `name` of n (`def` when absent).
  float attribute_number(const pugi::xml_node& n, const char* name, float def = 0.0f) const {
    const pugi::xml_attribute a = n.attribute(name);
    if (!a) return def;
    const std::string s = a.value();
    const char* b = s.data() + (s.size() && s[0] == '+' ? 1 : 0);
    float v = 0.0f;
    const auto [ptr, ec] = std::from_chars(b, s.data() + s.size(), v);
    if (s.empty() || ec != std::errc() || ptr != s.data() + s.size() || !std::isfinite(v))
      fail(n, "attribute " + std::string(name) + "=\"" + s + "\" must be a finite number");
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
    children(n, {"eye", "lookat", "up", "fov", "aperture", "focus", "shutter"},
             [&](const pugi::xml_node& c, const std::string& k) {
               if (k == "shutter") shutter(c, cam);
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

  /// <shutter open="O" close="C" steps="T"/>: the scene-time interval around the frame (motion blur).
  void shutter(const pugi::xml_node& n, Camera& cam) {
    check_attributes(n, {"open", "close", "steps"});
    cam.shutter_open = attribute_number(n, "open", 0.0f);
    cam.shutter_close = attribute_number(n, "close", 0.0f);
    cam.motion_steps = static_cast<uint32_t>(attribute_integer(n, "steps", cam.motion_steps, 2, 64));
    if (cam.shutter_close < cam.shutter_open) fail(n, "the shutter closes before it opens");
  }

  void render(const pugi::xml_node& n) {
    check_attributes(n, {});
    RenderSettings& r = scene_.render;
    children(n, {"width", "height", "spp", "maxdepth", "diffusedepth", "frames"},
             [&](const pugi::xml_node& c, const std::string& k) {
               if (k == "width") r.width = integer_in(c, 1, 16384);
               if (k == "height") r.height = integer_in(c, 1, 16384);
               if (k == "spp") r.spp = integer_in(c, 1, 65536);
               if (k == "maxdepth") r.max_depth = integer_in(c, 1, 64);
               if (k == "diffusedepth") r.diffuse_depth = integer_in(c, 0, 64);
               if (k == "frames") r.frames = integer_in(c, 1, 1'000'000);
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
    check_attributes(
        n, {"name", "file", "generator", "triangles", "seed", "frames", "count", "first", "start", "end"});
    SceneMesh m;
    m.name = required_attribute(n, "name");
    if (mesh_index_.count(m.name)) fail(n, "mesh '" + m.name + "' declared twice");
    const bool file = n.attribute("file"), gen = n.attribute("generator"), frames = n.attribute("frames");
    if (int(file) + int(gen) + int(frames) > 1) fail(n, "<mesh> takes one of file, generator or frames");
    if (!gen && (n.attribute("triangles") || n.attribute("seed")))
      fail(n, "triangles and seed apply only to a generator mesh");
    if (!frames &&
        (n.attribute("count") || n.attribute("first") || n.attribute("start") || n.attribute("end")))
      fail(n, "count, first, start and end apply only to a frames mesh");
    if (file) {
      children(n, {"deform"}, [](const pugi::xml_node&, const std::string&) {});
      m.base = std::make_shared<Mesh>(load_mesh_file(n, required_attribute(n, "file")));
      m.source = std::string("file ") + n.attribute("file").value();
    } else if (gen) {
      m.base = std::make_shared<Mesh>(generated_mesh(n));
      m.source = std::string("generator ") + n.attribute("generator").value();
    } else if (frames) {
      m.animation = frame_sequence(n);
      m.base = m.animation.frames.front();
      m.source = std::string("frames ") + n.attribute("frames").value();
    } else {
      m.base = std::make_shared<Mesh>(inline_mesh(n));
      m.source = "inline";
    }
    if (const pugi::xml_node d = n.child("deform")) m.animation = deformer(d);
    m.mesh = m.base;
    mesh_index_[m.name] = static_cast<uint32_t>(scene_.meshes.size());
    scene_.meshes.push_back(std::move(m));
  }

  /// The frame files of a `frames` mesh: pattern with one %d (or %0Nd), `count` files numbered from
  /// `first`, all with the first one's triangle count.
  MeshAnimation frame_sequence(const pugi::xml_node& n) const {
    children(n, {}, [](const pugi::xml_node&, const std::string&) {});
    const std::string pattern = required_attribute(n, "frames");
    if (!n.attribute("count")) fail(n, "a frames <mesh> needs attribute 'count'");
    const uint64_t count = attribute_integer(n, "count", 1, 1, 100000);
    const uint64_t first = attribute_integer(n, "first", 0, 0, 1'000'000'000);
    MeshAnimation a;
    a.kind = MeshAnimation::Kind::kFrames;
    a.start = attribute_number(n, "start", 0.0f);
    a.end = attribute_number(n, "end", 1.0f);
    if (!(a.end > a.start)) fail(n, "a frames <mesh> needs end > start");
    for (uint64_t k = 0; k < count; ++k) {
      std::string file;
      if (!frame_file_name(pattern, first + k, file))
        fail(n, "frames=\"" + pattern + "\" needs exactly one %d or %0Nd (and no other %)");
      auto mesh = std::make_shared<const Mesh>(load_mesh_file(n, file));
      if (k > 0 && mesh->size() != a.frames.front()->size())
        fail(n, file + ": frame has " + std::to_string(mesh->size()) + " triangles, the first frame " +
                    std::to_string(a.frames.front()->size()) + " (every frame needs the same triangles)");
      a.frames.push_back(std::move(mesh));
    }
    return a;
  }

  /// A <deform type="wave|twist|explode" start="t0" end="t1"> and its parameters.
  MeshAnimation deformer(const pugi::xml_node& d) const {
    check_attributes(d, {"type", "start", "end"});
    Deformer f;
    const std::string type = required_attribute(d, "type");
    std::set<std::string> allowed;
    if (type == "wave") {
      f.kind = Deformer::Kind::kWave;
      allowed = {"amplitude", "wavelength", "cycles", "axis", "direction"};
    } else if (type == "twist") {
      f.kind = Deformer::Kind::kTwist;
      allowed = {"degrees", "axis"};
    } else if (type == "explode") {
      f.kind = Deformer::Kind::kExplode;
      allowed = {"distance"};
    } else {
      fail(d, "unknown deformer type '" + type + "' (known: wave, twist, explode)");
    }
    f.start = attribute_number(d, "start", 0.0f);
    f.end = attribute_number(d, "end", 1.0f);
    if (!(f.end > f.start)) fail(d, "a <deform> needs end > start");
    const float big = std::numeric_limits<float>::max();
    children(d, allowed, [&](const pugi::xml_node& c, const std::string& k) {
      check_attributes(c, {});
      if (k == "amplitude") f.amplitude = number_in(c, -big, big);
      if (k == "wavelength") f.wavelength = number_in(c, 1e-6f, big);
      if (k == "cycles") f.cycles = number_in(c, -big, big);
      if (k == "degrees") f.degrees = number_in(c, -big, big);
      if (k == "distance") f.distance = number_in(c, -big, big);
      if (k == "axis") f.axis = unit_vector(c);
      if (k == "direction") f.direction = unit_vector(c);
    });
    MeshAnimation a;
    a.kind = MeshAnimation::Kind::kDeformer;
    a.deformer = f;
    return a;
  }

  vec3 unit_vector(const pugi::xml_node& c) const {
    const vec3 v = vector3(c);
    const float len = glm::length(v);
    if (!(len > 0.0f) || !std::isfinite(len)) fail(c, "<" + std::string(c.name()) + "> must not be zero");
    return v / len;
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
    children(n, {"param", "deform"}, [&](const pugi::xml_node& c, const std::string& k) {
      if (k == "deform") return;
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
    children(n, {"vertices", "triangles", "deform"}, [&](const pugi::xml_node& c, const std::string& k) {
      if (k == "deform") return;
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
  /// One transform element (translate, rotate, scale, matrix) of parent as a constant animated element.
  AnimatedElement transform_element(const pugi::xml_node& parent, const pugi::xml_node& c) const {
    using Kind = AnimatedElement::Kind;
    const std::string k = c.name();
    AnimatedElement e;
    e.times = {0.0f};
    if (k == "translate") {
      check_attributes(c, {});
      e.kind = Kind::kTranslate;
      e.values = {numbers(c, 3)};
    } else if (k == "scale") {
      check_attributes(c, {});
      std::vector<float> v = numbers(c, 0);
      if (v.size() != 1 && v.size() != 3)
        fail(c, "<scale> needs 1 or 3 numbers, got " + std::to_string(v.size()));
      if (v.size() == 1) v = {v[0], v[0], v[0]};
      e.kind = Kind::kScale;
      e.values = {v};
    } else if (k == "rotate") {
      check_attributes(c, {"axis"});
      e.kind = Kind::kRotate;
      e.axis = rotation_axis(c);
      e.values = {{number(c)}};
    } else if (k == "matrix") {
      check_attributes(c, {});
      const std::vector<float> v = numbers(c, 16);
      std::vector<float> m(16);
      for (int r = 0; r < 4; ++r)
        for (int col = 0; col < 4; ++col)
          m[size_t(col * 4 + r)] = v[size_t(r * 4 + col)];  // rows in the file
      e.kind = Kind::kMatrix;
      e.values = {m};
    } else {
      fail(c, "unknown element <" + k + "> in <" + parent.name() + ">");
    }
    return e;
  }

  /// The elements of one <keyframe> (plain elements only) and its time.
  std::vector<AnimatedElement> keyframe(const pugi::xml_node& k, float& time) const {
    check_attributes(k, {"time"});
    const pugi::xml_attribute a = k.attribute("time");
    if (!a) fail(k, "<keyframe> needs attribute 'time'");
    time = attribute_number(k, "time");
    std::vector<AnimatedElement> out;
    for (pugi::xml_node c : k.children()) {
      if (c.type() == pugi::node_pcdata &&
          std::string(c.value()).find_first_not_of(" \t\r\n") != std::string::npos)
        fail(c, "unexpected text in <keyframe>");
      if (c.type() == pugi::node_element) {
        out.push_back(transform_element(k, c));
        out.back().times = {time};
      }
    }
    return out;
  }

  /// A run of consecutive <keyframe> siblings starting at `first` as one animated segment: every keyframe
  /// has the same element sequence (kinds, and axes of rotations), the times strictly increase; element
  /// i takes its values from the i-th element of each keyframe. Returns the node after the run.
  pugi::xml_node keyframes(pugi::xml_node first, AnimatedTransform& x) const {
    std::vector<AnimatedElement> merged;
    pugi::xml_node c = first;
    for (; c; c = c.next_sibling()) {
      if (c.type() == pugi::node_pcdata &&
          std::string(c.value()).find_first_not_of(" \t\r\n") == std::string::npos)
        continue;
      if (c.type() == pugi::node_comment) continue;
      if (c.type() != pugi::node_element || std::string(c.name()) != "keyframe") break;
      float time = 0.0f;
      std::vector<AnimatedElement> elements = keyframe(c, time);
      if (merged.empty()) {
        merged = std::move(elements);
        if (merged.empty()) fail(c, "a <keyframe> needs at least one element");
        continue;
      }
      same_sequence(c, merged, elements);
      if (!(time > merged.front().times.back()))
        fail(c, "keyframe times must increase: " + fmt(time) + " after " + fmt(merged.front().times.back()));
      for (size_t i = 0; i < merged.size(); ++i) {
        merged[i].times.push_back(time);
        merged[i].values.push_back(elements[i].values.front());
      }
    }
    for (AnimatedElement& e : merged) x.elements.push_back(std::move(e));
    return c;
  }

  /// Fails unless `next` has the element sequence of `merged` (kinds, rotation axes).
  void same_sequence(const pugi::xml_node& k, const std::vector<AnimatedElement>& merged,
                     const std::vector<AnimatedElement>& next) const {
    if (next.size() != merged.size())
      fail(k, "keyframes must have the same elements: this one has " + std::to_string(next.size()) +
                  ", the first " + std::to_string(merged.size()));
    for (size_t i = 0; i < next.size(); ++i) {
      if (next[i].kind != merged[i].kind)
        fail(k, "keyframes must have the same elements in the same order: element " + std::to_string(i + 1) +
                    " differs from the first keyframe's");
      if (next[i].kind == AnimatedElement::Kind::kRotate && next[i].axis != merged[i].axis)
        fail(k, "keyframes must rotate about the same axis: element " + std::to_string(i + 1) +
                    " differs from the first keyframe's");
    }
  }

  /// Appends every element child of n, in document order; a run of <keyframe> children is one animated
  /// segment at its place; an unnamed <transform> child (only when `nested` is true) contributes its own
  /// elements at its place.
  void transform_elements(const pugi::xml_node& n, AnimatedTransform& x, bool nested) const {
    for (pugi::xml_node c = n.first_child(); c;) {
      if (c.type() == pugi::node_pcdata &&
          std::string(c.value()).find_first_not_of(" \t\r\n") != std::string::npos)
        fail(c, "unexpected text in <" + std::string(n.name()) + ">");
      if (c.type() != pugi::node_element) {
        c = c.next_sibling();
        continue;
      }
      if (std::string(c.name()) == "keyframe") {
        c = keyframes(c, x);
        continue;
      }
      if (nested && std::string(c.name()) == "transform") {
        check_attributes(c, {});
        transform_elements(c, x, false);
      } else {
        x.elements.push_back(transform_element(n, c));
      }
      c = c.next_sibling();
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

  /// Fails when the transform is singular at any of its key times.
  void check_regular(const pugi::xml_node& n, const AnimatedTransform& x) const {
    std::set<float> times = {0.0f};
    for (const AnimatedElement& e : x.elements) times.insert(e.times.begin(), e.times.end());
    Transform t;
    for (float time : times)
      if (!x.evaluate(time, t))
        fail(n, "the transform is singular (zero scale?) or not finite" +
                    (x.animated() ? " at time " + fmt(time) : std::string()));
  }

  void named_transform(const pugi::xml_node& n) {
    check_attributes(n, {"name"});
    const std::string name = required_attribute(n, "name");
    if (transforms_.count(name)) fail(n, "transform '" + name + "' declared twice");
    AnimatedTransform x;
    transform_elements(n, x, false);
    check_regular(n, x);
    transforms_[name] = x;
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
    AnimatedTransform x;
    if (n.attribute("transform")) {
      const std::string name = required_attribute(n, "transform");
      if (!transforms_.count(name)) fail(n, "unknown transform '" + name + "'");
      x = transforms_.at(name);
    }
    // Inline elements (directly or in an unnamed <transform>) follow the named one in document order.
    transform_elements(n, x, true);
    check_regular(n, x);
    inst.animation = std::move(x);
    scene_.instances.push_back(std::move(inst));
  }

  const std::string& text_;
  std::string path_, base_dir_;
  Scene scene_;
  std::map<std::string, uint32_t> mesh_index_, material_index_;
  std::map<std::string, AnimatedTransform> transforms_;
  bool default_replaced_ = false;
};

/// The scene-time range of every animated transform and mesh.
void set_time_range(Scene& scene) {
  bool any = false;
  const auto add = [&](float first, float last) {
    scene.time_first = any ? std::min(scene.time_first, first) : first;
    scene.time_last = any ? std::max(scene.time_last, last) : last;
    any = true;
  };
  float first = 0.0f, last = 0.0f;
  for (const SceneInstance& inst : scene.instances)
    if (inst.animation.animated()) {
      inst.animation.time_range(first, last);
      add(first, last);
    }
  for (const SceneMesh& m : scene.meshes)
    if (m.animation.animated()) {
      m.animation.time_range(first, last);
      add(first, last);
    }
}

}  // namespace

Scene scene_at(const Scene& scene, float u) {
  Scene out = scene;
  out.time = u;
  const float t = scene.time_first + u * (scene.time_last - scene.time_first);
  for (SceneMesh& m : out.meshes)
    if (m.animation.animated()) m.mesh = m.animation.at(m.base, t);
  for (size_t i = 0; i < out.instances.size(); ++i)
    if (!out.instances[i].animation.evaluate(t, out.instances[i].transform))
      throw InputError(scene.path + ": the transform of instance " + std::to_string(i) +
                       " is singular or not finite at time " + std::to_string(u));
  out.bounds = out.compute_world_bounds();
  return out;
}

float frame_time(uint64_t frame, uint64_t frames) {
  if (frames == 0) throw InputError("--frames must be at least 1");
  if (frame >= frames)
    throw InputError("--frame " + std::to_string(frame) + " is out of range: " + std::to_string(frames) +
                     " frames are 0.." + std::to_string(frames - 1));
  return frames == 1 ? 0.0f : float(double(frame) / double(frames - 1));
}

Scene parse_scene(const std::string& text, const std::string& path, const std::string& base_dir) {
  return SceneParser(text, path, base_dir).parse();
}

Scene load_scene(const std::string& path) {
  if (is_gltf_path(path)) return load_gltf_scene(path);
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
