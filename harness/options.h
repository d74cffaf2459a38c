// Options shared by several subcommands (--mesh/--scene, --param), added and read the same way everywhere.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "accel/core/params.h"

namespace ab {

/// The frame selector of an animated scene: --time T (T in [0, 1]) or --frame F --frames N (time
/// F / (N - 1)); `render` also takes --frames A-B (an animation). A static scene ignores it.
struct FrameOptions {
  double time = -1.0;  ///< --time T (negative: not given)
  int64_t frame = -1;  ///< --frame F (negative: not given)
  std::string frames;  ///< --frames N (or A-B for render)
  /// Adds the three options to app (--time excludes the other two).
  void add(CLI::App& app);
  /// The normalized time they select (0 when none is given). Throws InputError for --frame without
  /// --frames, a frame out of range, or a malformed --frames (a range A-B only when `allow_range`).
  float normalized_time(bool allow_range = false) const;
  /// True when --frames is a range A-B (render's animation); sets first and last.
  bool range(uint64_t& first, uint64_t& last) const;
};

/// --mesh F | --scene F (exactly one), and the frame selector.
struct TargetOptions {
  std::string mesh;    ///< --mesh F
  std::string scene;   ///< --scene F
  FrameOptions frame;  ///< --time T | --frame F --frames N
  /// Adds both options (mutually exclusive, the files checked for existence) and the frame selector.
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
