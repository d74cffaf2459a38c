#include "harness/suite.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "accel/core/error.h"
#include "accel/core/mesh.h"
#include "accel/core/registry.h"
#include "datasets/generators.h"
#include "datasets/rays.h"
#include "harness/selection.h"
#include "tracer/scene.h"
#include "tracer/update_strategy.h"
#include "tracer/workload.h"

namespace ab {

namespace {

using nlohmann::json;

/// Error context: the suite's name and the field path being read.
struct Where {
  const std::string& source;
  std::string field;

  Where at(const std::string& key) const { return {source, field.empty() ? key : field + "." + key}; }
  Where at(size_t index) const { return {source, field + "[" + std::to_string(index) + "]"}; }
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(source + ": " + (field.empty() ? "" : field + ": ") + what);
  }
};

const char* type_name(const json& j) {
  return j.type_name();
}

void check_keys(const json& obj, const Where& w, const std::set<std::string>& allowed) {
  if (!obj.is_object()) w.fail(std::string("expected an object, got ") + type_name(obj));
  for (const auto& [key, value] : obj.items())
    if (!allowed.count(key)) w.at(key).fail("unknown field");
}

uint64_t read_count(const json& j, const Where& w, uint64_t lo, uint64_t hi) {
  // A float must be a whole number in [0, 2^64) before it is converted (converting others is undefined).
  const bool whole_float = j.is_number_float() && j.get<double>() >= 0.0 && j.get<double>() < 0x1p64 &&
                           j.get<double>() == std::floor(j.get<double>());
  if (!j.is_number_integer() && !whole_float)
    w.fail(std::string("expected a non-negative integer, got ") + j.dump());
  const double as_double = j.get<double>();
  if (as_double < double(lo) || as_double > double(hi))
    w.fail(j.dump() + " is outside [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return j.is_number_float() ? uint64_t(as_double) : j.get<uint64_t>();
}

std::string read_string(const json& j, const Where& w) {
  if (!j.is_string() || j.get<std::string>().empty()) w.fail("expected a non-empty string, got " + j.dump());
  return j.get<std::string>();
}

bool read_bool(const json& j, const Where& w) {
  if (!j.is_boolean()) w.fail("expected true or false");
  return j.get<bool>();
}

/// A parameter value as the k=v string the structures parse.
std::string param_text(const json& v, const Where& w) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_number()) return v.dump();
  w.fail("expected a number, string or boolean (or a list of them), got " + v.dump());
}

/// Most configurations one entry's parameter lists may expand into.
constexpr size_t kMaxCombinations = 4096;

/// Expands {"k": [a, b], "m": c} into every combination, in key order with the last key varying fastest.
std::vector<std::map<std::string, std::string>> expand_grid(const json& params, const Where& w) {
  std::vector<std::map<std::string, std::string>> out{{}};
  if (params.is_null()) return out;
  if (!params.is_object()) w.fail(std::string("expected an object, got ") + type_name(params));
  for (const auto& [key, value] : params.items()) {
    const Where wk = w.at(key);
    std::vector<std::string> values;
    if (value.is_array()) {
      if (value.empty()) wk.fail("empty list of values");
      for (size_t i = 0; i < value.size(); ++i) values.push_back(param_text(value[i], wk.at(i)));
    } else {
      values.push_back(param_text(value, wk));
    }
    // Each list multiplies the combinations: bound them (a short file could ask for billions).
    if (out.size() * values.size() > kMaxCombinations)
      wk.fail("the parameter lists give more than " + std::to_string(kMaxCombinations) + " combinations");
    std::vector<std::map<std::string, std::string>> next;
    for (const auto& partial : out)
      for (const auto& v : values) {
        next.push_back(partial);
        next.back()[key] = v;
      }
    out = std::move(next);
  }
  return out;
}

std::string label_with_params(const std::string& base, const std::map<std::string, std::string>& params) {
  if (params.empty()) return base;
  std::string s = base + "{";
  bool first = true;
  for (const auto& [k, v] : params) {
    s += (first ? "" : ",") + k + "=" + v;
    first = false;
  }
  return s + "}";
}

std::string resolve(const std::string& path, const std::string& base_dir) {
  const std::filesystem::path p(path);
  if (p.is_absolute() || base_dir.empty()) return path;
  return (std::filesystem::path(base_dir) / p).lexically_normal().string();
}

