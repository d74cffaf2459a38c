// `accelbench compare BASE NEW [--threshold P] [--alpha A] [--cpu] [--json F] [--csv F]`: two runs (folders
// or report.json files) case by case; exit 1 on a significant regression beyond the threshold, 0 otherwise, 2
// on bad input.
#include <iostream>
#include <memory>

#include "datasets/atomic_file.h"
#include "harness/cli.h"
#include "harness/compare_runs.h"

namespace ab {
namespace {

struct CompareArgs {
  std::string base, next;
  double threshold_percent = 5.0;
  double alpha = 0.05;
  std::string json, csv;
  bool cpu = false;
};

int run_compare(const CompareArgs& a) {
  const nlohmann::json base = load_run_report(a.base);
  const nlohmann::json next = load_run_report(a.next);
  const RunComparison c = compare_runs(base, next, a.threshold_percent / 100.0, a.alpha, a.cpu);
  print_comparison(std::cout, c);
  if (!a.json.empty())
    write_file_atomically(
        a.json, [&](std::ostream& out) { out << to_json(c).dump(2) << "\n"; }, false);
  if (!a.csv.empty())
    write_file_atomically(
        a.csv, [&](std::ostream& out) { out << to_csv(c); }, false);
  return c.regressed() ? 1 : 0;
}

const CommandRegistrar kCompare{
    {"compare", "compare two runs case by case (ratio of medians, Mann-Whitney U); exit 1 on a regression",
     85, [](CLI::App& app) -> std::function<int()> {
       auto a = std::make_shared<CompareArgs>();
       app.add_option("base", a->base, "the earlier run: its folder or report.json")->required();
       app.add_option("new", a->next, "the run to judge: its folder or report.json")->required();
       app.add_option("--threshold", a->threshold_percent,
                      "percent change that counts (default 5): throughput or build time")
           ->check(CLI::Range(0.0, 1000.0));
       app.add_option("--alpha", a->alpha, "significance level of the Mann-Whitney U test (default 0.05)")
           ->check(CLI::Range(0.0, 1.0));
       app.add_flag("--cpu", a->cpu, "compare queries by the process's cpu seconds (not wall seconds)");
       app.add_option("--json", a->json, "write the table as JSON");
       app.add_option("--csv", a->csv, "write the table as CSV");
       return [a] { return run_compare(*a); };
     }}};

}  // namespace
}  // namespace ab
