#include "integrators/bidir/grid_statistics.h"

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

std::vector<double> box_blur(const std::vector<double>& in, int w, int h, int r) {
  std::vector<double> tmp(in.size()), out(in.size());
  auto pass = [r](const double* src, double* dst, int n, int stride) {
    double sum = 0;
    int count = 0, infinite = 0;
    auto enter = [&](double v, int sign) {
      if (std::isfinite(v))
        sum += sign * v;
      else
        infinite += sign;  // NaN counts as infinite
      count += sign;
    };
    for (int i = 0; i < std::min(r, n); ++i) enter(src[size_t(i) * stride], 1);
    for (int i = 0; i < n; ++i) {
      if (i + r < n) enter(src[size_t(i + r) * stride], 1);
      if (i - r - 1 >= 0) enter(src[size_t(i - r - 1) * stride], -1);
      dst[size_t(i) * stride] =
          infinite > 0 ? std::numeric_limits<double>::infinity() : sum / count;
    }
  };
  // Rows, then columns, each independent of the others: in parallel, the same sums.
  tbb::parallel_for(0, h, [&](int y) { pass(&in[size_t(y) * w], &tmp[size_t(y) * w], w, 1); });
  tbb::parallel_for(0, w, [&](int x) { pass(&tmp[x], &out[x], h, w); });
  return out;
}

}  // namespace caustica::bidir
