// A progress bar on stderr: percent, elapsed, ETA and throughput. On a terminal it redraws
// one line; otherwise (CI logs, pipes) it prints a plain line at most every few seconds.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>

namespace caustica {

class ProgressBar {
 public:
  // `quiet` disables all output (tests).
  ProgressBar(std::string label, bool quiet = false, std::FILE* out = stderr);
  // fraction in [0,1]; rate_label like "Mrays/s" with its value.
  void update(double fraction, double rate, const char* rate_unit);
  void finish();
  double elapsed_seconds() const;

 private:
  std::string label_;
  bool quiet_, tty_;
  std::FILE* out_;
  std::chrono::steady_clock::time_point start_, last_print_;
  double last_fraction_printed_ = -1;
  bool finished_ = false;
};

std::string format_duration(double seconds);

}  // namespace caustica
