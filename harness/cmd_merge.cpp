// `accelbench merge DIR... -o DIR`: one run folder (report.json, report.csv, gbench.json, plots) from every
// shard of one suite and commit (harness/merge.h). Exit 2 with one line for shards that do not make one run
// (nothing is written then), 1 when the merged run's verification failed, 0 otherwise.
#include <filesystem>
#include <iostream>

#include "accel/core/error.h"
#include "harness/cli.h"
#include "harness/merge.h"
#include "harness/plots.h"
#include "harness/report.h"
#include "harness/terminal.h"

namespace ab {
namespace {

namespace fs = std::filesystem;

struct MergeArgs {
  std::vector<std::string> dirs;
  std::string out;
  bool no_plot = false;
};

/// The output folder must not be one of the shards (their reports would be overwritten).
void check_output(const MergeArgs& a) {
  std::error_code ec;
  for (const std::string& d : a.dirs)
    if (fs::exists(a.out) && fs::equivalent(d, a.out, ec))
      throw InputError("-o " + a.out + ": is one of the shard folders (give a new folder)");
}

int merge_command(const MergeArgs& a) {
  check_output(a);
  const MergedRun run = merge_shards(a.dirs);  // every check before anything is written
  std::error_code ec;
  fs::create_directories(a.out, ec);
  if (ec || !fs::is_directory(a.out))
    throw InputError(a.out + ": cannot create output folder" + (ec ? ": " + ec.message() : ""));
  write_merged(run, a.out);
  const bool color = stdout_is_terminal();
  print_summary_table(std::cout, run.report, color);
  const Colors c = colors(color);
  for (const auto& f : run.report["failures"])
    std::cout << c.red << "FAILED: " << f.get<std::string>() << c.reset << "\n";
  for (const std::string& note : run.notes) std::cout << note << "\n";
  std::cout << "merge: " << a.dirs.size() << " shards, " << run.report["scenes"].size() << " scenes, "
            << run.report["results"].size() << " result rows into " << a.out
            << "/report.json, report.csv, gbench.json\n";
  if (!a.no_plot && draw_plots(a.out)) std::cout << "plots: " << a.out << "/*.png\n";
  const bool verified = run.report["verified"].get<bool>();
  if (!verified)
    std::cout << c.red << "merge: VERIFICATION FAILED (" << run.report["failures"].size() << " failures)"
              << c.reset << "\n";
  return verified ? 0 : 1;
}

const CommandRegistrar kMerge{
    {"merge",
     "merge the shards of one suite (run --shard K/N) into one report: report.json, report.csv, plots", 85,
     [](CLI::App& app) -> std::function<int()> {
       auto a = std::make_shared<MergeArgs>();
       app.add_option("dirs", a->dirs, "the shard folders (each written by accelbench run SUITE --shard K/N)")
           ->required()
           ->check(CLI::ExistingDirectory);
       app.add_option("-o,--output", a->out, "output folder of the merged run")->required();
       app.add_flag("--no-plot", a->no_plot, "do not run scripts/plot");
       return [a] { return merge_command(*a); };
     }}};

}  // namespace
}  // namespace ab
