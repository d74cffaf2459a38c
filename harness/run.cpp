#include "harness/run.h"

#include <oneapi/tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <memory>

#include "accel/core/registry.h"
#include "accel/core/trace.h"
#include "datasets/atomic_file.h"
#include "datasets/generators.h"
#include "datasets/rays.h"
#include "harness/bench.h"
#include "harness/compare.h"
#include "harness/hitfile.h"
#include "harness/machine.h"
#include "harness/report.h"
#include "harness/target.h"

namespace ab {

double pearson(const std::vector<double>& x, const std::vector<double>& y) {
  const size_t n = std::min(x.size(), y.size());
  if (n < 2) return std::nan("");
  double mx = 0, my = 0;
  for (size_t i = 0; i < n; ++i) mx += x[i], my += y[i];
  mx /= double(n);
  my /= double(n);
  double sxy = 0, sxx = 0, syy = 0;
  for (size_t i = 0; i < n; ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
    syy += (y[i] - my) * (y[i] - my);
  }
  return sxx > 0 && syy > 0 ? sxy / std::sqrt(sxx * syy) : std::nan("");
}

namespace {

using nlohmann::json;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::string utc_now_iso() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

bool is_registered(const std::string& name) {
  const auto& all = accelerators();
  return std::any_of(all.begin(), all.end(), [&](const AcceleratorInfo& a) { return a.name == name; });
}

/// A ray set of one scene with the reference answers every configuration is checked against.
struct RaySet {
  const RaySpec* spec = nullptr;
  std::vector<Ray> rays;
  uint64_t brute_checked = 0;  ///< the first brute_checked rays are traced by brute force
  std::vector<Hit> brute;      ///< brute force on those rays
  std::vector<Hit> reference;  ///< the verified reference structure on all rays
  std::vector<Hit> embree;     ///< Embree on all rays (empty when not compared)
};

json timing_json(const Timing& t) {
  return {{"median", t.median},
          {"min", t.min},
          {"max", t.max},
          {"mean", t.mean},
          {"stddev", t.stddev},
          {"repetitions", t.repetitions},
          {"iterations", t.iterations}};
}

class Runner {
 public:
  Runner(const Suite& suite, const RunOptions& options)
      : suite_(suite), options_(options), progress_(count_units(), options.progress) {}

  json run();

 private:
  size_t count_units() const;
  json header() const;
  bool stopping();
  void fail(const std::string& what);
  void save();
  void run_scene(const SceneSpec& scene);
  Target load(const SceneSpec& scene) const;
  std::vector<RaySet> make_ray_sets(const Target& target) const;
  void make_references(const Target& target, const SceneSpec& scene, std::vector<RaySet>& sets);
  std::unique_ptr<Accelerator> build(const Target& target, const std::string& scene, const AccelSpec& spec,
                                     json& base);
  void run_config(const Target& target, const SceneSpec& scene, const AccelSpec& spec,
                  std::vector<RaySet>& sets);
  json verify(const Target& target, const std::string& what, const AccelSpec& spec, const RaySet& set,
              const std::vector<Hit>& hits);
  void time_closest(const Accelerator& accel, const std::string& name, RaySet& set,
                    const std::vector<Hit>& expected, json row);
  void time_any(const Accelerator& accel, const std::string& name, RaySet& set, bool exact, json row);
  Timing time_query(const std::string& name, size_t rays, const std::function<void()>& work);
  void add_timed_row(json row, const Timing& t, int threads, const std::string& query, uint64_t mismatches);
  void fill_ratios();
  void fill_correlations();

