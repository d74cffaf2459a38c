#include "tracer/gltf.h"

#include <tiny_gltf.h>  // Debian's libtinygltf: the implementation lives in the shared library

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <set>

#include "accel/core/error.h"
#include "datasets/atomic_file.h"

namespace ab {

bool is_gltf_path(const std::string& path) {
  const size_t dot = path.rfind('.');
  std::string ext = dot == std::string::npos ? std::string() : path.substr(dot);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext == ".gltf" || ext == ".glb";
}

namespace {

/// tinygltf's messages span lines: one line, joined by "; ".
std::string one_line(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '\n' || c == '\r') {
      if (!out.empty() && out.back() != ' ') out += "; ";
    } else {
      out += c;
    }
  }
  while (!out.empty() && (out.back() == ' ' || out.back() == ';')) out.pop_back();
  return out;
}

/// Images are not needed for geometry: accept them without decoding.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int,
                void*) {
  return true;
}

/// The validated bytes of one accessor: element e, component k is at data + e * stride + k * size.
struct AccessorView {
  const unsigned char* data = nullptr;
  size_t stride = 0;
  size_t count = 0;
  int components = 0;
  int component_type = 0;
};

/// Turns a tinygltf Model into a Scene, checking every index, accessor and range before use.
class GltfReader {
 public:
  GltfReader(const tinygltf::Model& model, std::string path) : m_(model), path_(std::move(path)) {}

  Scene read() {
    scene_.path = path_;
    Material fallback;
    fallback.name = "default";
    scene_.materials.push_back(fallback);
    for (size_t i = 0; i < m_.meshes.size(); ++i) scene_.meshes.push_back(mesh(i));
    node_transforms();
    animations();
    for (int root : roots()) instances(root, AnimatedTransform{}, 0);
    if (scene_.instances.empty()) fail("the scene has no node with a mesh");
    return std::move(scene_);
  }

 private:
  [[noreturn]] void fail(const std::string& msg) const { throw InputError(path_ + ": " + msg); }

  template <class T>
  const T& at(const std::vector<T>& v, int index, const std::string& what) const {
    if (index < 0 || size_t(index) >= v.size())
      fail(what + " " + std::to_string(index) + " does not exist (" + std::to_string(v.size()) +
           " declared)");
    return v[size_t(index)];
  }

  AccessorView accessor(int index, const std::string& what, std::set<int> types,
                        std::set<int> components) const;
  std::vector<float> floats(int index, const std::string& what, int type) const;
  std::vector<uint32_t> indices(int index, const std::string& what, size_t vertices) const;
  SceneMesh mesh(size_t i) const;
  void primitive(const tinygltf::Primitive& p, const std::string& what, Mesh& out) const;
  void node_transforms();
  void animations();
  void channel(const tinygltf::Animation& a, const tinygltf::AnimationChannel& c, const std::string& what);
  std::vector<int> roots() const;
  void instances(int node, AnimatedTransform parent, int depth);

  const tinygltf::Model& m_;
  std::string path_;
  Scene scene_;
  /// Per node: its local transform (T, R, S elements, or one matrix element).
  std::vector<AnimatedTransform> local_;
  std::set<std::pair<int, std::string>> animated_;  ///< (node, path) pairs a channel drives
  std::vector<bool> visited_;
};

AccessorView GltfReader::accessor(int index, const std::string& what, std::set<int> types,
                                  std::set<int> components) const {
  const tinygltf::Accessor& a = at(m_.accessors, index, what + ": accessor");
  const std::string name = what + ": accessor " + std::to_string(index);
  if (a.sparse.isSparse) fail(name + " is sparse (not supported)");
  if (!types.count(a.type)) fail(name + " has the wrong type");
  if (!components.count(a.componentType)) fail(name + " has the wrong component type");
  const tinygltf::BufferView& bv = at(m_.bufferViews, a.bufferView, name + ": bufferView");
  const tinygltf::Buffer& buf = at(m_.buffers, bv.buffer, name + ": buffer");
  if (bv.byteOffset > buf.data.size() || bv.byteLength > buf.data.size() - bv.byteOffset)
    fail(name + ": its bufferView lies outside its buffer");
  AccessorView v;
  v.components = tinygltf::GetNumComponentsInType(uint32_t(a.type));
  const int size = tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType));
  if (v.components <= 0 || size <= 0) fail(name + " has an unknown type");
  const size_t element = size_t(v.components) * size_t(size);
  v.stride = bv.byteStride ? bv.byteStride : element;
  v.count = a.count;
  v.component_type = a.componentType;
  if (v.stride < element) fail(name + ": byteStride is smaller than an element");
  if (a.count > 0 &&
      (a.byteOffset > bv.byteLength || a.count - 1 > (bv.byteLength - a.byteOffset) / v.stride ||
       a.byteOffset + (a.count - 1) * v.stride + element > bv.byteLength))
    fail(name + ": " + std::to_string(a.count) + " elements do not fit in its bufferView");
  v.data = buf.data.data() + bv.byteOffset + a.byteOffset;
  return v;
}

