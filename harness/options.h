// Options shared by several subcommands (--mesh/--scene, --param), added and read the same way everywhere.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "accel/core/params.h"

namespace ab {

/// --mesh F | --scene F (exactly one).
struct TargetOptions {
  std::string mesh;   ///< --mesh F
  std::string scene;  ///< --scene F
  /// Adds both options to app, mutually exclusive, the files checked for existence.
  void add(CLI::App& app);
};

/// The structure options of trace and render besides --accel: --accel-top and --accel-bottom (scenes: the
/// structure of one level) and repeated --param k=v.
struct StructureOptions {
  std::string top;                  ///< --accel-top NAME
  std::string bottom;               ///< --accel-bottom NAME
  std::vector<std::string> params;  ///< --param k=v, in order
  /// Adds the three options to app (names checked against the registry).
  void add(CLI::App& app);
};

/// Adds --threads T (0: all cores) to app.
void add_threads_option(CLI::App& app, int& threads);

/// Turns repeated --param k=v values into Params (throws ParamError naming the bad one).
Params params_from(const std::vector<std::string>& kvs);

}  // namespace ab
