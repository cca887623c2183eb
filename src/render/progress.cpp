#include "render/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>

namespace caustica {

std::string format_duration(double s) {
  if (!std::isfinite(s) || s < 0) return "--:--";
  const long total = long(s + 0.5);
  char buf[32];
  if (total >= 3600)
    std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", total / 3600, (total / 60) % 60, total % 60);
  else
    std::snprintf(buf, sizeof buf, "%02ld:%02ld", total / 60, total % 60);
  return buf;
}

ProgressBar::ProgressBar(std::string label, bool quiet, std::FILE* out)
    : label_(std::move(label)),
      quiet_(quiet),
      tty_(!quiet && isatty(fileno(out))),
      out_(out),
      start_(std::chrono::steady_clock::now()),
      last_print_(start_) {}

double ProgressBar::elapsed_seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void ProgressBar::update(double fraction, double rate, const char* unit) {
  if (quiet_ || finished_) return;
  fraction = std::clamp(fraction, 0.0, 1.0);
  const auto now = std::chrono::steady_clock::now();
  const double since = std::chrono::duration<double>(now - last_print_).count();
  const double elapsed = elapsed_seconds();
  const double eta = fraction > 0 ? elapsed * (1 - fraction) / fraction : -1;
  if (tty_) {
    if (since < 0.1 && fraction < 1) return;
    constexpr int kWidth = 30;
    const int filled = int(fraction * kWidth);
    std::string bar(size_t(filled), '=');
    if (filled < kWidth) bar += '>' + std::string(size_t(kWidth - filled - 1), ' ');
    std::fprintf(out_, "\r%s [%s] %3d%% %s ETA %s %.2f %s ", label_.c_str(), bar.c_str(),
                 int(fraction * 100), format_duration(elapsed).c_str(),
                 format_duration(eta).c_str(), rate, unit);
    std::fflush(out_);
  } else {
    // Plain lines: every 10% or 5 s, whichever comes first.
    if (fraction < 1 && since < 5 && fraction - last_fraction_printed_ < 0.1) return;
    std::fprintf(out_, "%s %3d%% elapsed %s ETA %s %.2f %s\n", label_.c_str(), int(fraction * 100),
                 format_duration(elapsed).c_str(), format_duration(eta).c_str(), rate, unit);
    last_fraction_printed_ = fraction;
  }
  last_print_ = now;
}

void ProgressBar::finish() {
  if (quiet_ || finished_) return;
  finished_ = true;
  if (tty_) std::fprintf(out_, "\n");
}

}  // namespace caustica
