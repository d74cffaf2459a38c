#include "harness/cli.h"

#include <algorithm>
#include <iostream>

#include "accel/core/error.h"
#include "accel/core/registry.h"
#include "harness/selection.h"

namespace ab {

namespace {
std::vector<Command>& command_table() {
  static std::vector<Command> t;
  return t;
}

/// One line on stderr, exit 2: the contract's answer to bad input.
int fail_input(const std::string& message) {
  std::cerr << "accelbench: " << message << "\n";
  return 2;
}

std::string first_line(const std::string& s) {
  return s.substr(0, s.find('\n'));
}
}  // namespace

CommandRegistrar::CommandRegistrar(Command command) {
  auto& t = command_table();
  t.push_back(std::move(command));
  std::stable_sort(t.begin(), t.end(), [](const Command& a, const Command& b) { return a.order < b.order; });
}

const std::vector<Command>& commands() {
  return command_table();
}

CLI::Validator accelerator_name_validator(bool list) {
  return CLI::Validator(
      [list](std::string& value) -> std::string {
        for (const std::string& name : split_list(value)) {
          if (list && name == "all") continue;
          try {
            find_accelerator(name);
          } catch (const UnknownAccelerator& e) {
            return e.what();
          }
        }
        return {};
      },
      list ? "ACCEL[,ACCEL...]|all" : "ACCEL");
}

int run_cli(int argc, char** argv) {
  CLI::App app{"accelbench: benchmark and research harness for ray-tracing acceleration structures",
               "accelbench"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "accelbench 0.1");
  std::vector<std::pair<CLI::App*, std::function<int()>>> actions;
  for (const Command& c : commands()) {
    CLI::App* sub = app.add_subcommand(c.name, c.description);
    actions.emplace_back(sub, c.setup(*sub));
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return fail_input(first_line(e.what()));
  }
  for (auto& [sub, action] : actions) {
    if (!sub->parsed()) continue;
    try {
      return action();
    } catch (const InputError& e) {
      return fail_input(first_line(e.what()));
    } catch (const std::bad_alloc&) {
      std::cerr << "accelbench: out of memory\n";
      return 3;
    }
  }
  return fail_input("no subcommand given (see --help)");
}

}  // namespace ab