  const Suite& suite_;
  const RunOptions& options_;
  Progress progress_;
  BenchTimer timer_;
  json report_;
  bool interrupted_ = false;
};

size_t Runner::count_units() const {
  size_t per_config = 1;
  if (!suite_.build_only)
    for (const auto& r : suite_.rays) per_config += 1 + suite_.threads.size() * (r.any_hit ? 2 : 1);
  return suite_.scenes.size() * (1 + suite_.accelerators.size() * per_config);
}

json Runner::header() const {
  json suite = suite_.json;
  return {
      {"schema_version", kReportSchemaVersion},
      {"tool", "accelbench run"},
      {"date", utc_now_iso()},
      {"seed", suite_.seed},
      {"suite_name", suite_.name},
      {"suite_source", suite_.source},
      {"suite", suite},
      {"machine", machine_info()},
      {"compiler", compiler_info()},
      {"source", source_info()},
      {"libraries", library_versions()},
      {"max_threads", tbb::info::default_concurrency()},
      {"verification",
       {{"brute_rays", suite_.verify.brute_rays},
        {"reference", suite_.verify.reference},
        {"embree", suite_.verify.embree},
        {"method",
         "each configuration's hits (counting pass) are compared byte for byte with brute force on the first "
         "brute_rays rays of every set (0: all), and with the reference structure (itself checked against "
         "brute force on those rays) on all rays; the timed passes' hits at every thread count must equal "
         "the counting pass's; any-hit answers must equal whether the reference found a hit; Embree's hits "
         "are classified agree/tie/edge/graze/limit/unexplained, and an unexplained disagreement fails the "
         "run"}}},
      {"verified", true},
      {"interrupted", false},
      {"failures", json::array()},
      {"scenes", json::array()},
      {"builds", json::array()},
      {"results", json::array()},
      {"sah_correlation", json::array()}};
}

bool Runner::stopping() {
  if (options_.interrupted && options_.interrupted->load()) interrupted_ = true;
  return interrupted_;
}

void Runner::fail(const std::string& what) {
  report_["verified"] = false;
  report_["failures"].push_back(what);
  progress_.finish();
  const char* red = options_.color ? "\033[1;31m" : "";
  const char* reset = options_.color ? "\033[0m" : "";
  std::cerr << red << "VERIFICATION FAILED: " << what << reset << "\n";
}

void Runner::save() {
  fill_ratios();
  fill_correlations();
  report_["interrupted"] = interrupted_;
  write_report(report_, options_.out_dir);
  const std::string gbench = timer_.json();
  write_file_atomically((std::filesystem::path(options_.out_dir) / "gbench.json").string(),
                        [&](std::ostream& out) { out << gbench; }, false);
}

json Runner::run() {
  report_ = header();
  for (const SceneSpec& scene : suite_.scenes) {
    if (stopping()) break;
    run_scene(scene);
    save();
  }
  stopping();
  progress_.finish();
  save();
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
    set.rays = spec.path.empty() ? make_target_rays(target, rt, spec.kind, spec.count, suite_.seed) : read_rays(spec.path);
    sets.push_back(std::move(set));
  }
  return sets;
}

/// Brute force on the first brute_rays rays, the reference structure on all of them (checked against
/// brute force first), and Embree on all of them.
void Runner::make_references(const Target& target, const SceneSpec& scene, std::vector<RaySet>& sets) {
  if (sets.empty()) return;
  auto brute = make_target_accelerator(target, "brute", Params{});
  brute->build();
  auto reference = make_target_accelerator(target, suite_.verify.reference, Params{});
  reference->build();
  std::unique_ptr<Accelerator> embree;
  if (suite_.verify.embree && is_registered("embree")) {
    embree = make_target_accelerator(target, "embree", Params{});
    embree->build();
  }
  for (RaySet& set : sets) {
    const size_t n = set.rays.size();
    set.brute_checked = suite_.verify.brute_rays == 0 ? n : std::min<uint64_t>(n, suite_.verify.brute_rays);
    set.brute.resize(set.brute_checked);
    trace_closest(*brute, std::span<const Ray>(set.rays).first(set.brute_checked), set.brute, 0);
    set.reference.resize(n);
    trace_closest(*reference, set.rays, set.reference, 0);
    const IdenticalResult r =
        compare_identical(set.brute, std::span<const Hit>(set.reference).first(set.brute_checked));
    if (!r.identical())
      fail(scene.label + " / " + set.spec->label + ": the reference " + suite_.verify.reference +
           " differs from brute on " + std::to_string(r.differing) + " of " + std::to_string(r.compared) +
           " rays (first ray " + std::to_string(r.first_differences.front()) + ")");
    if (embree) {
      set.embree.resize(n);
      trace_closest(*embree, set.rays, set.embree, 0);
    }
  }
}

void Runner::run_scene(const SceneSpec& scene) {
  const auto t0 = std::chrono::steady_clock::now();
  const Target target = load(scene);
  std::vector<RaySet> sets = make_ray_sets(target);
  make_references(target, scene, sets);
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
                                {"file", s.spec->path},
                                {"count", s.rays.size()},
                                {"brute_checked", s.brute_checked}});
  info["setup_seconds"] = seconds_since(t0);
  report_["scenes"].push_back(info);
  progress_.step(scene.label + ": references ready");
  for (const AccelSpec& spec : suite_.accelerators) {
    if (stopping()) return;
    run_config(target, scene, spec, sets);
  }
}

