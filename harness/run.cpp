#include "harness/run.h"

#include <filesystem>
#include <iostream>
#include <memory>

#include "accel/core/trace.h"
#include "datasets/atomic_file.h"
#include "datasets/generators.h"
#include "harness/analysis.h"
#include "harness/hitfile.h"
#include "harness/report.h"
#include "harness/report_rows.h"
#include "harness/terminal.h"
#include "harness/timing.h"
#include "harness/verification.h"

namespace ab {

namespace {

using nlohmann::json;

/// The orchestration of a run: scenes one at a time, in each the reference answers of its ray sets, then
/// every configuration built, verified and timed; the report saved after every scene.
class Runner {
 public:
  Runner(const Suite& suite, const RunOptions& options)
      : suite_(suite), options_(options), progress_(count_units(), options.progress), timer_(suite) {}

  json run();

 private:
  size_t count_units() const;
  bool stopping();
  void fail(const std::string& what);
  FailureSink failure_sink() {
    return [this](const std::string& what) { fail(what); };
  }
  void save(bool finished = false);
  void run_scene(const SceneSpec& scene);
  Target load(const SceneSpec& scene) const;
  std::vector<RaySet> make_ray_sets(const Target& target) const;
  std::unique_ptr<Accelerator> build(const Target& target, const std::string& scene, const AccelSpec& spec,
                                     json& base);
  void run_config(const Target& target, const SceneSpec& scene, const AccelSpec& spec,
                  std::vector<RaySet>& sets);
  void run_ray_set(const Accelerator& accel, const Target& target, const std::string& what,
                   const AccelSpec& spec, RaySet& set, const json& base);
  void time_closest(const Accelerator& accel, const std::string& name, RaySet& set,
                    const std::vector<Hit>& expected, json row);
  void time_any(const Accelerator& accel, const std::string& name, RaySet& set, bool exact, json row);
  void add_timed_row(json row, const Timing& t, int threads, const std::string& query, uint64_t mismatches);

