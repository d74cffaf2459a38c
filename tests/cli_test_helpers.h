// What the tests that run the accelbench binary share: finding it, running it and reading what it wrote.
#pragma once

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>

namespace ab::test {

/// The accelbench binary (CTest sets ACCELBENCH_BIN), "" when not set.
inline std::string accelbench_bin() {
  const char* b = std::getenv("ACCELBENCH_BIN");
  return b ? b : "";
}

/// The binary to run: ACCELBENCH_BIN, else build/accelbench (a test started from the source folder).
inline std::string accelbench_exe() {
  const std::string b = accelbench_bin();
  return b.empty() ? "build/accelbench" : b;
}

/// Runs a shell command; returns its exit code (-1 when it did not exit).
inline int shell(const std::string& cmd) {
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// A file's bytes ("" when it cannot be read).
inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Runs `accelbench ARGS` with stdout discarded and stderr kept in dir/stderr.txt; its exit code and stderr.
inline std::pair<int, std::string> run_accelbench(const std::string& args, const std::filesystem::path& dir) {
  const std::filesystem::path err = dir / "stderr.txt";
  const int code = shell(accelbench_exe() + " " + args + " >/dev/null 2>" + err.string());
  return {code, read_text(err)};
}

}  // namespace ab::test
