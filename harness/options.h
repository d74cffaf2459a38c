// Options shared by several subcommands (--mesh/--scene, --param), added and read the same way everywhere.
#pragma once

#include "accel/core/params.h"

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace ab {

/// --mesh F | --scene F (exactly one).
struct TargetOptions {
  std::string mesh;
  std::string scene;
  /// Adds both options to app, mutually exclusive, the files checked for existence.
  void add(CLI::App& app);
};

/// Turns repeated --param k=v values into Params (throws ParamError naming the bad one).
Params params_from(const std::vector<std::string>& kvs);

}  // namespace ab
