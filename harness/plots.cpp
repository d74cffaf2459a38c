#include "harness/plots.h"

#include <cstdlib>
#include <filesystem>
#include <iostream>

namespace ab {

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

}  // namespace ab
