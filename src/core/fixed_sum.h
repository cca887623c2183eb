// Exact, order-independent sums of estimates: signed 64.64 fixed point.
//
// Why: a render split over processes (render/ranks.h) must give the image one process gives,
// bit for bit. Floating-point addition is not associative, so per-rank double sums added at the
// end differ from one sequential double sum. Integer addition is associative and commutative:
// each estimate (a camera sample, a pixel of merged splats: the same on every process) is
// converted once to fixed point, and any grouping of those integers — one process, K ranks, an
// MPI reduction tree — gives the same total.
//
// Range and resolution: 2^-64 (5.4e-20) absolute resolution; a value is truncated toward zero
// below that, so a double above 2^-12 converts exactly (its 53-bit mantissa fits), a float
// above 2^-41. An estimate is clamped to |v| <= 2^31, so a total of fewer than 2^32 estimates
// (a camera sample and a splat in each of 2^31 iterations) stays below 2^127 and cannot
// overflow.
#pragma once

#include <cmath>

namespace caustica {

__extension__ typedef __int128 FixedSum;

inline constexpr double kFixedSumMaxValue = 2147483648.0;  // 2^31

inline FixedSum to_fixed(double v) {
  v = v < -kFixedSumMaxValue ? -kFixedSumMaxValue : (v > kFixedSumMaxValue ? kFixedSumMaxValue : v);
  // Scaling by a power of two is exact (no overflow below 2^95; a subnormal scales up exactly),
  // the same as std::ldexp(v, 64) without the call; then truncation.
  return FixedSum(v * 0x1p64);
}

// Correctly rounded to the nearest double (libgcc's __floattidf), then scaled exactly.
inline double from_fixed(FixedSum s) { return std::ldexp(double(s), -64); }

}  // namespace caustica