std::unique_ptr<Accelerator> Runner::build(const Target& target, const std::string& scene,
                                           const AccelSpec& spec, json& base) {
  std::unique_ptr<Accelerator> accel;
  auto pass = [&] {
    accel.reset();
    accel = make_target_accelerator(target, spec.name, Params(spec.params));
    accel->build();
    return accel->stats().build_seconds;
  };
  const Timing t = timer_.time("build/" + scene + "/" + spec.label, suite_.build_repetitions, 1, pass,
                               double(target.triangles));
  const BuildStats& s = accel->stats();
  const double tri = target.triangles ? double(target.triangles) : 1.0;
  base = {{"scene", scene},
          {"triangles", target.triangles},
          {"accelerator", spec.name},
          {"config_label", spec.label},
          {"params", spec.params},
          {"config", accel->config()},
          {"build_seconds_median", t.median},
          {"build_seconds_min", t.min},
          {"build_seconds_max", t.max},
          {"bytes", s.bytes},
          {"bytes_per_triangle", double(s.bytes) / tri},
          {"nodes", s.nodes},
          {"leaves", s.leaves},
          {"max_depth", s.max_depth},
          {"references_per_triangle", double(s.references) / tri},
          {"sah_cost", s.sah_cost > 0 ? json(s.sah_cost) : json()}};
  json b = {{"scene", scene},
            {"triangles", target.triangles},
            {"accelerator", spec.name},
            {"config_label", spec.label},
            {"params", spec.params},
            {"config", accel->config()},
            {"build_seconds", timing_json(t)},
            {"bytes_per_triangle", double(s.bytes) / tri},
            {"stats", to_json(s)},
            {"verification", json::array()}};
  report_["builds"].push_back(b);
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
  const bool exact = spec.name != "embree";  // every structure of the project matches brute byte for byte
  for (RaySet& set : sets) {
    if (stopping()) return;
    const std::string what = scene.label + " / " + spec.label + " / " + set.spec->label;
    std::vector<Hit> hits(set.rays.size());
    const RayCounters c = trace_closest_counted(*accel, set.rays, hits, 0);
    json row = base;
    row.update(verify(target, what, spec, set, hits));
    progress_.step(what + ": verified");
    row["rays"] = set.spec->label;
    row["ray_kind"] = set.spec->kind.empty() ? json() : json(set.spec->kind);
    row["ray_count"] = set.rays.size();
    if (exact) {
      row.update(to_json(c, set.rays.size()));
      row["havran_cost_per_ray"] = row["nodes_per_ray"].get<double>() + row["prims_per_ray"].get<double>();
    }
    time_closest(*accel, what, set, hits, row);
    if (set.spec->any_hit) time_any(*accel, what, set, exact, row);
  }
}