void parse_generator_scene(const json& s, const Where& w, std::vector<SceneSpec>& out) {
  check_keys(s, w, {"generator", "triangles", "seed", "params"});
  const std::string generator = read_string(s["generator"], w.at("generator"));
  if (!s.contains("triangles")) w.fail("missing field 'triangles'");
  const json& tri = s["triangles"];
  std::vector<uint64_t> sizes;
  if (tri.is_array()) {
    if (tri.empty()) w.at("triangles").fail("empty list");
    for (size_t i = 0; i < tri.size(); ++i)
      sizes.push_back(read_count(tri[i], w.at("triangles").at(i), 1, 1ull << 32));
  } else {
    sizes.push_back(read_count(tri, w.at("triangles"), 1, 1ull << 32));
  }
  const uint64_t seed = s.contains("seed") ? read_count(s["seed"], w.at("seed"), 0, UINT64_MAX) : 1;
  for (const auto& params : expand_grid(s.value("params", json()), w.at("params")))
    for (uint64_t n : sizes) {
      SceneSpec spec;
      spec.source = SceneSpec::Source::kGenerator;
      spec.generator = generator;
      spec.triangles = n;
      spec.seed = seed;
      spec.params = params;
      spec.label = label_with_params(generator, params) + "-" + std::to_string(n);
      spec.field = w.field;
      out.push_back(std::move(spec));
    }
}

/// An animated scene's "frames", "strategies" and "threshold" (docs/suites.md, docs/dynamic.md).
void parse_animation(const json& s, const Where& w, SceneSpec& spec) {
  const bool any = s.contains("frames") || s.contains("strategies") || s.contains("threshold");
  if (!any) return;
  if (spec.source != SceneSpec::Source::kScene) w.fail("'frames' and 'strategies' need an animated 'scene'");
  if (!s.contains("frames")) w.fail("missing field 'frames' (an animated scene's frame count)");
  spec.frames = read_count(s["frames"], w.at("frames"), 2, 100000);
  spec.strategies = {"rebuild", "refit"};
  if (s.contains("strategies")) {
    const json& list = s["strategies"];
    const Where ws = w.at("strategies");
    if (!list.is_array() || list.empty()) ws.fail("expected a non-empty list of strategies");
    spec.strategies.clear();
    std::set<std::string> seen;
    for (size_t i = 0; i < list.size(); ++i) {
      const std::string name = read_string(list[i], ws.at(i));
      try {
        parse_strategy(name);
      } catch (const ParamError& e) {
        ws.at(i).fail(e.what());
      }
      if (!seen.insert(name).second) ws.at(i).fail("duplicate strategy '" + name + "'");
      spec.strategies.push_back(name);
    }
  }
  if (s.contains("threshold")) {
    const json& t = s["threshold"];
    if (!t.is_number() || t.get<double>() <= 1.0 || t.get<double>() > 100.0)
      w.at("threshold").fail("expected a number in (1, 100] (rebuild once the SAH cost grew by this factor)");
    spec.threshold = t.get<double>();
  }
}

void parse_file_scene(const json& s, const Where& w, const std::string& base_dir,
                      std::vector<SceneSpec>& out) {
  const bool is_mesh = s.contains("mesh");
  const std::string key = is_mesh ? "mesh" : "scene";
  check_keys(s, w, {key, "label", "frames", "strategies", "threshold"});
  SceneSpec spec;
  spec.source = is_mesh ? SceneSpec::Source::kMesh : SceneSpec::Source::kScene;
  spec.path = resolve(read_string(s[key], w.at(key)), base_dir);
  spec.label = s.contains("label") ? read_string(s["label"], w.at("label"))
                                   : std::filesystem::path(spec.path).stem().string();
  spec.field = w.field;
  parse_animation(s, w, spec);
  out.push_back(std::move(spec));
}

std::vector<SceneSpec> parse_scenes(const json& j, const Where& w, const std::string& base_dir) {
  if (!j.is_array() || j.empty()) w.fail("expected a non-empty list of scenes");
  std::vector<SceneSpec> out;
  for (size_t i = 0; i < j.size(); ++i) {
    const Where wi = w.at(i);
    const json& s = j[i];
    if (!s.is_object()) wi.fail(std::string("expected an object, got ") + type_name(s));
    const int kinds = int(s.contains("generator")) + int(s.contains("mesh")) + int(s.contains("scene"));
    if (kinds != 1) wi.fail("give exactly one of 'generator', 'mesh' or 'scene'");
    if (s.contains("generator"))
      parse_generator_scene(s, wi, out);
    else
      parse_file_scene(s, wi, base_dir, out);
  }
  return out;
}