std::vector<float> GltfReader::floats(int index, const std::string& what, int type) const {
  const AccessorView v = accessor(index, what, {type}, {TINYGLTF_COMPONENT_TYPE_FLOAT});
  std::vector<float> out(v.count * size_t(v.components));
  for (size_t e = 0; e < v.count; ++e)
    for (int k = 0; k < v.components; ++k) {
      float x;
      std::memcpy(&x, v.data + e * v.stride + size_t(k) * 4, 4);
      if (!std::isfinite(x))
        fail(what + ": accessor " + std::to_string(index) + " holds a value that is not finite");
      out[e * size_t(v.components) + size_t(k)] = x;
    }
  return out;
}

std::vector<uint32_t> GltfReader::indices(int index, const std::string& what, size_t vertices) const {
  const AccessorView v =
      accessor(index, what + " indices", {TINYGLTF_TYPE_SCALAR},
               {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT});
  std::vector<uint32_t> out(v.count);
  for (size_t e = 0; e < v.count; ++e) {
    const unsigned char* p = v.data + e * v.stride;
    uint32_t x = 0;
    if (v.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) {
      x = *p;
    } else if (v.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) {
      uint16_t s;
      std::memcpy(&s, p, 2);
      x = s;
    } else {
      std::memcpy(&x, p, 4);
    }
    if (x >= vertices)
      fail(what + ": index " + std::to_string(x) + " out of range (" + std::to_string(vertices) +
           " vertices)");
    out[e] = x;
  }
  return out;
}

/// One primitive's triangles appended to out: TRIANGLES, TRIANGLE_STRIP and TRIANGLE_FAN in index order
/// (strips alternate winding as the glTF spec says); points and lines add no triangles.
void GltfReader::primitive(const tinygltf::Primitive& p, const std::string& what, Mesh& out) const {
  const int mode = p.mode < 0 ? TINYGLTF_MODE_TRIANGLES : p.mode;
  if (mode < TINYGLTF_MODE_POINTS || mode > TINYGLTF_MODE_TRIANGLE_FAN)
    fail(what + ": unknown mode " + std::to_string(mode));
  if (mode < TINYGLTF_MODE_TRIANGLES) return;
  const auto pos = p.attributes.find("POSITION");
  if (pos == p.attributes.end()) fail(what + " has no POSITION");
  const std::vector<float> v = floats(pos->second, what + " POSITION", TINYGLTF_TYPE_VEC3);
  const size_t n = v.size() / 3;
  std::vector<uint32_t> idx;
  if (p.indices >= 0) {
    idx = indices(p.indices, what, n);
  } else {
    idx.resize(n);
    for (size_t i = 0; i < n; ++i) idx[i] = uint32_t(i);
  }
  const auto base = uint32_t(out.vertices.size());
  for (size_t i = 0; i < n; ++i) out.vertices.emplace_back(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
  const auto add = [&](uint32_t a, uint32_t b, uint32_t c) {
    out.triangles.emplace_back(base + a, base + b, base + c);
  };
  if (mode == TINYGLTF_MODE_TRIANGLES) {
    if (idx.size() % 3) fail(what + ": " + std::to_string(idx.size()) + " indices are not a multiple of 3");
    for (size_t i = 0; i + 2 < idx.size(); i += 3) add(idx[i], idx[i + 1], idx[i + 2]);
  } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
    for (size_t i = 0; i + 2 < idx.size(); ++i)
      i % 2 ? add(idx[i + 1], idx[i], idx[i + 2]) : add(idx[i], idx[i + 1], idx[i + 2]);
  } else {
    for (size_t i = 1; i + 1 < idx.size(); ++i) add(idx[0], idx[i], idx[i + 1]);
  }
}

