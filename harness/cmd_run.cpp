// `accelbench run [SUITE.json] [-o DIR] [--shard K/N [--plan]]`: runs a
// benchmark suite (the built-in default when none is given), or one shard of it
// (harness/shard.h), writes DIR/report.json, DIR/report.csv and
// DIR/gbench.json, prints the summary table, and draws the plots with
// scripts/plot when Debian's Python has matplotlib. Exit 1 when a verification
// failed, 2 for a bad suite (before any work starts), 130 when interrupted by
// SIGINT or SIGTERM (finished cases are kept).
#include <atomic>
#include <csignal>
#include <filesystem>
#include <iomanip>
#include <iostream>

#include "accel/core/error.h"
#include "harness/cli.h"
#include "harness/machine.h"
#include "harness/plots.h"
#include "harness/report.h"
#include "harness/run.h"
#include "harness/shard.h"
#include "harness/suite.h"
#include "harness/terminal.h"

namespace ab {
namespace {

std::atomic<bool> g_interrupted{false};

/// SIGINT (Ctrl-C) and SIGTERM (a scheduler's time limit or scancel): stop
/// after the current case.
extern "C" void on_interrupt(int signal) {
  g_interrupted.store(true);
  std::signal(signal, SIG_DFL);  // a second one ends the process at once
}

struct RunArgs {
  std::string suite;
  std::string out;
  std::string shard;
  bool plan = false;
  bool no_plot = false;
};

std::string default_out_dir() {
  return "results/" + utc_now("%Y%m%dT%H%M%SZ");
}

/// `--plan`: every shard's scenes and estimated share of the work.
void print_plan(const Suite& suite, int count) {
  const nlohmann::json partition = shard_json(suite, {1, count})["partition"];
  double total = 0.0;
  for (const auto& s : partition) total += s["estimated_cost"].get<double>();
  for (size_t k = 0; k < partition.size(); ++k) {
    const auto& s = partition[k];
    const double share = total > 0 ? 100.0 * s["estimated_cost"].get<double>() / total : 0.0;
    const size_t n = s["scenes"].size();
    std::cout << "shard " << k + 1 << "/" << count << ": " << n << (n == 1 ? " scene, " : " scenes, ")
              << std::fixed << std::setprecision(1) << share << "% of the estimated work:";
    for (const auto& label : s["scenes"]) std::cout << " " << label.get<std::string>();
    if (n == 0) std::cout << " none";
    std::cout << "\n";
  }
}

void print_failures(const nlohmann::json& report, bool color) {
  const Colors c = colors(color);
  for (const auto& f : report["failures"])
    std::cout << c.red << "FAILED: " << f.get<std::string>() << c.reset << "\n";
  if (!report["verified"].get<bool>())
    std::cout << c.red << "run: VERIFICATION FAILED (" << report["failures"].size() << " failures)" << c.reset
              << "\n";
}

int run_command(const RunArgs& a) {
  const Suite whole = a.suite.empty() ? default_suite() : read_suite(a.suite);
  validate_suite(whole);  // bad names or parameters: one line and exit 2, before any work
  const ShardSpec shard = a.shard.empty() ? ShardSpec{} : parse_shard(a.shard);
  if (a.plan) {
    print_plan(whole, shard.count);
    return 0;
  }
  const Suite suite = a.shard.empty() ? whole : shard_suite(whole, shard);
  RunOptions options;
  if (!a.shard.empty()) {
    options.shard = shard_json(whole, shard);
    std::cout << "run: shard " << a.shard << " of suite '" << whole.name << "': " << suite.scenes.size()
              << " of " << whole.scenes.size() << " scenes\n";
  }
  options.out_dir = a.out.empty() ? default_out_dir() : a.out;
  options.progress = stderr_is_terminal();
  options.color = stderr_is_terminal();
  options.interrupted = &g_interrupted;
  g_interrupted.store(false);
  std::error_code ec;
  std::filesystem::create_directories(options.out_dir, ec);
  if (ec || !std::filesystem::is_directory(options.out_dir))
    throw InputError(options.out_dir + ": cannot create output folder" + (ec ? ": " + ec.message() : ""));
  auto previous_int = std::signal(SIGINT, on_interrupt);
  auto previous_term = std::signal(SIGTERM, on_interrupt);
  const nlohmann::json report = run_suite(suite, options);
  std::signal(SIGINT, previous_int);
  std::signal(SIGTERM, previous_term);
  const bool color = stdout_is_terminal();
  print_summary_table(std::cout, report, color);
  print_failures(report, color);
  std::cout << "report: " << options.out_dir << "/report.json, report.csv, gbench.json\n";
  if (report["interrupted"].get<bool>()) {
    std::cout << "run: interrupted; the report keeps the finished cases\n";
    return 130;
  }
  if (!a.no_plot && draw_plots(options.out_dir)) std::cout << "plots: " << options.out_dir << "/*.png\n";
  return report["verified"].get<bool>() ? 0 : 1;
}

const CommandRegistrar kRun{{"run",
                             "run a benchmark suite (built-in default when none is given): "
                             "report.json, report.csv, plots",
                             80, [](CLI::App& app) -> std::function<int()> {
                               auto a = std::make_shared<RunArgs>();
                               app.add_option("suite", a->suite,
                                              "suite file (JSON, see docs/suites.md); default: the "
                                              "built-in suite")
                                   ->check(CLI::ExistingFile);
                               app.add_option("-o,--output", a->out,
                                              "output folder (default results/<UTC timestamp>/)");
                               CLI::Option* shard = app.add_option("--shard", a->shard,
                                                                   "run shard K of N of the suite (by "
                                                                   "scene; merge the shards with "
                                                                   "accelbench merge)")
                                                        ->type_name("K/N");
                               app.add_flag("--plan", a->plan,
                                            "with --shard: print every shard's scenes and share of the "
                                            "work, run nothing")
                                   ->needs(shard);
                               app.add_flag("--no-plot", a->no_plot, "do not run scripts/plot");
                               return [a] { return run_command(*a); };
                             }}};

}  // namespace
}  // namespace ab