/// Names "all" stands for: every listed accelerator but brute (too slow to time on real sizes; it is the
/// verification reference) and the outside peers cgal and bullet (10 to 20 times slower than Embree; a suite
/// names them, as suites/peers.json does).
std::vector<std::string> all_accelerator_names() {
  return listed_accelerators({"brute", "cgal", "bullet"});
}

std::vector<AccelSpec> parse_accelerators(const json& j, const Where& w) {
  if (!j.is_array() || j.empty()) w.fail("expected a non-empty list of accelerators");
  std::vector<AccelSpec> out;
  for (size_t i = 0; i < j.size(); ++i) {
    const Where wi = w.at(i);
    if (j[i].is_string()) {
      const std::string name = read_string(j[i], wi);
      const auto names = name == "all" ? all_accelerator_names() : std::vector<std::string>{name};
      for (const auto& n : names) {
        const bool listed =
            std::any_of(out.begin(), out.end(), [&](const AccelSpec& a) { return a.label == n; });
        if (!(listed && name == "all")) out.push_back({n, {}, n, wi.field});
      }
      continue;
    }
    check_keys(j[i], wi, {"name", "params"});
    const std::string name = read_string(j[i].value("name", json()), wi.at("name"));
    for (const auto& params : expand_grid(j[i].value("params", json()), wi.at("params")))
      out.push_back({name, params, label_with_params(name, params), wi.field});
  }
  return out;
}

std::vector<RaySpec> parse_rays(const json& j, const Where& w, const std::string& base_dir) {
  if (!j.is_array()) w.fail("expected a list of ray sets");
  std::vector<RaySpec> out;
  for (size_t i = 0; i < j.size(); ++i) {
    const Where wi = w.at(i);
    check_keys(j[i], wi, {"kind", "count", "file", "any_hit", "label", "views"});
    RaySpec spec;
    spec.field = wi.field;
    if (j[i].contains("file") == j[i].contains("kind"))
      wi.fail("give exactly one of 'kind' (with 'count') or 'file'");
    if (j[i].contains("kind")) {
      spec.kind = read_string(j[i]["kind"], wi.at("kind"));
      if (!j[i].contains("count")) wi.fail("missing field 'count'");
      spec.count = read_count(j[i]["count"], wi.at("count"), 1, 1ull << 30);
      spec.label = spec.kind;
      spec.any_hit = spec.kind == "shadow";
      if (j[i].contains("views")) {
        if (spec.kind != "primary") wi.at("views").fail("applies to the primary ray kind only");
        spec.views = uint32_t(read_count(j[i]["views"], wi.at("views"), 1, 4096));
        if (spec.views > 1) spec.label += "-views" + std::to_string(spec.views);
      }
    } else {
      if (j[i].contains("count")) wi.at("count").fail("not allowed with 'file' (the file gives the count)");
      if (j[i].contains("views")) wi.at("views").fail("not allowed with 'file'");
      spec.path = resolve(read_string(j[i]["file"], wi.at("file")), base_dir);
      spec.label = "file:" + std::filesystem::path(spec.path).filename().string();
    }
    if (j[i].contains("any_hit")) spec.any_hit = read_bool(j[i]["any_hit"], wi.at("any_hit"));
    if (j[i].contains("label")) spec.label = read_string(j[i]["label"], wi.at("label"));
    out.push_back(std::move(spec));
  }
  return out;
}

std::vector<int> parse_threads(const json& j, const Where& w) {
  if (!j.is_array() || j.empty()) w.fail("expected a non-empty list of thread counts (0 = all cores)");
  std::vector<int> out;
  for (size_t i = 0; i < j.size(); ++i) out.push_back(int(read_count(j[i], w.at(i), 0, 4096)));
  return out;
}

VerifySpec parse_verify(const json& j, const Where& w) {
  check_keys(j, w, {"brute_rays", "reference", "embree"});
  VerifySpec v;
  if (j.contains("brute_rays")) v.brute_rays = read_count(j["brute_rays"], w.at("brute_rays"), 0, 1ull << 30);
  if (j.contains("reference")) v.reference = read_string(j["reference"], w.at("reference"));
  if (j.contains("embree")) v.embree = read_bool(j["embree"], w.at("embree"));
  return v;
}