SceneMesh GltfReader::mesh(size_t i) const {
  const tinygltf::Mesh& gm = m_.meshes[i];
  SceneMesh sm;
  sm.name = gm.name.empty() ? "mesh" + std::to_string(i) : gm.name;
  sm.source = "gltf mesh " + std::to_string(i);
  Mesh mesh;
  for (size_t j = 0; j < gm.primitives.size(); ++j)
    primitive(gm.primitives[j], "mesh " + std::to_string(i) + " primitive " + std::to_string(j), mesh);
  if (mesh.vertices.size() > std::numeric_limits<uint32_t>::max())
    fail("mesh " + std::to_string(i) + " is too large");
  sm.base = sm.mesh = std::make_shared<const Mesh>(std::move(mesh));
  return sm;
}

AnimatedElement constant(AnimatedElement::Kind kind, std::vector<float> values) {
  AnimatedElement e;
  e.kind = kind;
  e.times = {0.0f};
  e.values = {std::move(values)};
  return e;
}

/// Each node's local transform: its matrix (column-major, as glTF stores it), or T * R * S.
void GltfReader::node_transforms() {
  using Kind = AnimatedElement::Kind;
  for (size_t i = 0; i < m_.nodes.size(); ++i) {
    const tinygltf::Node& n = m_.nodes[i];
    const std::string what = "node " + std::to_string(i);
    AnimatedTransform x;
    const auto values = [&](const std::vector<double>& v, size_t count, std::vector<float> def,
                            const char* name) {
      if (v.empty()) return def;
      if (v.size() != count) fail(what + ": " + name + " needs " + std::to_string(count) + " numbers");
      std::vector<float> out(v.begin(), v.end());
      for (float f : out)
        if (!std::isfinite(f)) fail(what + ": " + name + " is not finite");
      return out;
    };
    if (!n.matrix.empty()) {
      x.elements.push_back(constant(Kind::kMatrix, values(n.matrix, 16, {}, "matrix")));
    } else {
      x.elements.push_back(constant(Kind::kTranslate, values(n.translation, 3, {0, 0, 0}, "translation")));
      x.elements.push_back(constant(Kind::kQuaternion, values(n.rotation, 4, {0, 0, 0, 1}, "rotation")));
      x.elements.push_back(constant(Kind::kScale, values(n.scale, 3, {1, 1, 1}, "scale")));
    }
    local_.push_back(std::move(x));
  }
}

void GltfReader::animations() {
  for (size_t a = 0; a < m_.animations.size(); ++a)
    for (size_t c = 0; c < m_.animations[a].channels.size(); ++c)
      channel(m_.animations[a], m_.animations[a].channels[c],
              "animation " + std::to_string(a) + " channel " + std::to_string(c));
}

/// A channel's sampler becomes the keys of the node's T, R or S element (LINEAR: lerp, slerp for
/// rotations, as the glTF 2.0 spec says; STEP; CUBICSPLINE read as LINEAR through its values).
void GltfReader::channel(const tinygltf::Animation& a, const tinygltf::AnimationChannel& c,
                         const std::string& what) {
  const std::string& target = c.target_path;
  if (target != "translation" && target != "rotation" && target != "scale") return;  // weights: no morphing
  const tinygltf::AnimationSampler& s = at(a.samplers, c.sampler, what + ": sampler");
  const tinygltf::Node& node = at(m_.nodes, c.target_node, what + ": node");
  if (!node.matrix.empty())
    fail(what + ": node " + std::to_string(c.target_node) + " has a matrix and is animated");
  if (!animated_.insert({c.target_node, target}).second)
    fail(what + ": a second channel animates the " + target + " of node " + std::to_string(c.target_node));
  const std::vector<float> times = floats(s.input, what + " input", TINYGLTF_TYPE_SCALAR);
  if (times.empty()) fail(what + ": the input has no keys");
  for (size_t k = 1; k < times.size(); ++k)
    if (!(times[k] > times[k - 1])) fail(what + ": input times must increase");
  const int slot = target == "translation" ? 0 : (target == "rotation" ? 1 : 2);
  const int type = slot == 1 ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3;
  const std::vector<float> out = floats(s.output, what + " output", type);
  const size_t width = slot == 1 ? 4 : 3;
  const bool cubic = s.interpolation == "CUBICSPLINE";
  if (!cubic && s.interpolation != "LINEAR" && s.interpolation != "STEP")
    fail(what + ": unknown interpolation '" + s.interpolation + "'");
  const size_t per_key = cubic ? 3 : 1;  // cubic: in-tangent, value, out-tangent
  if (out.size() != times.size() * width * per_key)
    fail(what + ": " + std::to_string(out.size() / width) + " output values for " +
         std::to_string(times.size()) + " keys");
  AnimatedElement& e = local_[size_t(c.target_node)].elements[size_t(slot)];
  e.times = times;
  e.values.clear();
  e.interpolation = s.interpolation == "STEP" ? Interpolation::kStep : Interpolation::kLinear;
  for (size_t k = 0; k < times.size(); ++k) {
    const size_t first = (k * per_key + (cubic ? 1 : 0)) * width;
    e.values.emplace_back(out.begin() + ptrdiff_t(first), out.begin() + ptrdiff_t(first + width));
  }
}

