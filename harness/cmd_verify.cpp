// `accelbench verify (--mesh F | --scene F) [--accel all|NAME,...] [--rays FILE.rays | --kind KIND --count
// N]` Traces with every named accelerator, with brute force and with Embree; prints the agreement table; exit
// 1 on any hit that differs from brute's, or any disagreement with Embree that is not explained. The outside
// references (cgal, bullet) are classified against brute force as Embree's hits are (agree, tie, edge,
// graze, limit, rounding), an unexplained disagreement failing the same way.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <memory>

#include "accel/core/registry.h"
#include "accel/reference/embree_device.h"
#include "harness/cli.h"
#include "harness/compare.h"
#include "harness/hitfile.h"
#include "harness/options.h"
#include "harness/selection.h"
#include "harness/target.h"
#include "harness/verification.h"

namespace ab {
namespace {

struct VerifyArgs {
  TargetOptions target;
  std::string accels = "all";
  std::string rays;
  std::string kind;
  uint64_t count = 10000;
  uint64_t seed = 1;
  int threads = 0;
};

/// The accelerators to check: "all" (every listed one but Embree, brute force first; for a scene, only those
/// that can be its top level, which leaves out the outside references cgal and bullet), or the named ones
/// with brute force put first when it is not named (Embree is the reference of the agreement columns).
std::vector<std::string> accelerator_list(const std::string& spec, bool scene) {
  std::vector<std::string> names;
  for (const std::string& name : split_list(spec)) {
    if (name == "all") {
      names = listed_accelerators({kEmbreeName});
      if (scene)
        std::erase_if(names, [](const std::string& n) { return !find_accelerator(n).make_for_instances; });
      return names;
    }
    if (name != kEmbreeName) names.push_back(name);
  }
  if (std::find(names.begin(), names.end(), "brute") == names.end()) names.insert(names.begin(), "brute");
  return names;
}

/// Builds `name` over the target with its default parameters and traces the rays.
std::vector<Hit> trace_with(const Target& target, const std::string& name, const std::vector<Ray>& rays,
                            int threads, double& build_seconds) {
  const std::unique_ptr<Accelerator> accel = build_default(target, name);
  build_seconds = accel->stats().build_seconds;
  return closest_hits(*accel, rays, threads);
}

/// One row of the table: the build time, the comparison with brute force and the classified agreement.
void print_row(const std::string& name, double build, const std::string& vs_brute, const Agreement& ag) {
  std::printf("%-16s %9.3f  %-22s %9llu %7llu %7llu %7llu %7llu %8llu %11llu\n", name.c_str(), build,
              vs_brute.c_str(), (unsigned long long)ag.agree, (unsigned long long)ag.tie,
              (unsigned long long)ag.edge, (unsigned long long)ag.graze, (unsigned long long)ag.limit,
              (unsigned long long)ag.rounding, (unsigned long long)ag.unexplained);
  if (!ag.unexplained) return;
  std::printf("  unexplained disagreements at rays:");
  for (uint64_t i : ag.unexplained_rays) std::printf(" %llu", (unsigned long long)i);
  std::printf("\n");
}

/// Whether `name` is held to brute force byte for byte (the project's structures) or, as an outside
/// reference (cgal, bullet), has its hits classified against brute force's.
bool classified_against_brute(const std::string& name) {
  return name != "brute" && !is_exact(name);
}

int run_verify(const VerifyArgs& a) {
  const Target target = load_target(a.target.mesh, a.target.scene, a.target.frame.normalized_time());
  std::vector<Ray> rays;
  if (!a.rays.empty())
    rays = read_rays(a.rays);
  else
    rays = make_target_rays(target, a.kind.empty() ? "incoherent" : a.kind, a.count, a.seed);
  const HitTriangleAtFn triangle_of = hit_triangles(target);
  double embree_build = 0.0;
  const std::vector<Hit> embree = trace_with(target, kEmbreeName, rays, a.threads, embree_build);
  std::vector<Hit> brute;
  bool failed = false;
  std::printf("%s: %zu triangles, %zu rays\n", target.path.c_str(), size_t(target.triangles), rays.size());
  std::printf("%-16s %9s  %-22s %9s %7s %7s %7s %7s %8s %11s\n", "accelerator", "build s", "vs brute",
              "agree", "tie", "edge", "graze", "limit", "rounding", "unexplained");
  for (const std::string& name : accelerator_list(a.accels, target.scene != nullptr)) {
    double build = 0.0;
    const std::vector<Hit> hits = trace_with(target, name, rays, a.threads, build);
    std::string vs_brute = "reference";
    Agreement ag;
    if (name == "brute") {
      brute = hits;
    } else if (classified_against_brute(name)) {
      vs_brute = "classified (columns)";
      ag = classify_agreement(rays, brute, hits, triangle_of);
    } else {
      const IdenticalResult r = compare_identical(brute, hits);
      vs_brute = r.identical() ? "identical" : std::to_string(r.differing) + " DIFFER";
      if (!r.identical()) {
        failed = true;
        vs_brute += " (first ray " + std::to_string(r.first_differences.front()) + ")";
      }
    }
    if (!classified_against_brute(name)) ag = classify_agreement(rays, hits, embree, triangle_of);
    if (ag.unexplained) failed = true;
    print_row(name, build, vs_brute, ag);
  }
  std::printf(
      "%-16s %9.3f  (reference for the agreement columns; outside references (cgal, bullet) are\n"
      "%-16s %9s   classified against brute instead)\n",
      kEmbreeName, embree_build, "", "");
  std::printf(failed ? "verify: FAILED\n" : "verify: all accelerators agree\n");
  return failed ? 1 : 0;
}

const CommandRegistrar kVerify{
    {"verify", "trace with accelerators, brute force and Embree; print the agreement table", 50,
     [](CLI::App& app) -> std::function<int()> {
       auto a = std::make_shared<VerifyArgs>();
       a->target.add(app);
       app.add_option("--accel", a->accels, "all, or a comma-separated list of accelerators")
           ->check(accelerator_name_validator(true));
       auto* rays = app.add_option("--rays", a->rays, "input .rays file")->check(CLI::ExistingFile);
       auto* kind = app.add_option("--kind", a->kind, "ray kind to generate (default incoherent)");
       app.add_option("--count", a->count, "rays to generate")
           ->check(CLI::Range(uint64_t{1}, uint64_t{100'000'000}));
       app.add_option("--seed", a->seed, "random seed for generated rays");
       add_threads_option(app, a->threads);
       rays->excludes(kind);
       return [a] { return run_verify(*a); };
     }}};

}  // namespace
}  // namespace ab