template <class T>
void check_unique_labels(const std::vector<T>& items, const Where& w) {
  std::set<std::string> seen;
  for (const auto& item : items)
    if (!seen.insert(item.label).second)
      Where{w.source, item.field}.fail("duplicate entry '" + item.label + "'");
}

void parse_settings(const json& j, const Where& w, Suite& suite) {
  if (j.contains("name")) suite.name = read_string(j["name"], w.at("name"));
  if (j.contains("seed")) suite.seed = read_count(j["seed"], w.at("seed"), 0, UINT64_MAX);
  if (j.contains("repetitions"))
    suite.repetitions = int(read_count(j["repetitions"], w.at("repetitions"), 1, 1000));
  suite.build_repetitions = suite.repetitions;
  if (j.contains("build_repetitions"))
    suite.build_repetitions = int(read_count(j["build_repetitions"], w.at("build_repetitions"), 1, 1000));
  if (j.contains("warmup")) suite.warmup = int(read_count(j["warmup"], w.at("warmup"), 0, 1000));
  if (j.contains("min_time")) {
    if (!j["min_time"].is_number() || j["min_time"].get<double>() < 0 || j["min_time"].get<double>() > 60)
      w.at("min_time").fail("expected a number of seconds in [0, 60]");
    suite.min_time = j["min_time"].get<double>();
  }
  if (j.contains("build_only")) suite.build_only = read_bool(j["build_only"], w.at("build_only"));
  if (j.contains("interleave")) suite.interleave = read_bool(j["interleave"], w.at("interleave"));
  if (j.contains("threads")) suite.threads = parse_threads(j["threads"], w.at("threads"));
  if (j.contains("verify")) suite.verify = parse_verify(j["verify"], w.at("verify"));
}

}  // namespace

Suite parse_suite(const nlohmann::json& j, const std::string& source, const std::string& base_dir) {
  const Where root{source, ""};
  check_keys(j, root,
             {"name", "description", "seed", "repetitions", "build_repetitions", "warmup", "min_time",
              "threads", "build_only", "interleave", "scenes", "accelerators", "rays", "verify"});
  Suite suite;
  suite.source = source;
  suite.json = j;
  parse_settings(j, root, suite);
  if (!j.contains("scenes")) root.fail("missing field 'scenes'");
  if (!j.contains("accelerators")) root.fail("missing field 'accelerators'");
  suite.scenes = parse_scenes(j["scenes"], root.at("scenes"), base_dir);
  suite.accelerators = parse_accelerators(j["accelerators"], root.at("accelerators"));
  if (j.contains("rays")) suite.rays = parse_rays(j["rays"], root.at("rays"), base_dir);
  if (suite.rays.empty() && !suite.build_only)
    root.at("rays").fail("no ray sets (set \"build_only\": true to time builds only)");
  if (suite.accelerators.empty()) root.at("accelerators").fail("no accelerator registered for 'all'");
  check_unique_labels(suite.scenes, root);
  check_unique_labels(suite.accelerators, root);
  check_unique_labels(suite.rays, root);
  return suite;
}

Suite read_suite(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open suite file");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in, nullptr, true, /*ignore_comments=*/true);
  } catch (const nlohmann::json::exception& e) {  // parse_error, and out_of_range for a number like 1e400
    std::string what = e.what();
    const auto colon = what.find("] ");
    throw InputError(path +
                     ": invalid JSON: " + (colon == std::string::npos ? what : what.substr(colon + 2)));
  }
  const std::string base = std::filesystem::path(path).parent_path().string();
  return parse_suite(j, path, base);
}

