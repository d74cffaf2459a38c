// Benchmark suites: what `accelbench run` measures, read from JSON (format in docs/suites.md).
#pragma once

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace ab {

/// One scene of a suite: a generated mesh, a mesh file or a scene file.
struct SceneSpec {
  /// Where the geometry comes from.
  enum class Source { kGenerator, kMesh, kScene };
  Source source = Source::kGenerator;         ///< generator, mesh file or scene file
  std::string label;                          ///< unique name in reports (for example "sphere-10000")
  std::string generator;                      ///< generator name (kGenerator)
  uint64_t triangles = 0;                     ///< requested triangle count (kGenerator)
  uint64_t seed = 1;                          ///< generator seed (kGenerator)
  std::map<std::string, std::string> params;  ///< generator parameters (kGenerator)
  std::string path;                           ///< file (kMesh, kScene), resolved against the suite's folder
  std::string field;    ///< where it came from in the suite ("scenes[2]"), for error messages
  uint64_t frames = 0;  ///< an animated scene followed over this many frames (0: one static scene)
  std::vector<std::string> strategies;  ///< per-frame update strategies (tracer/update_strategy.h)
  double threshold = 1.5;               ///< adaptive: rebuild once the SAH cost grew past this factor
};

/// One accelerator configuration: a name and one value per parameter (grids are already expanded).
struct AccelSpec {
  std::string name;                           ///< registered accelerator name
  std::map<std::string, std::string> params;  ///< one value per parameter
  std::string label;  ///< name plus parameters, unique in the suite ("grid{lambda=4}")
  std::string field;  ///< "accelerators[1]"
};

/// One ray set: a kind and a count, or a .rays file.
struct RaySpec {
  std::string kind;      ///< ray kind (empty for a file)
  uint64_t count = 0;    ///< rays to make (kind)
  uint32_t views = 1;    ///< cameras around the bounds (kind "primary" only; make_rays)
  std::string path;      ///< .rays file, resolved against the suite's folder
  bool any_hit = false;  ///< also time any-hit (occlusion) queries; default true for kind "shadow"
  std::string label;     ///< unique name in reports ("primary", "shadow", "file:foo.rays")
  std::string field;     ///< "rays[0]"
};

/// How results are verified.
struct VerifySpec {
  uint64_t brute_rays = 2000;  ///< rays of each set checked against brute (0: all rays)
  /// Structure (default config) checked against brute, then used for all rays.
  std::string reference = "bvh-sah";
  bool embree = true;  ///< classify each structure's hits against Embree when it is registered
};

/// A whole suite after parsing, with defaults filled in and parameter grids expanded.
struct Suite {
  std::string name = "suite";           ///< the suite's name in reports
  std::string source;                   ///< file name (or "default suite") used in error messages and reports
  nlohmann::json json;                  ///< the suite as given
  std::vector<SceneSpec> scenes;        ///< in order
  std::vector<AccelSpec> accelerators;  ///< configurations, grids expanded
  std::vector<RaySpec> rays;            ///< ray sets made on every scene
  std::vector<int> threads{1, 0};       ///< 0 = all hardware threads
  int repetitions = 3;                  ///< timed repetitions (median, min and max over them)
  int build_repetitions = 3;            ///< builds per scene x configuration (default: repetitions)
  int warmup = 1;                       ///< untimed passes before timing
  double min_time = 0.02;   ///< seconds each timed repetition lasts at least (more iterations if faster)
  uint64_t seed = 1;        ///< seed of the ray sets
  bool build_only = false;  ///< measure builds only (no ray sets)
  /// Time each ray set's queries with every configuration's repetitions interleaved (all of a scene's
  /// configurations alive at once) instead of one configuration after another.
  bool interleave = false;
  VerifySpec verify;  ///< how results are verified
};

/// Parses a suite. `source` names it in errors; relative paths are resolved against `base_dir`.
/// Throws InputError "source: field: what is wrong" (for example "s.json: accelerators[2].name: ...").
Suite parse_suite(const nlohmann::json& json, const std::string& source, const std::string& base_dir);
/// Reads and parses a suite file (throws InputError naming the file on bad JSON).
Suite read_suite(const std::string& path);
/// The built-in default suite (the same JSON as suites/default.json).
Suite default_suite();
/// The JSON text of the built-in default suite: suites/default.json of the source tree, or the
/// compiled-in copy when the source tree is not there.
const std::string& default_suite_text();
/// The compiled-in copy of suites/default.json (a test keeps the two identical).
const char* compiled_default_suite_text();

/// Checks, before any work, that every name and parameter of the suite is valid: accelerators and their
/// parameters (by creating each configuration over a tiny mesh without building it), generators and their
/// parameters (by generating a tiny mesh), ray kinds, and that files exist. Throws InputError naming the
/// field.
void validate_suite(const Suite& suite);

}  // namespace ab