std::vector<int> GltfReader::roots() const {
  if (!m_.scenes.empty()) {
    const int s = m_.defaultScene >= 0 ? m_.defaultScene : 0;
    return at(m_.scenes, s, "scene").nodes;
  }
  std::vector<bool> child(m_.nodes.size(), false);
  for (const tinygltf::Node& n : m_.nodes)
    for (int c : n.children)
      if (c >= 0 && size_t(c) < child.size()) child[size_t(c)] = true;
  std::vector<int> out;
  for (size_t i = 0; i < child.size(); ++i)
    if (!child[i]) out.push_back(int(i));
  return out;
}

/// Depth-first, children in order: each node with a mesh is an instance under the composed transform
/// of its ancestors and itself (world = parent world * local).
void GltfReader::instances(int node, AnimatedTransform parent, int depth) {
  const tinygltf::Node& n = at(m_.nodes, node, "node");
  if (depth > 256) fail("the node hierarchy is deeper than 256 levels");
  visited_.resize(m_.nodes.size(), false);
  if (visited_[size_t(node)])
    fail("node " + std::to_string(node) + " is reached twice (a cycle or a shared child)");
  visited_[size_t(node)] = true;
  parent.then(local_[size_t(node)]);
  if (n.mesh >= 0 || n.mesh < -1) {
    at(m_.meshes, n.mesh, "node " + std::to_string(node) + ": mesh");
    SceneInstance inst;
    inst.mesh = uint32_t(n.mesh);
    inst.animation = parent;
    scene_.instances.push_back(std::move(inst));
  }
  for (int c : n.children) instances(c, parent, depth + 1);
}

/// A camera that sees the whole animation from the front and above, a light beside it.
void default_view(Scene& scene) {
  AABB b;
  for (float u : {0.0f, 0.5f, 1.0f}) b.extend(scene_at(scene, u).world_bounds());
  const vec3 c = b.center();
  const float r = std::max(0.5f * glm::length(b.extent()), 1e-3f);
  scene.camera.eye = c + vec3(0.0f, 0.35f, 1.0f) * (2.4f * r);
  scene.camera.look_at = c;
  scene.camera.up = vec3(0, 1, 0);
  scene.camera.fov_degrees = 45.0f;
  PointLight light;
  light.position = c + vec3(-1.0f, 2.0f, 1.5f) * (2.0f * r);
  light.intensity = vec3(12.0f * r * r);
  scene.point_lights.push_back(light);
  scene.render.ambient = vec3(0.08f);
}

/// The first and last key time over all instances' elements.
void time_range(Scene& scene) {
  bool any = false;
  for (const SceneInstance& inst : scene.instances) {
    if (!inst.animation.animated()) continue;
    float first = 0.0f, last = 0.0f;
    inst.animation.time_range(first, last);
    scene.time_first = any ? std::min(scene.time_first, first) : first;
    scene.time_last = any ? std::max(scene.time_last, last) : last;
    any = true;
  }
  if (scene.animated())
    scene.render.frames = std::max(2, int(std::lround(24.0f * (scene.time_last - scene.time_first))) + 1);
}

}  // namespace