namespace {
/// The compiled-in copy of suites/default.json (used when the source tree is not there); a test keeps
/// the two identical.
constexpr const char* kDefaultSuiteJson = R"json({
  "name": "default",
  "description": "Every registered accelerator on four generators at two sizes, four ray kinds, 1 thread and all cores; about 10 minutes on 2 cores.",
  "seed": 1,
  "repetitions": 5,
  "build_repetitions": 3,
  "warmup": 1,
  "min_time": 0.05,
  "threads": [1, 0],
  "scenes": [
    {"generator": "sphereflake", "triangles": [10000, 100000], "seed": 1},
    {"generator": "terrain", "triangles": [10000, 100000], "seed": 1},
    {"generator": "stadium", "triangles": [10000, 100000], "seed": 1},
    {"generator": "soup", "triangles": [10000, 100000], "seed": 1}
  ],
  "accelerators": ["all"],
  "rays": [
    {"kind": "primary", "count": 65536},
    {"kind": "shadow", "count": 65536},
    {"kind": "diffuse", "count": 65536},
    {"kind": "incoherent", "count": 65536}
  ],
  "verify": {"brute_rays": 1000, "reference": "bvh-sah", "embree": true}
}
)json";
}  // namespace

const std::string& default_suite_text() {
  static const std::string text = [] {
    std::ifstream in(std::string(ACCELBENCH_SOURCE_DIR) + "/suites/default.json");
    if (!in) return std::string(kDefaultSuiteJson);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }();
  return text;
}

const char* compiled_default_suite_text() {
  return kDefaultSuiteJson;
}

Suite default_suite() {
  return parse_suite(nlohmann::json::parse(default_suite_text()), "default suite", ACCELBENCH_SOURCE_DIR);
}

namespace {

void validate_accelerators(const Suite& suite) {
  // A tiny mesh: each configuration is created (parameters read and checked), never built.
  const auto prims = one_triangle_prims();
  std::vector<std::string> names{suite.verify.reference};
  for (const auto& a : suite.accelerators) {
    const Where w{suite.source, a.field};
    try {
      find_accelerator(a.name);
    } catch (const InputError&) {
      w.at("name").fail("unknown accelerator '" + a.name + "'");
    }
    try {
      make_accelerator(a.name, prims, Params(a.params));
    } catch (const InputError& e) {
      w.at("params").fail(std::string(e.what()) + " (configuration " + a.label + ")");
    }
  }
  try {
    find_accelerator(suite.verify.reference);
  } catch (const InputError&) {
    Where{suite.source, "verify.reference"}.fail("unknown accelerator '" + suite.verify.reference + "'");
  }
}

void validate_scenes(const Suite& suite) {
  for (const auto& s : suite.scenes) {
    const Where w{suite.source, s.field};
    if (s.source != SceneSpec::Source::kGenerator) {
      if (!std::filesystem::is_regular_file(s.path))
        w.at(s.source == SceneSpec::Source::kMesh ? "mesh" : "scene").fail(s.path + ": no such file");
      if (s.frames > 0 && !load_scene(s.path).animated())
        w.at("frames").fail(s.path + " is not animated (nothing moves over time)");
      continue;
    }
    const auto& gens = generators();
    if (std::none_of(gens.begin(), gens.end(), [&](const GeneratorInfo& g) { return g.name == s.generator; }))
      w.at("generator").fail("unknown generator '" + s.generator + "'");
    try {
      generate_mesh(s.generator, 16, s.seed, Params(s.params));
    } catch (const InputError& e) {
      w.at("params").fail(e.what());
    }
  }
}

void validate_rays(const Suite& suite) {
  const auto& kinds = ray_kinds();
  // The tracer's own kinds (dof, glossy, ...) need a camera and lights: only when every scene is a scene
  // file.
  const bool all_scene_files = std::all_of(suite.scenes.begin(), suite.scenes.end(), [](const SceneSpec& s) {
    return s.source == SceneSpec::Source::kScene;
  });
  for (const auto& r : suite.rays) {
    const Where w{suite.source, r.field};
    const bool mesh_kind =
        std::any_of(kinds.begin(), kinds.end(), [&](const RayKindInfo& k) { return k.name == r.kind; });
    if (!r.kind.empty() && !mesh_kind && !(all_scene_files && is_scene_ray_kind(r.kind)))
      w.at("kind").fail(
          "unknown ray kind '" + r.kind + "'" +
          (is_scene_ray_kind(r.kind) ? " for meshes (it needs every scene to be a scene file)" : ""));
    if (!r.path.empty() && !std::filesystem::is_regular_file(r.path))
      w.at("file").fail(r.path + ": no such file");
  }
}

}  // namespace

void validate_suite(const Suite& suite) {
  validate_accelerators(suite);
  validate_scenes(suite);
  validate_rays(suite);
}

}  // namespace ab
