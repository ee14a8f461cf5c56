// A one-line progress bar on stderr for long renders (only when stderr is a terminal,
// so logs and CI output stay clean).
#pragma once
#include <chrono>
#include <cstdio>
#include <string>

namespace volley::cli {

class ProgressBar {
 public:
  explicit ProgressBar(std::string label);
  /// Redraws at most ~10 times a second; fraction in [0, 1].
  void update(double fraction);
  /// Clears the bar line.
  void finish();
  bool enabled() const { return enabled_; }

 private:
  std::string label_;
  bool enabled_;
  std::chrono::steady_clock::time_point start_, last_;
};

}  // namespace volley::cli