  const Suite& suite_;
  const RunOptions& options_;
  Progress progress_;
  SuiteTimer timer_;
  json report_;
  bool interrupted_ = false;
};

size_t Runner::count_units() const {
  size_t per_config = 1;
  if (!suite_.build_only)
    for (const auto& r : suite_.rays) per_config += 1 + suite_.threads.size() * (r.any_hit ? 2 : 1);
  return suite_.scenes.size() * (1 + suite_.accelerators.size() * per_config);
}

bool Runner::stopping() {
  if (options_.interrupted && options_.interrupted->load()) interrupted_ = true;
  return interrupted_;
}

void Runner::fail(const std::string& what) {
  report_["verified"] = false;
  report_["failures"].push_back(what);
  progress_.finish();
  const Colors c = colors(options_.color);
  std::cerr << c.red << "VERIFICATION FAILED: " << what << c.reset << "\n";
}

void Runner::save(bool finished) {
  fill_ratios(report_);
  fill_correlations(report_, suite_.threads.front());
  report_["interrupted"] = interrupted_;
  report_["complete"] = finished && !interrupted_;
  write_report(report_, options_.out_dir);
  const std::string gbench = timer_.gbench_json();
  write_file_atomically((std::filesystem::path(options_.out_dir) / "gbench.json").string(),
                        [&](std::ostream& out) { out << gbench; }, false);
}

json Runner::run() {
  report_ = report_header(suite_);
  if (!options_.shard.is_null()) report_["shard"] = options_.shard;
  for (const SceneSpec& scene : suite_.scenes) {
    if (stopping()) break;
    run_scene(scene);
    save();
  }
  stopping();
  progress_.finish();
  save(true);
  return report_;
}

Target Runner::load(const SceneSpec& scene) const {
  switch (scene.source) {
    case SceneSpec::Source::kMesh:
      return load_target(scene.path, "");
    case SceneSpec::Source::kScene:
      return load_target("", scene.path);
    case SceneSpec::Source::kGenerator:
      break;
  }
  auto mesh = std::make_shared<const Mesh>(
      generate_mesh(scene.generator, scene.triangles, scene.seed, Params(scene.params)));
  return mesh_target(std::move(mesh), scene.label);
}

std::vector<RaySet> Runner::make_ray_sets(const Target& target) const {
  std::vector<RaySet> sets;
  if (suite_.build_only) return sets;
  const RayTarget rt = ray_target(target);
  for (const RaySpec& spec : suite_.rays) {
    RaySet set;
    set.spec = &spec;
    set.rays = spec.path.empty() ? make_target_rays(target, rt, spec.kind, spec.count, suite_.seed)
                                 : read_rays(spec.path);
    sets.push_back(std::move(set));
  }
  return sets;
}

void Runner::run_scene(const SceneSpec& scene) {
  const auto t0 = std::chrono::steady_clock::now();
  const Target target = load(scene);
  std::vector<RaySet> sets = make_ray_sets(target);
  make_references(target, scene.label, suite_.verify, sets, failure_sink());
  report_["scenes"].push_back(scene_entry(scene, target, sets, seconds_since(t0)));
  progress_.step(scene.label + ": references ready");
  for (const AccelSpec& spec : suite_.accelerators) {
    if (stopping()) return;
    run_config(target, scene, spec, sets);
  }
}

/// Builds the configuration build_repetitions times (each build timed alone), records its build entry and
/// returns the last structure built, with the fields its result rows start from in `base`.
std::unique_ptr<Accelerator> Runner::build(const Target& target, const std::string& scene,
                                           const AccelSpec& spec, json& base) {
  std::unique_ptr<Accelerator> accel;
  auto pass = [&] {
    accel.reset();
    accel = make_target_accelerator(target, spec.name, Params(spec.params));
    accel->build();
    return accel->stats().build_seconds;
  };
  const Timing t = timer_.time_build("build/" + scene + "/" + spec.label, double(target.triangles), pass);
  base = configuration_fields(scene, target, spec, *accel, t);
  report_["builds"].push_back(build_entry(scene, target, spec, *accel, t));
  return accel;
}

void Runner::run_config(const Target& target, const SceneSpec& scene, const AccelSpec& spec,
                        std::vector<RaySet>& sets) {
  json base;
  const std::unique_ptr<Accelerator> accel = build(target, scene.label, spec, base);
  progress_.step(scene.label + " " + spec.label + ": built");
  if (suite_.build_only) {
    json row = base;
    row["query"] = "build";
    row["verified"] = true;
    report_["results"].push_back(row);
    return;
  }
  for (RaySet& set : sets) {
    if (stopping()) return;
    run_ray_set(*accel, target, scene.label + " / " + spec.label + " / " + set.spec->label, spec, set, base);
  }
}

/// One configuration on one ray set: the counting pass, verified; then the timed passes at every thread
/// count.
void Runner::run_ray_set(const Accelerator& accel, const Target& target, const std::string& what,
                         const AccelSpec& spec, RaySet& set, const json& base) {
  const bool exact = is_exact(spec.name);  // every structure of the project matches brute byte for byte
  std::vector<Hit> hits(set.rays.size());
  const RayCounters c = trace_closest_counted(accel, set.rays, hits, 0);
  const json v = verify_hits(target, what, spec.name, suite_.verify.reference, set, hits, failure_sink());
  json detail = v;
  detail["rays"] = set.spec->label;
  report_["builds"].back()["verification"].push_back(detail);
  json row = base;
  row.update(v);
  progress_.step(what + ": verified");
  row["rays"] = set.spec->label;
  row["ray_kind"] = set.spec->kind.empty() ? json() : json(set.spec->kind);
  row["ray_count"] = set.rays.size();
  if (exact) row.update(per_ray_fields(c, set.rays.size()));
  time_closest(accel, what, set, hits, row);
  if (set.spec->any_hit) time_any(accel, what, set, exact, row);
}

void Runner::add_timed_row(json row, const Timing& t, int threads, const std::string& query,
                           uint64_t mismatches) {
  row["query"] = query;
  row.update(query_timing_fields(t, threads, row["ray_count"].get<double>()));
  row["ratio_to_embree"] = nullptr;
  row[query == "closest" ? "thread_mismatches" : "any_hit_mismatches"] = mismatches;
  if (mismatches && (query == "closest" || is_exact(row["accelerator"].get<std::string>())))
    row["verified"] = false;
  report_["results"].push_back(row);
}

void Runner::time_closest(const Accelerator& accel, const std::string& name, RaySet& set,
                          const std::vector<Hit>& expected, json row) {
  for (int threads : suite_.threads) {
    if (stopping()) return;
    std::vector<Hit> out(set.rays.size());
    const std::string case_name = name + "/closest/threads:" + std::to_string(threads);
    const Timing t =
        timer_.time_query(case_name, set.rays.size(), [&] { trace_closest(accel, set.rays, out, threads); });
    add_timed_row(row, t, threads, "closest", check_timed_hits(case_name, expected, out, failure_sink()));
    progress_.step(case_name);
  }
}

void Runner::time_any(const Accelerator& accel, const std::string& name, RaySet& set, bool exact, json row) {
  if (exact) {  // the any-hit counting pass (one thread; counters never run on the timed path)
    std::vector<uint8_t> counted(set.rays.size());
    RayCounters c;
    accel.occluded_counted(set.rays, counted, c);
    row.update(per_ray_fields(c, set.rays.size()));
  }
  for (int threads : suite_.threads) {
    if (stopping()) return;
    std::vector<uint8_t> out(set.rays.size());
    const std::string case_name = name + "/any/threads:" + std::to_string(threads);
    const Timing t =
        timer_.time_query(case_name, set.rays.size(), [&] { trace_occluded(accel, set.rays, out, threads); });
    add_timed_row(row, t, threads, "any", check_any_hits(case_name, exact, out, set, failure_sink()));
    progress_.step(case_name);
  }
}

}  // namespace

nlohmann::json run_suite(const Suite& suite, const RunOptions& options) {
  std::filesystem::create_directories(options.out_dir);
  Runner runner(suite, options);
  return runner.run();
}

}  // namespace ab