/// Checks one configuration's hits (from the counting pass) and returns the row's verification fields.
json Runner::verify(const Target& target, const std::string& what, const AccelSpec& spec, const RaySet& set,
                    const std::vector<Hit>& hits) {
  json v = {{"verified", true}};
  const bool exact = spec.name != "embree";
  if (exact) {
    const IdenticalResult b =
        compare_identical(set.brute, std::span<const Hit>(hits).first(set.brute_checked));
    const IdenticalResult r = compare_identical(set.reference, hits);
    v.update({{"brute_rays_checked", b.compared},
              {"brute_mismatches", b.differing},
              {"reference_rays_checked", r.compared},
              {"reference_mismatches", r.differing}});
    if (!b.identical())
      fail(what + ": " + std::to_string(b.differing) + " of " + std::to_string(b.compared) +
           " hits differ from brute (first ray " + std::to_string(b.first_differences.front()) + ")");
    else if (!r.identical())
      fail(what + ": " + std::to_string(r.differing) + " of " + std::to_string(r.compared) +
           " hits differ from " + suite_.verify.reference + " (first ray " +
           std::to_string(r.first_differences.front()) + ")");
    if (!b.identical() || !r.identical()) v["verified"] = false;
  }
  const std::vector<Hit>& theirs = exact ? set.embree : hits;
  const std::vector<Hit>& ours = exact ? hits : set.reference;
  if (!theirs.empty()) {
    const Agreement a = classify_agreement(set.rays, ours, theirs, hit_triangles(target));
    v.update({{"embree_agree", a.agree},
              {"embree_tie", a.tie},
              {"embree_edge", a.edge},
              {"embree_graze", a.graze},
              {"embree_limit", a.limit},
              {"embree_unexplained", a.unexplained}});
    if (a.unexplained) {
      v["verified"] = false;
      fail(what + ": " + std::to_string(a.unexplained) +
           " unexplained disagreements with embree (first ray " + std::to_string(a.unexplained_rays.front()) +
           ")");
    }
  }
  json detail = v;
  detail["rays"] = set.spec->label;
  report_["builds"].back()["verification"].push_back(detail);
  return v;
}

Timing Runner::time_query(const std::string& name, size_t rays, const std::function<void()>& work) {
  auto pass = [&] {
    const auto t0 = std::chrono::steady_clock::now();
    work();
    return seconds_since(t0);
  };
  double estimate = 0.0;  // the fastest warm-up pass (the least disturbed by other processes)
  for (int i = 0; i < suite_.warmup; ++i) {
    const double s = pass();
    estimate = i == 0 ? s : std::min(estimate, s);
  }
  const int64_t iterations = estimate > 0 ? iterations_for(estimate, suite_.min_time) : 1;
  return timer_.time(name, suite_.repetitions, iterations, pass, double(rays));
}

void Runner::add_timed_row(json row, const Timing& t, int threads, const std::string& query,
                           uint64_t mismatches) {
  const double n = row["ray_count"].get<double>();
  row["query"] = query;
  row["threads"] = threads;
  row["threads_used"] = threads > 0 ? threads : tbb::info::default_concurrency();
  row["repetitions"] = t.repetitions;
  row["iterations"] = t.iterations;
  row.update({{"seconds_median", t.median},
              {"seconds_min", t.min},
              {"seconds_max", t.max},
              {"seconds_mean", t.mean},
              {"seconds_stddev", t.stddev}});
  row["rays_per_second"] = t.median > 0 ? n / t.median : 0.0;
  row["rays_per_second_min"] = t.max > 0 ? n / t.max : 0.0;
  row["rays_per_second_max"] = t.min > 0 ? n / t.min : 0.0;
  row["ratio_to_embree"] = nullptr;
  row[query == "closest" ? "thread_mismatches" : "any_hit_mismatches"] = mismatches;
  if (mismatches && (query == "closest" || row["accelerator"] != "embree")) row["verified"] = false;
  report_["results"].push_back(row);
}

void Runner::time_closest(const Accelerator& accel, const std::string& name, RaySet& set,
                          const std::vector<Hit>& expected, json row) {
  for (int threads : suite_.threads) {
    if (stopping()) return;
    std::vector<Hit> out(set.rays.size());
    const std::string case_name = name + "/closest/threads:" + std::to_string(threads);
    const Timing t =
        time_query(case_name, set.rays.size(), [&] { trace_closest(accel, set.rays, out, threads); });
    const IdenticalResult r = compare_identical(expected, out);
    if (!r.identical())
      fail(case_name + ": " + std::to_string(r.differing) +
           " hits of the timed pass differ from the counting pass");
    add_timed_row(row, t, threads, "closest", r.differing);
    progress_.step(case_name);
  }
}

