// `accelbench run [SUITE.json] [-o DIR]`: runs a benchmark suite (the built-in default when none is given),
// writes DIR/report.json, DIR/report.csv and DIR/gbench.json, prints the summary table, and draws the
// plots with scripts/plot when Debian's Python has matplotlib. Exit 1 when a verification failed,
// 2 for a bad suite (before any work starts), 130 when interrupted (finished cases are kept).
#include <atomic>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <iostream>

#include "accel/core/error.h"
#include "harness/cli.h"
#include "harness/machine.h"
#include "harness/report.h"
#include "harness/run.h"
#include "harness/suite.h"
#include "harness/terminal.h"

namespace ab {
namespace {

std::atomic<bool> g_interrupted{false};

extern "C" void on_sigint(int) {
  g_interrupted.store(true);
  std::signal(SIGINT, SIG_DFL);  // a second Ctrl-C ends the process at once
}

struct RunArgs {
  std::string suite;
  std::string out;
  bool no_plot = false;
};

std::string default_out_dir() {
  return "results/" + utc_now("%Y%m%dT%H%M%SZ");
}

/// Runs scripts/plot DIR with Debian's Python when it can import matplotlib; returns whether it drew.
bool draw_plots(const std::string& dir) {
  const std::string script = std::string(ACCELBENCH_SOURCE_DIR) + "/scripts/plot";
  if (!std::filesystem::exists(script) || !std::filesystem::exists("/usr/bin/python3")) return false;
  if (std::system("/usr/bin/python3 -c 'import matplotlib' >/dev/null 2>&1") != 0) {
    std::cout << "plots: skipped (/usr/bin/python3 cannot import matplotlib)\n";
    return false;
  }
  const std::string cmd = "/usr/bin/python3 '" + script + "' '" + dir + "'";
  return std::system(cmd.c_str()) == 0;
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
  const Suite suite = a.suite.empty() ? default_suite() : read_suite(a.suite);
  validate_suite(suite);  // bad names or parameters: one line and exit 2, before any work
  RunOptions options;
  options.out_dir = a.out.empty() ? default_out_dir() : a.out;
  options.progress = stderr_is_terminal();
  options.color = stderr_is_terminal();
  options.interrupted = &g_interrupted;
  g_interrupted.store(false);
  std::error_code ec;
  std::filesystem::create_directories(options.out_dir, ec);
  if (ec || !std::filesystem::is_directory(options.out_dir))
    throw InputError(options.out_dir + ": cannot create output folder" + (ec ? ": " + ec.message() : ""));
  auto previous = std::signal(SIGINT, on_sigint);
  const nlohmann::json report = run_suite(suite, options);
  std::signal(SIGINT, previous);
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

const CommandRegistrar kRun{
    {"run", "run a benchmark suite (built-in default when none is given): report.json, report.csv, plots", 80,
     [](CLI::App& app) -> std::function<int()> {
       auto a = std::make_shared<RunArgs>();
       app.add_option("suite", a->suite, "suite file (JSON, see docs/suites.md); default: the built-in suite")
           ->check(CLI::ExistingFile);
       app.add_option("-o,--output", a->out, "output folder (default results/<UTC timestamp>/)");
       app.add_flag("--no-plot", a->no_plot, "do not run scripts/plot");
       return [a] { return run_command(*a); };
     }}};

}  // namespace
}  // namespace ab
