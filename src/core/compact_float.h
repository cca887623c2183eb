// Floats in fewer bytes, for large tables whose values need float's range but not all of its
// precision.
//
// bfloat16: a float's top 16 bits (sign, the full 8-bit exponent, 7 mantissa bits), rounded to
// nearest even. Relative error <= 2^-8; infinities kept, NaN stays NaN. A sum kept in it stops
// growing once an increment falls below half its rounding step: only for sums of a few terms.
//
// float24: a float's top 24 bits (15 mantissa bits) in three bytes, rounded to nearest (ties
// away from zero). Relative error <= 2^-16; infinities and NaN kept.
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

inline void put_float24(uint8_t* out, float v) {
  uint32_t bits = std::bit_cast<uint32_t>(v);
  if ((bits & 0x7f800000u) != 0x7f800000u) bits += 0x80u;
  bits >>= 8;
  out[0] = uint8_t(bits);
  out[1] = uint8_t(bits >> 8);
  out[2] = uint8_t(bits >> 16);
}

inline float get_float24(const uint8_t* in) {
  return std::bit_cast<float>((uint32_t(in[0]) | uint32_t(in[1]) << 8 | uint32_t(in[2]) << 16)
                              << 8);
}

}  // namespace caustica
