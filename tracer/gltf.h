// glTF 2.0 scenes (.gltf with embedded or external buffers, .glb) through tinygltf: meshes become base
// meshes, nodes with a mesh become instances under their world matrices, node animation channels
// (translation, rotation, scale; LINEAR and STEP) become keyframes. The mapping is in docs/scenes.md.
#pragma once

#include <string>

#include "tracer/scene.h"

namespace ab {

/// True when the path ends in .gltf or .glb (any case).
bool is_gltf_path(const std::string& path);

/// Reads a glTF 2.0 file as a scene at time 0 (its animation range: the first to the last key time of
/// all its animations, in seconds). Throws InputError with one line naming the file and what is wrong.
Scene load_gltf_scene(const std::string& path);

/// Writes a scene as glTF 2.0 (.glb binary, .gltf with the buffer embedded): each base mesh one glTF mesh
/// (one primitive, triangles in id order), each instance a chain of nodes (one per transform element,
/// the last holding the mesh), each keyed element an animation channel (rotations about an axis become
/// quaternion keys at most 90 degrees apart, so slerp turns them as the angles do). Materials, lights
/// and the camera are not written. Throws InputError for a deforming mesh (glTF has no such animation)
/// or an animated matrix element; the file is written atomically.
void write_gltf_scene(const Scene& scene, const std::string& path);

}  // namespace ab
