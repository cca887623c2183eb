// bfloat16: a float's top 16 bits (sign, the full 8-bit exponent, 7 mantissa bits), rounded to
// nearest even. Same range as float (infinities kept, NaN stays NaN), relative error <= 2^-8.
// For large per-pixel tables of statistics whose sampling noise far exceeds that rounding.
#pragma once

#include <bit>
#include <cstdint>

namespace caustica {

inline uint16_t to_bfloat16(float v) {
  const uint32_t bits = std::bit_cast<uint32_t>(v);
  if ((bits & 0x7fffffffu) > 0x7f800000u) return uint16_t(bits >> 16 | 0x40);  // quiet NaN
  // Round to nearest, ties to even; a finite value that rounds past the largest one becomes
  // infinity, as float arithmetic would.
  return uint16_t((bits + 0x7fffu + ((bits >> 16) & 1u)) >> 16);
}

inline float from_bfloat16(uint16_t b) { return std::bit_cast<float>(uint32_t(b) << 16); }

}  // namespace caustica
