// The plots of a run folder: scripts/plot DIR, drawn by Debian's Python when it can import matplotlib.
#pragma once

#include <string>

namespace ab {

/// Runs scripts/plot DIR with /usr/bin/python3 when it can import matplotlib (prints a line when it cannot);
/// returns whether it drew.
bool draw_plots(const std::string& dir);

}  // namespace ab