void Runner::time_any(const Accelerator& accel, const std::string& name, RaySet& set, bool exact, json row) {
  if (exact) {  // the any-hit counting pass (one thread; counters never run on the timed path)
    std::vector<uint8_t> counted(set.rays.size());
    RayCounters c;
    accel.occluded_counted(set.rays, counted, c);
    row.update(to_json(c, set.rays.size()));
    row["havran_cost_per_ray"] = row["nodes_per_ray"].get<double>() + row["prims_per_ray"].get<double>();
  }
  for (int threads : suite_.threads) {
    if (stopping()) return;
    std::vector<uint8_t> out(set.rays.size());
    const std::string case_name = name + "/any/threads:" + std::to_string(threads);
    const Timing t =
        time_query(case_name, set.rays.size(), [&] { trace_occluded(accel, set.rays, out, threads); });
    uint64_t mismatches = 0;
    for (size_t i = 0; i < out.size(); ++i) mismatches += (out[i] != 0) != set.reference[i].found();
    if (exact && mismatches)
      fail(case_name + ": " + std::to_string(mismatches) +
           " any-hit answers differ from the reference's closest hits");
    add_timed_row(row, t, threads, "any", mismatches);
    progress_.step(case_name);
  }
}

/// ratio_to_embree: rays/s over the rays/s of the first "embree" configuration on the same scene, ray set,
/// query and thread count.
void Runner::fill_ratios() {
  std::map<std::string, double> embree;
  auto key = [](const json& r) {
    return r.value("scene", "") + "\n" + r.value("rays", "") + "\n" + r.value("query", "") + "\n" +
           std::to_string(r.value("threads", -1));
  };
  for (const json& r : report_["results"])
    if (r.value("accelerator", "") == "embree" && r.contains("rays_per_second") && !embree.count(key(r)))
      embree[key(r)] = r["rays_per_second"].get<double>();
  for (json& r : report_["results"]) {
    const auto it = embree.find(key(r));
    if (r.contains("rays_per_second") && it != embree.end() && it->second > 0)
      r["ratio_to_embree"] = r["rays_per_second"].get<double>() / it->second;
  }
}

// Havran 2000 ("Heuristic Ray Shooting Algorithms", PhD thesis, ch. 2) judges structures by
// hardware-independent counts: traversal steps and intersection tests per ray, combined with the same
// costs the surface area heuristic (Goldsmith and Salmon 1987; MacDonald and Booth 1990) predicts with.
// The correlation is Pearson's product-moment coefficient.
/// Pearson's r between the SAH-predicted cost of each configuration and its measured Havran cost
/// (traversal steps + intersection tests per ray, costs 1 and 1 like sah_cost), per scene and ray set.
void Runner::fill_correlations() {
  std::map<std::pair<std::string, std::string>, json> groups;
  for (const json& r : report_["results"]) {
    if (r.value("query", "") != "closest" || r.value("threads", -1) != suite_.threads.front()) continue;
    if (!r["sah_cost"].is_number() || !r.contains("havran_cost_per_ray")) continue;
    json& g = groups[{r["scene"], r["rays"]}];
    g["points"].push_back({{"config_label", r["config_label"]},
                           {"sah_cost", r["sah_cost"]},
                           {"havran_cost_per_ray", r["havran_cost_per_ray"]}});
  }
  report_["sah_correlation"] = json::array();
  for (auto& [k, g] : groups) {
    std::vector<double> x, y;
    for (const json& p : g["points"]) x.push_back(p["sah_cost"]), y.push_back(p["havran_cost_per_ray"]);
    const double r = x.size() >= 3 ? pearson(x, y) : std::nan("");
    report_["sah_correlation"].push_back({{"scene", k.first},
                                          {"rays", k.second},
                                          {"configurations", x.size()},
                                          {"pearson", std::isnan(r) ? json() : json(r)},
                                          {"points", g["points"]}});
  }
}

}  // namespace

nlohmann::json run_suite(const Suite& suite, const RunOptions& options) {
  std::filesystem::create_directories(options.out_dir);
  Runner runner(suite, options);
  return runner.run();
}

}  // namespace ab
