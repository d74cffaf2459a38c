// Shared by the fuzz targets: hand libFuzzer's bytes to the path-taking readers through one file
// per process in /dev/shm (tmpfs; /tmp is a real disk here, 2.8 ms per input), and treat
// ab::InputError as the one acceptable way to reject input.
#pragma once

#include <fcntl.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace fuzz {

/// Path of this process's input file, removed at exit.
inline std::string& input_path() {
  static std::string path;
  return path;
}

/// Writes the input to this process's file with extension `ext` (the readers dispatch on it) and
/// returns its path: the same name every time, so no files pile up. FUZZ_TMPDIR overrides /dev/shm.
inline const std::string& write_input(const uint8_t* data, size_t size, const std::string& ext) {
  std::string& path = input_path();
  if (path.empty()) {
    const char* dir = std::getenv("FUZZ_TMPDIR");
    path = std::string(dir ? dir : "/dev/shm") + "/accelbench-fuzz-" + std::to_string(getpid()) + "." + ext;
    std::atexit([] { ::unlink(input_path().c_str()); });
  }
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) std::abort();
  for (size_t done = 0; done < size;) {
    const ssize_t n = ::write(fd, data + done, size - done);
    if (n <= 0) std::abort();
    done += static_cast<size_t>(n);
  }
  ::close(fd);
  return path;
}

}  // namespace fuzz

/// Contract check: abort (a finding) when a reader accepted something it must not.
#define FUZZ_CHECK(cond)                                                                  \
  do {                                                                                    \
    if (!(cond)) {                                                                        \
      std::fprintf(stderr, "FUZZ_CHECK failed: %s (%s:%d)\n", #cond, __FILE__, __LINE__); \
      std::abort();                                                                       \
    }                                                                                     \
  } while (0)
