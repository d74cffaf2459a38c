// Accelerator names -> factories. Unknown names and unknown parameters are errors.
#pragma once

#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "accel/core/accelerator.h"
#include "accel/core/concepts.h"
#include "accel/core/error.h"
#include "accel/core/instances.h"
#include "accel/core/motion_prims.h"
#include "accel/core/params.h"
#include "accel/core/primitives.h"

namespace ab {

/// An unknown accelerator name; the message names it and lists the known ones.
struct UnknownAccelerator : InputError {
  using InputError::InputError;
};

/// Factory over a triangle set. It reads its Config from params (Params::get_*).
using MeshFactory =
    std::function<std::unique_ptr<Accelerator>(std::shared_ptr<const TrianglePrims>, Params&)>;
/// Factory over an instance set (the top level of a scene).
using InstanceFactory =
    std::function<std::unique_ptr<Accelerator>(std::shared_ptr<const InstancePrims>, Params&)>;

/// Factory over a moving triangle set (motion blur: a deforming mesh's time steps).
using MotionMeshFactory =
    std::function<std::unique_ptr<Accelerator>(std::shared_ptr<const MotionTrianglePrims>, Params&)>;

/// One registered accelerator.
struct AcceleratorInfo {
  std::string name;
  std::string description;
  int order = 100;  ///< position in listings (smaller first)
  MeshFactory make_for_mesh;
  InstanceFactory make_for_instances;      ///< empty when the structure cannot be a top level
  MotionMeshFactory make_for_motion_mesh;  ///< empty when the structure cannot hold a moving mesh
  bool is_reference = false;               ///< brute and embree: not a structure of the project's own
};

/// Registers at static-initialization time: `static const Registrar reg{{"name", "...", 10, f, g}};`
struct Registrar {
  explicit Registrar(AcceleratorInfo info);
};

/// One triangle as a primitive set: enough to create (not build) any structure and read its parameters.
std::shared_ptr<const TrianglePrims> one_triangle_prims();

/// The effective parameters of `name` with every default (the structure created over one triangle).
nlohmann::json default_params(const std::string& name);

/// Every registered accelerator, in listing order.
const std::vector<AcceleratorInfo>& accelerators();
/// The accelerator called name; throws UnknownAccelerator.
const AcceleratorInfo& find_accelerator(const std::string& name);
/// Creates (does not build) an accelerator over triangles; throws UnknownAccelerator or ParamError
/// (unknown or bad parameters).
std::unique_ptr<Accelerator> make_accelerator(const std::string& name,
                                              std::shared_ptr<const TrianglePrims> prims, Params params);
/// Creates (does not build) a top-level accelerator over instances.
std::unique_ptr<Accelerator> make_instance_accelerator(const std::string& name,
                                                       std::shared_ptr<const InstancePrims> prims,
                                                       Params params);

/// Creates (does not build) an accelerator over a moving mesh; throws UnknownAccelerator (also when the
/// structure cannot hold one) or ParamError.
std::unique_ptr<Accelerator> make_motion_accelerator(const std::string& name,
                                                     std::shared_ptr<const MotionTrianglePrims> prims,
                                                     Params params);

/// The factory of structure S over primitive set P: reads S's Config from the parameters once and passes
/// it typed to the constructor (the shape of pbrt-v4's Create()).
template <class S>
std::unique_ptr<Accelerator> create_structure(std::shared_ptr<const typename S::Prims> prims,
                                              Params& params) {
  return std::make_unique<S>(std::move(prims), S::Config::read(params));
}

/// Describes structure template S for the registry, over the three primitive sets (triangles, instances,
/// moving triangles); the concepts name what is missing when S<P> is not a Structure. The name given here
/// is the only place it is written.
template <template <class> class S>
requires Structure<S<TrianglePrims>> && Structure<S<InstancePrims>> && Structure<S<MotionTrianglePrims>>
    AcceleratorInfo structure_info(std::string name, std::string description, int order) {
  AcceleratorInfo info;
  info.name = std::move(name);
  info.description = std::move(description);
  info.order = order;
  info.make_for_mesh = create_structure<S<TrianglePrims>>;
  info.make_for_instances = create_structure<S<InstancePrims>>;
  info.make_for_motion_mesh = create_structure<S<MotionTrianglePrims>>;
  return info;
}

}  // namespace ab
