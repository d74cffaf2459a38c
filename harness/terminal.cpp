#include "harness/terminal.h"

#include <unistd.h>

#include <cstdio>
#include <iomanip>
#include <iostream>
#include <memory>

namespace ab {

bool stderr_is_terminal() {
  return ::isatty(2) == 1;
}
bool stdout_is_terminal() {
  return ::isatty(1) == 1;
}

Colors colors(bool enabled) {
  if (!enabled) return {};
  return {"\033[1;31m", "\033[32m", "\033[0m"};
}

Progress::Progress(size_t total, bool enabled)
    : total_(total ? total : 1), enabled_(enabled), start_(std::chrono::steady_clock::now()) {}

void Progress::step(const std::string& what) {
  ++done_;
  if (done_ > total_) done_ = total_;
  draw(what);
}

void Progress::draw(const std::string& what) {
  if (!enabled_) return;
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double frac = double(done_) / double(total_);
  const double eta = done_ ? elapsed * (1.0 - frac) / frac : 0.0;
  constexpr int kWidth = 30;
  const int filled = int(frac * kWidth);
  char eta_text[32];
  std::snprintf(eta_text, sizeof eta_text, "%d:%02d", int(eta) / 60, int(eta) % 60);
  std::cerr << "\r\033[K[" << std::string(filled, '#') << std::string(kWidth - filled, '.') << "] "
            << std::setw(3) << int(frac * 100) << "% ETA " << eta_text << "  " << what.substr(0, 60)
            << std::flush;
}

void Progress::finish() {
  if (enabled_) std::cerr << "\r\033[K" << std::flush;
}

std::function<void(size_t, size_t)> progress_callback(std::string what) {
  if (!stderr_is_terminal()) return {};
  auto bar = std::make_shared<std::unique_ptr<Progress>>();
  return [bar, what = std::move(what)](size_t done, size_t total) {
    if (!*bar) *bar = std::make_unique<Progress>(total, true);
    (*bar)->step(what);
    if (done >= total) (*bar)->finish();
  };
}

}  // namespace ab
