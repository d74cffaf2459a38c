#include "harness/run.h"

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>

#include "accel/core/trace.h"
#include "datasets/atomic_file.h"
#include "datasets/generators.h"
#include "harness/analysis.h"
#include "harness/frames.h"
#include "harness/hitfile.h"
#include "harness/report.h"
#include "harness/report_rows.h"
#include "harness/terminal.h"
#include "harness/timing.h"
#include "harness/verification.h"
#include "tracer/scene.h"
#include "tracer/update_strategy.h"

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
  /// One configuration under one strategy across the frames of an animated scene.
  struct FrameCase {
    AccelSpec spec;  ///< the configuration, labelled "label:strategy"
    std::string strategy;
    std::unique_ptr<FrameUpdater> updater;
  };
  void run_animated_scene(const SceneSpec& scene);
  std::vector<FrameCase> frame_cases(const SceneSpec& scene) const;
  void run_frame(FrameCase& c, const Target& target, const SceneSpec& scene, uint64_t frame,
                 std::vector<RaySet>& sets, std::map<std::string, double>& rebuild_cost);
  Target load(const SceneSpec& scene) const;
  std::vector<RaySet> make_ray_sets(const Target& target) const;
  std::unique_ptr<Accelerator> build(const Target& target, const std::string& scene, const AccelSpec& spec,
                                     json& base);
  void run_config(const Target& target, const SceneSpec& scene, const AccelSpec& spec,
                  std::vector<RaySet>& sets);
  void run_interleaved(const Target& target, const SceneSpec& scene, std::vector<RaySet>& sets);
  void run_sets(const Accelerator& accel, const Target& target, const std::string& where,
                const AccelSpec& spec, std::vector<RaySet>& sets, const json& base);
  /// A configuration verified on one ray set and waiting to be timed: its structure, the case name's
  /// start, its row so far and the hits every timed pass must give again.
  struct Verified {
    const Accelerator* accel = nullptr;
    std::string what;
    json row;
    std::vector<Hit> hits;
    bool exact = false;
  };
  Verified verify_set(const Accelerator& accel, const Target& target, const std::string& what,
                      const AccelSpec& spec, RaySet& set, const json& base);
  void time_set(std::vector<Verified>& group, RaySet& set);
  template <typename Out, typename Trace, typename Check>
  void time_group(const std::vector<Verified>& group, const std::vector<json>& rows, RaySet& set,
                  const std::string& query, Trace trace, Check check);
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
  size_t units = 0;
  for (const SceneSpec& s : suite_.scenes)
    units += std::max<size_t>(s.frames, 1) *
             (1 + suite_.accelerators.size() * std::max<size_t>(s.strategies.size(), 1) * per_config);
  return units;
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
  fill_frame_summary(report_);
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
    set.rays = spec.path.empty()
                   ? make_target_rays(target, rt, spec.kind, spec.count, suite_.seed, spec.views)
                   : read_rays(spec.path);
    sets.push_back(std::move(set));
  }
  return sets;
}

void Runner::run_scene(const SceneSpec& scene) {
  if (scene.frames > 0) return run_animated_scene(scene);
  const auto t0 = std::chrono::steady_clock::now();
  const Target target = load(scene);
  std::vector<RaySet> sets = make_ray_sets(target);
  make_references(target, scene.label, suite_.verify, sets, failure_sink());
  report_["scenes"].push_back(scene_entry(scene, target, sets, seconds_since(t0)));
  progress_.step(scene.label + ": references ready");
  if (suite_.interleave && !suite_.build_only) return run_interleaved(target, scene, sets);
  for (const AccelSpec& spec : suite_.accelerators) {
    if (stopping()) return;
    run_config(target, scene, spec, sets);
  }
}

/// An interleaved suite's static scene: every configuration built and verified on every ray set first
/// (all of them alive at once), then each ray set's queries timed with the configurations' repetitions
/// interleaved (SuiteTimer::time_queries), so that a change of the machine's load falls on all alike.
void Runner::run_interleaved(const Target& target, const SceneSpec& scene, std::vector<RaySet>& sets) {
  std::vector<std::unique_ptr<Accelerator>> built;
  std::vector<std::vector<Verified>> groups(sets.size());
  for (const AccelSpec& spec : suite_.accelerators) {
    if (stopping()) return;
    json base;
    built.push_back(build(target, scene.label, spec, base));
    progress_.step(scene.label + " " + spec.label + ": built");
    for (size_t i = 0; i < sets.size() && !stopping(); ++i)
      groups[i].push_back(verify_set(*built.back(), target,
                                     scene.label + " / " + spec.label + " / " + sets[i].spec->label, spec,
                                     sets[i], base));
  }
  for (size_t i = 0; i < sets.size() && !stopping(); ++i) time_set(groups[i], sets[i]);
}

