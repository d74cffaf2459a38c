#include "harness/report_rows.h"

#include <oneapi/tbb/info.h>

#include "harness/machine.h"
#include "harness/report.h"
#include "harness/shard.h"
#include "harness/timing.h"

namespace ab {

using nlohmann::json;

namespace {

/// The report's "verification": the suite's settings and how each configuration is checked.
json verification_method(const VerifySpec& v) {
  return {
      {"brute_rays", v.brute_rays},
      {"reference", v.reference},
      {"embree", v.embree},
      {"method",
       "each configuration's hits (counting pass) are compared byte for byte with brute force on the first "
       "brute_rays rays of every set (0: all), and with the reference structure (itself checked against "
       "brute force on those rays) on all rays; the timed passes' hits at every thread count must equal "
       "the counting pass's; any-hit answers must equal whether the reference found a hit; Embree's hits "
       "are classified agree/tie/edge/graze/limit/rounding/unexplained, and an unexplained disagreement "
       "fails the "
       "run"}};
}

}  // namespace

json report_header(const Suite& suite) {
  return {{"schema_version", kReportSchemaVersion},
          {"tool", "accelbench run"},
          {"date", utc_now("%Y-%m-%dT%H:%M:%SZ")},
          {"seed", suite.seed},
          {"suite_name", suite.name},
          {"suite_source", suite.source},
          {"suite", suite.json},
          {"suite_hash", suite_hash(suite.json)},
          {"machine", machine_info()},
          {"compiler", compiler_info()},
          {"source", source_info()},
          {"libraries", library_versions()},
          {"max_threads", tbb::info::default_concurrency()},
          {"verification", verification_method(suite.verify)},
          {"verified", true},
          {"interrupted", false},
          {"complete", false},
          {"failures", json::array()},
          {"scenes", json::array()},
          {"builds", json::array()},
          {"results", json::array()},
          {"sah_correlation", json::array()}};
}

json scene_entry(const SceneSpec& scene, const Target& target, const std::vector<RaySet>& sets,
                 double setup_seconds) {
  json info = {{"label", scene.label},
               {"triangles", target.triangles},
               {"source", target.path},
               {"bounds_lo", {target.bounds.lo.x, target.bounds.lo.y, target.bounds.lo.z}},
               {"bounds_hi", {target.bounds.hi.x, target.bounds.hi.y, target.bounds.hi.z}}};
  if (scene.source == SceneSpec::Source::kGenerator)
    info["generator"] = {{"name", scene.generator},
                         {"triangles", scene.triangles},
                         {"seed", scene.seed},
                         {"params", scene.params}};
  info["ray_sets"] = json::array();
  for (const RaySet& s : sets)
    info["ray_sets"].push_back({{"label", s.spec->label},
                                {"kind", s.spec->kind},
                                {"views", s.spec->views},
                                {"file", s.spec->path},
                                {"count", s.rays.size()},
                                {"brute_checked", s.brute_checked}});
  info["setup_seconds"] = setup_seconds;
  return info;
}

namespace {

/// The fields naming a configuration on a scene, shared by result rows and build entries.
json configuration_identity(const std::string& scene, const Target& target, const AccelSpec& spec,
                            const Accelerator& accel) {
  return {{"scene", scene},           {"triangles", target.triangles},
          {"accelerator", spec.name}, {"config_label", spec.label},
          {"params", spec.params},    {"config", accel.config()}};
}

}  // namespace

json configuration_fields(const std::string& scene, const Target& target, const AccelSpec& spec,
                          const Accelerator& accel, const Timing& build) {
  const BuildStats& s = accel.stats();
  const double tri = target.triangles ? double(target.triangles) : 1.0;
  json j = configuration_identity(scene, target, spec, accel);
  j.update({{"build_seconds_median", build.median},
            {"build_seconds_min", build.min},
            {"build_seconds_max", build.max},
            {"bytes", s.bytes},
            {"bytes_per_triangle", double(s.bytes) / tri},
            {"peak_bytes", s.peak_bytes},
            {"peak_bytes_per_triangle", double(s.peak_bytes) / tri},
            {"nodes", s.nodes},
            {"leaves", s.leaves},
            {"max_depth", s.max_depth},
            {"references_per_triangle", double(s.references) / tri},
            {"sah_cost", s.sah_cost > 0 ? json(s.sah_cost) : json()},
            {"epo", s.epo >= 0 ? json(s.epo) : json()}});
  return j;
}

json build_entry(const std::string& scene, const Target& target, const AccelSpec& spec,
                 const Accelerator& accel, const Timing& build) {
  const BuildStats& s = accel.stats();
  const double tri = target.triangles ? double(target.triangles) : 1.0;
  json j = configuration_identity(scene, target, spec, accel);
  j.update({{"build_seconds", timing_json(build)},
            {"bytes_per_triangle", double(s.bytes) / tri},
            {"peak_bytes_per_triangle", double(s.peak_bytes) / tri},
            {"stats", to_json(s)},
            {"verification", json::array()}});
  return j;
}

json per_ray_fields(const RayCounters& counters, size_t rays) {
  json j = to_json(counters, rays);
  j["havran_cost_per_ray"] = j["nodes_per_ray"].get<double>() + j["prims_per_ray"].get<double>();
  return j;
}

}  // namespace ab
