// What the CLI draws on a terminal: whether a stream is one, the ANSI colors of verdicts, the progress bar.
#pragma once

#include <chrono>
#include <cstddef>
#include <functional>
#include <string>

namespace ab {

/// True when stderr is a terminal (progress bar and colors).
bool stderr_is_terminal();
/// True when stdout is a terminal.
bool stdout_is_terminal();

/// ANSI escapes for verdicts; empty strings when color is off.
struct Colors {
  const char* red = "";    ///< failures
  const char* green = "";  ///< success
  const char* reset = "";  ///< back to normal
};
/// The escapes when `enabled`, empty ones otherwise.
Colors colors(bool enabled);

/// A progress bar with ETA on stderr, drawn only when enabled (stderr a terminal).
class Progress {
 public:
  /// `total` units of work; `enabled` false draws nothing.
  Progress(size_t total, bool enabled);
  /// One more unit done; `what` says what is running now.
  void step(const std::string& what);
  /// Clears the bar.
  void finish();

 private:
  void draw(const std::string& what);
  size_t total_;
  size_t done_ = 0;
  bool enabled_;
  std::chrono::steady_clock::time_point start_;
};

/// A (done, total) callback drawing a Progress labelled `what` when stderr is a terminal (the bar is made on
/// the first call, cleared when done reaches total); empty when stderr is not a terminal. Calls must not
/// overlap (the caller serializes them).
std::function<void(size_t done, size_t total)> progress_callback(std::string what);

}  // namespace ab