std::vector<Runner::FrameCase> Runner::frame_cases(const SceneSpec& scene) const {
  std::vector<FrameCase> cases;
  // Rebuild first, so that every other strategy's SAH cost has a fresh build's on the same frame to compare.
  for (const AccelSpec& spec : suite_.accelerators)
    for (const UpdateStrategy s : all_update_strategies()) {
      const std::string name = strategy_name(s);
      if (std::find(scene.strategies.begin(), scene.strategies.end(), name) == scene.strategies.end())
        continue;
      if (!FrameUpdater::supports(spec.name, Params(spec.params), s)) continue;
      FrameCase c{spec, name,
                  std::make_unique<FrameUpdater>(spec.name, Params(spec.params), s, scene.threshold)};
      c.spec.label = spec.label + ":" + name;
      cases.push_back(std::move(c));
    }
  return cases;
}

// An animated scene (docs/dynamic.md): per frame, the frame's scene, ray sets (its camera, its geometry) and
// reference answers, then every configuration x strategy updated (timed alone), verified and timed.
void Runner::run_animated_scene(const SceneSpec& scene) {
  const auto t0 = std::chrono::steady_clock::now();
  const Target first = load(scene);
  if (!first.scene || !first.scene->animated())
    throw InputError(scene.path + ": " + scene.field +
                     ": 'frames' needs an animated scene (this one is static)");
  std::vector<FrameCase> cases = frame_cases(scene);
  for (uint64_t f = 0; f < scene.frames; ++f) {
    if (stopping()) return;
    auto frame = std::make_shared<const Scene>(scene_at(*first.scene, frame_time(f, scene.frames)));
    const Target target = scene_target(frame, first.path);
    std::vector<RaySet> sets = make_ray_sets(target);
    make_references(target, scene.label + " frame " + std::to_string(f), suite_.verify, sets, failure_sink());
    if (f == 0) {
      json entry = scene_entry(scene, target, sets, seconds_since(t0));
      entry["frames"] = scene.frames;
      entry["strategies"] = scene.strategies;
      entry["threshold"] = scene.threshold;
      report_["scenes"].push_back(entry);
    }
    progress_.step(scene.label + " frame " + std::to_string(f) + ": references ready");
    std::map<std::string, double> rebuild_cost;  // configuration label -> a fresh build's SAH cost this frame
    for (FrameCase& c : cases) {
      if (stopping()) return;
      run_frame(c, target, scene, f, sets, rebuild_cost);
    }
  }
}

/// One frame of one configuration x strategy: the update (timed alone: FrameUpdater::repeat_update does it
/// again build_repetitions times, the update itself the warm-up), its build entry, then every ray set
/// verified and timed as for a static scene. The rows carry frame, strategy, update_seconds and the SAH cost
/// against a rebuild's.
void Runner::run_frame(FrameCase& c, const Target& target, const SceneSpec& scene, uint64_t frame,
                       std::vector<RaySet>& sets, std::map<std::string, double>& rebuild_cost) {
  const FrameUpdate u = c.updater->update(target.scene);
  const Timing t =
      timer_.time_build("update/" + scene.label + "/frame" + std::to_string(frame) + "/" + c.spec.label,
                        double(target.triangles), [&] { return c.updater->repeat_update(); });
  const Accelerator& accel = c.updater->accelerator();
  const std::string base_label = c.spec.label.substr(0, c.spec.label.rfind(':'));
  if (u.rebuilt && !rebuild_cost.count(base_label)) rebuild_cost[base_label] = u.sah_cost;
  const json frame_fields = {{"frame", frame},
                             {"frames", scene.frames},
                             {"strategy", c.strategy},
                             {"update_seconds", t.median},
                             {"rebuilt", u.rebuilt},
                             {"update_sah_cost", u.sah_cost > 0 ? json(u.sah_cost) : json()},
                             {"sah_ratio_to_rebuild",
                              rebuild_cost.count(base_label) && rebuild_cost[base_label] > 0 && u.sah_cost > 0
                                  ? json(u.sah_cost / rebuild_cost[base_label])
                                  : json()}};
  json base = configuration_fields(scene.label, target, c.spec, accel, t);
  base.update(frame_fields);
  json entry = build_entry(scene.label, target, c.spec, accel, t);
  entry.update(frame_fields);
  report_["builds"].push_back(entry);
  const std::string where = scene.label + " frame " + std::to_string(frame) + " / " + c.spec.label;
  progress_.step(where + ": updated");
  run_sets(accel, target, where, c.spec, sets, base);
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
  accel->measure_quality();
  base = configuration_fields(scene, target, spec, *accel, t);
  report_["builds"].push_back(build_entry(scene, target, spec, *accel, t));
  return accel;
}

void Runner::run_config(const Target& target, const SceneSpec& scene, const AccelSpec& spec,
                        std::vector<RaySet>& sets) {
  json base;
  const std::unique_ptr<Accelerator> accel = build(target, scene.label, spec, base);
  progress_.step(scene.label + " " + spec.label + ": built");
  run_sets(*accel, target, scene.label + " / " + spec.label, spec, sets, base);
}

