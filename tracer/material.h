// Materials of the tracer: diffuse, mirror, glossy (Phong lobe around the mirror direction, after
// Cook 1984) and dielectric (Snell refraction with Fresnel reflection).
#pragma once

#include <string>

#include "accel/core/aabb.h"

namespace ab {

/// A surface material.
struct Material {
  /// How the surface scatters light.
  enum class Type { kDiffuse, kMirror, kGlossy, kDielectric };
  std::string name;
  Type type = Type::kDiffuse;
  vec3 color{0.8f};        ///< albedo (diffuse), tint (mirror, glossy, dielectric)
  float roughness = 0.1f;  ///< glossy: 0 is a mirror, 1 is very blurry
  float ior = 1.5f;        ///< dielectric: index of refraction (outside is 1)

  /// Phong exponent of the glossy lobe for this roughness.
  float phong_exponent() const;
};

/// Material type name in scene files ("diffuse", "mirror", "glossy", "dielectric").
const char* material_type_name(Material::Type t);

}  // namespace ab
