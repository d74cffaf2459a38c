#include "tracer/material.h"

#include <algorithm>

namespace ab {

float Material::phong_exponent() const {
  // roughness r maps to exponent 2 / r^2 - 2 (the Blinn-Phong / Beckmann correspondence, Walter 2007).
  const float r = std::clamp(roughness, 1e-3f, 1.0f);
  return std::max(1.0f, 2.0f / (r * r) - 2.0f);
}

const char* material_type_name(Material::Type t) {
  switch (t) {
    case Material::Type::kDiffuse:
      return "diffuse";
    case Material::Type::kMirror:
      return "mirror";
    case Material::Type::kGlossy:
      return "glossy";
    case Material::Type::kDielectric:
      return "dielectric";
  }
  return "diffuse";
}

}  // namespace ab
