#include "integrators/bidir/grid_statistics.h"

#include <array>
#include <cmath>
#include <limits>

namespace caustica::bidir {

double finite_quantile(const std::vector<double>& values, double q) {
  std::vector<double> finite;
  finite.reserve(values.size());
  for (double v : values)
    if (std::isfinite(v)) finite.push_back(v);
  if (finite.empty()) return 0.0;
  const size_t at = std::min(finite.size() - 1, size_t(double(finite.size()) * q));
  std::nth_element(finite.begin(), finite.begin() + at, finite.end());
  return finite[at];
}

namespace {

// The running window sum of one line (a row, or a column's value in each of a band of
// columns): enter() adds or removes a value, an infinite one counted instead of summed.
struct Window {
  double sum = 0;
  int count = 0, infinite = 0;
  void enter(double v, int sign) {
    if (std::isfinite(v))
      sum += sign * v;
    else
      infinite += sign;  // NaN counts as infinite
    count += sign;
  }
  double value() const {
    return infinite > 0 ? std::numeric_limits<double>::infinity() : sum / count;
  }
};

constexpr int kColumnBand = 64;  // columns swept together, a row of them at a time

}  // namespace

std::vector<double> box_blur(const std::vector<double>& in, int w, int h, int r) {
  std::vector<double> tmp(in.size()), out(in.size());
  // Rows, then columns, each independent of the others: in parallel, the same sums.
  tbb::parallel_for(0, h, [&](int y) {
    const double* src = &in[size_t(y) * w];
    double* dst = &tmp[size_t(y) * w];
    Window win;
    for (int i = 0; i < std::min(r, w); ++i) win.enter(src[i], 1);
    for (int i = 0; i < w; ++i) {
      if (i + r < w) win.enter(src[i + r], 1);
      if (i - r - 1 >= 0) win.enter(src[i - r - 1], -1);
      dst[i] = win.value();
    }
  });
  // Each column's window takes the same steps as a row's, but a band of columns advances one
  // row at a time, so that every step reads and writes along rows (a column of its own walked
  // the image at a stride of w, a cache line per value).
  tbb::parallel_for(0, (w + kColumnBand - 1) / kColumnBand, [&](int band) {
    const int x0 = band * kColumnBand, n = std::min(kColumnBand, w - x0);
    std::array<Window, kColumnBand> win{};
    const auto enter = [&](int y, int sign) {
      const double* row = &tmp[size_t(y) * w + x0];
      for (int k = 0; k < n; ++k) win[k].enter(row[k], sign);
    };
    for (int i = 0; i < std::min(r, h); ++i) enter(i, 1);
    for (int i = 0; i < h; ++i) {
      if (i + r < h) enter(i + r, 1);
      if (i - r - 1 >= 0) enter(i - r - 1, -1);
      double* row = &out[size_t(i) * w + x0];
      for (int k = 0; k < n; ++k) row[k] = win[k].value();
    }
  });
  return out;
}

}  // namespace caustica::bidir
