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
#include <cstdint>

namespace caustica {

__extension__ typedef __int128 FixedSum;

inline constexpr double kFixedSumMaxValue = 2147483648.0;  // 2^31

inline FixedSum to_fixed(double v) {
  v = v < -kFixedSumMaxValue ? -kFixedSumMaxValue : (v > kFixedSumMaxValue ? kFixedSumMaxValue : v);
  // trunc(v 2^64) without the libgcc call that a double -> __int128 conversion is (1% of a path
  // tracer's profile): the integer part and the fraction (exact: a - trunc(a)) scaled exactly
  // by 2^64, each by one hardware conversion to 64 bits; the same value bit for bit.
  const bool negative = v < 0;
  const double a = negative ? -v : v;  // [0, 2^31]
  const uint64_t whole = uint64_t(a);
  const uint64_t fraction = uint64_t((a - double(whole)) * 0x1p64);  // < 2^64
  const FixedSum magnitude = (FixedSum(whole) << 64) | FixedSum(fraction);
  return negative ? -magnitude : magnitude;
}

// Correctly rounded to the nearest double (libgcc's __floattidf), then scaled exactly.
inline double from_fixed(FixedSum s) { return std::ldexp(double(s), -64); }

}  // namespace caustica