Scene load_gltf_scene(const std::string& path) {
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(skip_image, nullptr);
  tinygltf::Model model;
  std::string err, warn;
  const bool binary = path.size() >= 4 && is_gltf_path(path) && std::tolower(path.back()) == 'b';
  const bool ok = binary ? loader.LoadBinaryFromFile(&model, &err, &warn, path)
                         : loader.LoadASCIIFromFile(&model, &err, &warn, path);
  // tinygltf may return true with a message in err after dropping a malformed part (a primitive without
  // attributes): that would shift triangle ids, so any message is an error.
  if (!ok || !err.empty())
    throw InputError(path +
                     ": malformed glTF: " + (err.empty() ? std::string("unknown error") : one_line(err)));
  Scene scene = GltfReader(model, path).read();
  time_range(scene);
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    Transform t;
    for (float u : {0.0f, 1.0f})
      if (!scene.instances[i].animation.evaluate(scene.time_first + u * (scene.time_last - scene.time_first),
                                                 t))
        throw InputError(path + ": node transform of instance " + std::to_string(i) +
                         " is singular or not finite");
  }
  default_view(scene);
  return scene_at(scene, 0.0f);
}

namespace {

/// Builds a tinygltf Model from a scene: one buffer, views and accessors appended as needed.
class GltfWriter {
 public:
  explicit GltfWriter(const Scene& scene) : scene_(scene) {
    model_.asset.version = "2.0";
    model_.asset.generator = "accelbench";
    model_.buffers.resize(1);
    model_.animations.resize(1);
    model_.animations[0].name = "animation";
    model_.scenes.resize(1);
    model_.defaultScene = 0;
  }

  tinygltf::Model write() {
    for (const SceneMesh& m : scene_.meshes) {
      if (m.animation.animated())
        throw InputError(scene_.path + ": mesh '" + m.name +
                         "' deforms; glTF export keeps rigid animation only");
      mesh(*m.base, m.name);
    }
    for (size_t i = 0; i < scene_.instances.size(); ++i) instance(scene_.instances[i], i);
    if (model_.animations[0].channels.empty()) model_.animations.clear();
    return std::move(model_);
  }

 private:
  int view(const void* data, size_t bytes, int target) {
    std::vector<unsigned char>& buf = model_.buffers[0].data;
    while (buf.size() % 4) buf.push_back(0);
    tinygltf::BufferView bv;
    bv.buffer = 0;
    bv.byteOffset = buf.size();
    bv.byteLength = bytes;
    bv.target = target;
    const auto* p = static_cast<const unsigned char*>(data);
    buf.insert(buf.end(), p, p + bytes);
    model_.bufferViews.push_back(bv);
    return int(model_.bufferViews.size() - 1);
  }

  int accessor(const void* data, size_t count, int type, int component, int target,
               std::vector<double> lo = {}, std::vector<double> hi = {}) {
    const size_t bytes = count * size_t(tinygltf::GetNumComponentsInType(uint32_t(type))) * 4;
    tinygltf::Accessor a;
    a.bufferView = view(data, bytes, target);
    a.componentType = component;
    a.type = type;
    a.count = count;
    a.minValues = std::move(lo);
    a.maxValues = std::move(hi);
    model_.accessors.push_back(a);
    return int(model_.accessors.size() - 1);
  }

