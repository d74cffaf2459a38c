// The CLI: one file per subcommand (harness/cmd_*.cpp), each registering itself here.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

namespace ab {

/// A subcommand: `setup` adds its options to `app` (already created with name and description) and
/// returns the action to run after parsing; the action returns the exit code (0, 1 or 2) and may throw
/// InputError (printed as one line, exit 2).
struct Command {
  std::string name;         ///< the subcommand's word
  std::string description;  ///< one line for --help
  int order = 100;          ///< position in --help
  std::function<std::function<int()>(CLI::App& app)> setup;
};

/// Registers a command at static-initialization time.
struct CommandRegistrar {
  /// Adds `command` to the table, in order.
  explicit CommandRegistrar(Command command);
};

/// Every command, in order.
const std::vector<Command>& commands();

/// Runs the CLI (main() calls this); returns the exit code.
int run_cli(int argc, char** argv);

/// CLI11 validator: accepts a registered accelerator name (or a comma list when `list` is true, with "all").
CLI::Validator accelerator_name_validator(bool list = false);

}  // namespace ab
