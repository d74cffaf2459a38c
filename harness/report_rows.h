// What report.json holds, entry by entry: its header (what the run was, on what, verified how), a scene's
// entry, a configuration's build entry and the fields every result row of that configuration starts from.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "accel/core/accelerator.h"
#include "harness/bench.h"
#include "harness/suite.h"
#include "harness/target.h"
#include "harness/verification.h"

namespace ab {

/// The report before any work: schema, tool, date, seed, the suite, machine, compiler, source, libraries,
/// thread count, the verification method, verified true, and the empty lists the run fills.
nlohmann::json report_header(const Suite& suite);

/// A scene's entry in report["scenes"]: label, triangles, source, bounds, generator, ray sets, setup time.
nlohmann::json scene_entry(const SceneSpec& scene, const Target& target, const std::vector<RaySet>& sets,
                           double setup_seconds);

/// The fields every result row of a built configuration starts from: scene, accelerator, parameters,
/// effective config, build time and the structure's figures (bytes, nodes, references, SAH cost).
nlohmann::json configuration_fields(const std::string& scene, const Target& target, const AccelSpec& spec,
                                    const Accelerator& accel, const Timing& build);

/// A configuration's entry in report["builds"]: its build timing and statistics, and an empty
/// "verification" list that receives one entry per ray set.
nlohmann::json build_entry(const std::string& scene, const Target& target, const AccelSpec& spec,
                           const Accelerator& accel, const Timing& build);

/// The counting pass's figures per ray, with Havran's cost (traversal steps + intersection tests per ray).
nlohmann::json per_ray_fields(const RayCounters& counters, size_t rays);

}  // namespace ab