  void mesh(const Mesh& m, const std::string& name) {
    AABB b;
    for (const vec3& v : m.vertices) b.extend(v);
    if (m.vertices.empty()) b.extend(vec3(0.0f));
    tinygltf::Primitive p;
    p.mode = TINYGLTF_MODE_TRIANGLES;
    p.attributes["POSITION"] =
        accessor(m.vertices.data(), m.vertices.size(), TINYGLTF_TYPE_VEC3, TINYGLTF_COMPONENT_TYPE_FLOAT,
                 TINYGLTF_TARGET_ARRAY_BUFFER, {b.lo.x, b.lo.y, b.lo.z}, {b.hi.x, b.hi.y, b.hi.z});
    p.indices = accessor(m.triangles.data(), m.triangles.size() * 3, TINYGLTF_TYPE_SCALAR,
                         TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    tinygltf::Mesh gm;
    gm.name = name;
    gm.primitives.push_back(p);
    model_.meshes.push_back(gm);
  }

  /// The quaternion keys of a rotation about one axis, subdivided so consecutive keys are at most 90
  /// degrees apart (slerp then turns at the angles' own constant rate).
  static AnimatedElement as_quaternion(const AnimatedElement& e) {
    AnimatedElement q;
    q.kind = AnimatedElement::Kind::kQuaternion;
    q.interpolation = e.interpolation;
    const vec3 axis = glm::normalize(e.axis);
    const auto add = [&](float t, float degrees) {
      const float h = 0.5f * degrees * 3.14159265358979f / 180.0f;
      q.times.push_back(t);
      q.values.push_back({axis.x * std::sin(h), axis.y * std::sin(h), axis.z * std::sin(h), std::cos(h)});
    };
    for (size_t k = 0; k < e.times.size(); ++k) {
      if (k > 0 && e.interpolation == Interpolation::kLinear) {
        const float a = e.values[k - 1][0], b = e.values[k][0];
        const int steps = int(std::ceil(std::fabs(b - a) / 90.0f));
        for (int j = 1; j < steps; ++j) {
          const float s = float(j) / float(steps);
          add(e.times[k - 1] + s * (e.times[k] - e.times[k - 1]), a + s * (b - a));
        }
      }
      add(e.times[k], e.values[k][0]);
    }
    return q;
  }

  /// One node for one element; a keyed element also gets a sampler and a channel.
  int element_node(const AnimatedElement& in) {
    using Kind = AnimatedElement::Kind;
    const AnimatedElement e = in.kind == Kind::kRotate ? as_quaternion(in) : in;
    tinygltf::Node n;
    const std::vector<double> v0(e.values.front().begin(), e.values.front().end());
    if (e.kind == Kind::kMatrix) {
      if (e.times.size() > 1)
        throw InputError(scene_.path + ": an animated <matrix> cannot be written as glTF");
      n.matrix = v0;
    }
    const char* path = e.kind == Kind::kTranslate ? "translation"
                       : e.kind == Kind::kScale   ? "scale"
                                                  : "rotation";
    if (e.kind == Kind::kTranslate) n.translation = v0;
    if (e.kind == Kind::kScale) n.scale = v0;
    if (e.kind == Kind::kQuaternion) n.rotation = v0;
    model_.nodes.push_back(n);
    const int index = int(model_.nodes.size() - 1);
    if (e.times.size() > 1) channel(e, index, path);
    return index;
  }

  void channel(const AnimatedElement& e, int node, const char* path) {
    std::vector<float> values;
    for (const std::vector<float>& v : e.values) values.insert(values.end(), v.begin(), v.end());
    tinygltf::AnimationSampler s;
    s.input = accessor(e.times.data(), e.times.size(), TINYGLTF_TYPE_SCALAR, TINYGLTF_COMPONENT_TYPE_FLOAT, 0,
                       {e.times.front()}, {e.times.back()});
    s.output =
        accessor(values.data(), e.values.size(),
                 e.kind == AnimatedElement::Kind::kQuaternion ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3,
                 TINYGLTF_COMPONENT_TYPE_FLOAT, 0);
    s.interpolation = e.interpolation == Interpolation::kStep ? "STEP" : "LINEAR";
    tinygltf::Animation& a = model_.animations[0];
    a.samplers.push_back(s);
    tinygltf::AnimationChannel c;
    c.sampler = int(a.samplers.size() - 1);
    c.target_node = node;
    c.target_path = path;
    a.channels.push_back(c);
  }

  /// A chain of element nodes, the last one holding the mesh (an instance without elements: one node).
  void instance(const SceneInstance& inst, size_t i) {
    int parent = -1;
    for (const AnimatedElement& e : inst.animation.elements) {
      const int node = element_node(e);
      (parent < 0 ? model_.scenes[0].nodes : model_.nodes[size_t(parent)].children).push_back(node);
      parent = node;
    }
    tinygltf::Node leaf;
    leaf.name = "instance " + std::to_string(i);
    leaf.mesh = int(inst.mesh);
    model_.nodes.push_back(leaf);
    const int node = int(model_.nodes.size() - 1);
    (parent < 0 ? model_.scenes[0].nodes : model_.nodes[size_t(parent)].children).push_back(node);
  }

  const Scene& scene_;
  tinygltf::Model model_;
};

}  // namespace

void write_gltf_scene(const Scene& scene, const std::string& path) {
  tinygltf::Model model = GltfWriter(scene).write();
  const bool binary = is_gltf_path(path) && std::tolower(path.back()) == 'b';
  if (!is_gltf_path(path)) throw InputError(path + ": a glTF file name ends in .gltf or .glb");
  write_file_atomically(path, [&](std::ostream& out) {
    tinygltf::TinyGLTF writer;
    if (!writer.WriteGltfSceneToStream(&model, out, !binary, binary))
      throw InputError(path + ": cannot write glTF");
  });
}

}  // namespace ab
