// Deforming meshes with a fixed triangle list: a sequence of frame meshes (the `frames` pattern of a
// scene's <mesh>) or a built-in deformer (wave, twist, explode) applied to a base mesh over time. The
// triangle ids never change, so a frame's hits name the same triangles as any other frame's.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "accel/core/mesh.h"

namespace ab {

/// A built-in deformation of a base mesh, a function of the phase p in [0, 1] (p = 0 at `start`, 1 at
/// `end`, clamped outside).
struct Deformer {
  /// Which deformation.
  enum class Kind {
    kWave,   ///< a travelling sine wave: v += amplitude sin(2 pi (dot(v, direction) / wavelength - cycles p))
             ///< axis
    kTwist,  ///< rotation about `axis` through the bounds' centre by degrees * p * (height along axis, 0..1)
    kExplode,  ///< each triangle moves along its unit normal by distance * p * (0.5 + its hash in [0, 1))
  };
  Kind kind = Kind::kWave;
  float start = 0.0f;       ///< scene time of phase 0
  float end = 1.0f;         ///< scene time of phase 1 (> start)
  vec3 axis{0, 1, 0};       ///< wave: displacement direction; twist: rotation axis (unit)
  vec3 direction{1, 0, 0};  ///< wave: the direction the wave travels (unit)
  float amplitude = 0.1f;   ///< wave: displacement, in units of the base mesh's bounds diagonal
  float wavelength = 0.5f;  ///< wave: in units of the bounds diagonal
  float cycles = 1.0f;      ///< wave: periods travelled from phase 0 to 1
  float degrees = 180.0f;   ///< twist: rotation of the top relative to the bottom at phase 1
  float distance = 0.5f;    ///< explode: mean flight at phase 1, in units of the bounds diagonal

  /// The phase at scene time t.
  float phase(float t) const;
  /// The deformed mesh at scene time t: same triangle count and order as `base`.
  Mesh apply(const Mesh& base, float t) const;
};

/// How a base mesh changes over time: not at all, through frame files, or by a deformer.
struct MeshAnimation {
  /// Which of the three.
  enum class Kind { kStatic, kFrames, kDeformer };
  Kind kind = Kind::kStatic;
  std::vector<std::shared_ptr<const Mesh>> frames;  ///< kFrames: the meshes, same triangle count
  float start = 0.0f;                               ///< kFrames: scene time of the first frame
  float end = 1.0f;                                 ///< kFrames: scene time of the last frame
  Deformer deformer;                                ///< kDeformer

  /// True unless static.
  bool animated() const { return kind != Kind::kStatic; }
  /// The scene-time range it spans (start, end).
  void time_range(float& first, float& last) const;
  /// The mesh at scene time t. kFrames: the frame nearest to t's position in the sequence (frame k
  /// at start + k (end - start) / (count - 1)); kDeformer: the deformer on `base`; kStatic: `base`.
  std::shared_ptr<const Mesh> at(const std::shared_ptr<const Mesh>& base, float t) const;
};

}  // namespace ab
