// PCG32 random streams (O'Neill 2014). Streams are keyed by what is being sampled
// (pixel or light-path index, iteration, user seed), never by thread, so images are
// bit-identical for any thread count.
#pragma once

#include <cstdint>

#include "core/math.h"
#include "core/vec.h"

namespace caustica {

// SplitMix64 finaliser: a cheap, well-mixed 64-bit hash.
constexpr uint64_t mix_bits(uint64_t v) {
  v ^= v >> 31;
  v *= 0x7fb5d329728ea185ull;
  v ^= v >> 27;
  v *= 0x81dadef4bc2dd44dull;
  v ^= v >> 33;
  return v;
}
constexpr uint64_t hash_combine(uint64_t a, uint64_t b) {
  return mix_bits(a ^ (mix_bits(b) + 0x9e3779b97f4a7c15ull + (a << 6) + (a >> 2)));
}

class Pcg32 {
 public:
  Pcg32() { set_sequence(0, 0x853c49e6748fea9bull); }
  Pcg32(uint64_t sequence, uint64_t seed) { set_sequence(sequence, seed); }
  // The canonical key: one stream per (index, iteration, seed).
  static Pcg32 for_sample(uint64_t index, uint64_t iteration, uint64_t seed) {
    return Pcg32(index, hash_combine(hash_combine(seed, iteration), 0x5eedull));
  }

  void set_sequence(uint64_t sequence, uint64_t seed) {
    state_ = 0u;
    inc_ = (sequence << 1u) | 1u;
    next_u32();
    state_ += seed;
    next_u32();
  }
  uint32_t next_u32() {
    const uint64_t old = state_;
    state_ = old * 0x5851f42d4c957f2dull + inc_;
    const uint32_t xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
    const uint32_t rot = uint32_t(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31));
  }
  // Uniform in [0, 1).
  float next_float() { return std::min(kOneMinusEpsilon, float(next_u32()) * 0x1p-32f); }
  Vec2 next_2d() {
    const float a = next_float();
    return {a, next_float()};
  }
  // Uniform integer in [0, bound).
  uint32_t next_bounded(uint32_t bound) {
    const uint32_t threshold = (~bound + 1u) % bound;
    for (;;) {
      const uint32_t r = next_u32();
      if (r >= threshold) return r % bound;
    }
  }

 private:
  uint64_t state_ = 0, inc_ = 0;
};

}  // namespace caustica
