#include "accel/core/registry.h"

#include <algorithm>

namespace ab {

namespace {
std::vector<AcceleratorInfo>& table() {
  static std::vector<AcceleratorInfo> t;
  return t;
}
/// Creates through one of info's factories (throws UnknownAccelerator saying `missing` when it is empty),
/// then checks the parameters and records the name and the effective configuration.
template <class Factory, class Prims>
std::unique_ptr<Accelerator> create_with(const AcceleratorInfo& info, const Factory& factory, Prims prims,
                                         Params& params, const std::string& missing) {
  if (!factory) throw UnknownAccelerator("accelerator '" + info.name + "' " + missing);
  auto accel = factory(std::move(prims), params);
  params.finish(info.name);
  accel->identify(info.name, params.effective());
  return accel;
}

}  // namespace

Registrar::Registrar(AcceleratorInfo info) {
  auto& t = table();
  t.push_back(std::move(info));
  std::stable_sort(t.begin(), t.end(), [](const AcceleratorInfo& a, const AcceleratorInfo& b) {
    return a.order != b.order ? a.order < b.order : a.name < b.name;
  });
}

const std::vector<AcceleratorInfo>& accelerators() {
  return table();
}

const AcceleratorInfo& find_accelerator(const std::string& name) {
  for (const auto& info : table())
    if (info.name == name) return info;
  std::string known;
  for (const auto& info : table()) known += (known.empty() ? "" : ", ") + info.name;
  throw UnknownAccelerator("unknown accelerator '" + name + "' (known: " + known + ")");
}

std::unique_ptr<Accelerator> make_accelerator(const std::string& name,
                                              std::shared_ptr<const TrianglePrims> prims, Params params) {
  const AcceleratorInfo& info = find_accelerator(name);
  return create_with(info, info.make_for_mesh, std::move(prims), params, "");
}

std::shared_ptr<const TrianglePrims> one_triangle_prims() {
  auto mesh = std::make_shared<Mesh>();
  mesh->vertices = {vec3(0, 0, 0), vec3(1, 0, 0), vec3(0, 1, 0)};
  mesh->triangles = {glm::uvec3(0, 1, 2)};
  return std::make_shared<const TrianglePrims>(std::move(mesh));
}

nlohmann::json default_params(const std::string& name) {
  return make_accelerator(name, one_triangle_prims(), Params())->config();
}

std::unique_ptr<Accelerator> make_instance_accelerator(const std::string& name,
                                                       std::shared_ptr<const InstancePrims> prims,
                                                       Params params) {
  const AcceleratorInfo& info = find_accelerator(name);
  return create_with(info, info.make_for_instances, std::move(prims), params,
                     "cannot serve as the top level of a scene");
}

std::unique_ptr<Accelerator> make_motion_accelerator(const std::string& name,
                                                     std::shared_ptr<const MotionTrianglePrims> prims,
                                                     Params params) {
  const AcceleratorInfo& info = find_accelerator(name);
  return create_with(info, info.make_for_motion_mesh, std::move(prims), params,
                     "cannot hold a moving mesh (motion blur)");
}

}  // namespace ab