/// A built (or updated) configuration's rows: one "build" row in a build-only suite, otherwise every ray
/// set verified and timed (`where` names the case in progress lines).
void Runner::run_sets(const Accelerator& accel, const Target& target, const std::string& where,
                      const AccelSpec& spec, std::vector<RaySet>& sets, const json& base) {
  if (suite_.build_only) {
    json row = base;
    row["query"] = "build";
    row["verified"] = true;
    report_["results"].push_back(row);
    return;
  }
  for (RaySet& set : sets) {
    if (stopping()) return;
    std::vector<Verified> group;
    group.push_back(verify_set(accel, target, where + " / " + set.spec->label, spec, set, base));
    time_set(group, set);
  }
}

/// One configuration on one ray set: the counting pass and its verification (the rows' counts and
/// checks); the timing is time_set's.
Runner::Verified Runner::verify_set(const Accelerator& accel, const Target& target, const std::string& what,
                                    const AccelSpec& spec, RaySet& set, const json& base) {
  Verified v{&accel, what, base, std::vector<Hit>(set.rays.size()), is_exact(spec.name)};
  const RayCounters c = trace_closest_counted(accel, set.rays, v.hits, 0);
  const json checked =
      verify_hits(target, what, spec.name, suite_.verify.reference, set, v.hits, failure_sink());
  json detail = checked;
  detail["rays"] = set.spec->label;
  report_["builds"].back()["verification"].push_back(detail);
  v.row.update(checked);
  progress_.step(what + ": verified");
  v.row["rays"] = set.spec->label;
  v.row["ray_kind"] = set.spec->kind.empty() ? json() : json(set.spec->kind);
  v.row["ray_count"] = set.rays.size();
  // every structure of the project matches brute byte for byte: its per-ray counts are exact too
  if (v.exact) v.row.update(per_ray_fields(c, set.rays.size()));
  return v;
}

/// The timed passes of a group of verified configurations on one ray set, at every thread count, the
/// group's repetitions interleaved: closest hit, then any hit when the set asks for it (its own counting
/// pass first, on one thread: counters never run on the timed path).
void Runner::time_set(std::vector<Verified>& group, RaySet& set) {
  std::vector<json> rows;
  for (const Verified& v : group) rows.push_back(v.row);
  time_group<Hit>(
      group, rows, set, "closest",
      [&](const Accelerator& a, std::vector<Hit>& out, int threads) {
        trace_closest(a, set.rays, out, threads);
      },
      [&](const std::string& name, const Verified& v, const std::vector<Hit>& out) {
        return check_timed_hits(name, v.hits, out, failure_sink());
      });
  if (!set.spec->any_hit) return;
  for (size_t k = 0; k < group.size(); ++k) {
    if (!group[k].exact) continue;
    std::vector<uint8_t> counted(set.rays.size());
    RayCounters c;
    group[k].accel->occluded_counted(set.rays, counted, c);
    rows[k].update(per_ray_fields(c, set.rays.size()));
  }
  time_group<uint8_t>(
      group, rows, set, "any",
      [&](const Accelerator& a, std::vector<uint8_t>& out, int threads) {
        trace_occluded(a, set.rays, out, threads);
      },
      [&](const std::string& name, const Verified& v, const std::vector<uint8_t>& out) {
        return check_any_hits(name, v.exact, out, set, failure_sink());
      });
}

/// One query of a group at every thread count: `trace` fills a structure's answers (Out per ray), `check`
/// counts how many differ from the verified ones; one row per configuration and thread count.
template <typename Out, typename Trace, typename Check>
void Runner::time_group(const std::vector<Verified>& group, const std::vector<json>& rows, RaySet& set,
                        const std::string& query, Trace trace, Check check) {
  for (int threads : suite_.threads) {
    if (stopping()) return;
    std::vector<std::vector<Out>> outs(group.size(), std::vector<Out>(set.rays.size()));
    std::vector<SuiteTimer::Query> queries;
    for (size_t k = 0; k < group.size(); ++k)
      queries.push_back({group[k].what + "/" + query + "/threads:" + std::to_string(threads), set.rays.size(),
                         [&, k, threads] { trace(*group[k].accel, outs[k], threads); }});
    const std::vector<Timing> timings = timer_.time_queries(queries);
    for (size_t k = 0; k < group.size(); ++k) {
      add_timed_row(rows[k], timings[k], threads, query, check(queries[k].name, group[k], outs[k]));
      progress_.step(queries[k].name);
    }
  }
}

void Runner::add_timed_row(json row, const Timing& t, int threads, const std::string& query,
                           uint64_t mismatches) {
  row["query"] = query;
  row.update(query_timing_fields(t, threads, row["ray_count"].get<double>()));
  row["ratio_to_embree"] = nullptr;
  row["cpu_ratio_to_embree"] = nullptr;
  row[query == "closest" ? "thread_mismatches" : "any_hit_mismatches"] = mismatches;
  if (mismatches && (query == "closest" || is_exact(row["accelerator"].get<std::string>())))
    row["verified"] = false;
  report_["results"].push_back(row);
}

}  // namespace

nlohmann::json run_suite(const Suite& suite, const RunOptions& options) {
  std::filesystem::create_directories(options.out_dir);
  Runner runner(suite, options);
  return runner.run();
}

}  // namespace ab
