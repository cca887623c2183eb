// Which light subpath a pixel's camera subpath connects to.
//
// With one light path per pixel (N >= pixel count) pixel p takes path p. With fewer paths,
// `pixel % N` made pixels exactly N apart share a path every iteration: correlated noise in a
// regular pattern. Instead, pixels are shuffled by a keyed bijection of [0, pixel_count) that
// changes every iteration, then dealt to the N paths in turn: each path still serves
// floor(P/N) or ceil(P/N) pixels, but which pixels share a path is scattered over the image and
// different in every iteration. Any assignment keeps the estimator unbiased (every light path
// is an independent sample of the same distribution); this one removes the structure.
#pragma once

#include <bit>
#include <cstdint>

#include "core/rng.h"

namespace caustica::bidir {

class LightPathAssignment {
 public:
  LightPathAssignment() = default;  // every pixel its own path
  LightPathAssignment(uint64_t pixel_count, uint64_t light_paths, uint32_t iteration, uint64_t seed)
      : pixels_(pixel_count), paths_(light_paths) {
    bits_ = pixel_count > 1 ? std::bit_width(pixel_count - 1) : 1;
    mask_ = bits_ >= 64 ? ~0ull : (1ull << bits_) - 1;
    const uint64_t k = hash_combine(hash_combine(seed, iteration), 0x1a55u);
    for (int r = 0; r < kRounds; ++r) keys_[r] = mix_bits(k + uint64_t(r) * 0x9e3779b97f4a7c15ull);
  }

  uint64_t light_path(uint64_t pixel) const {
    if (paths_ >= pixels_) return pixel;
    uint64_t x = pixel;
    do x = permute(x);  // cycle-walking: a bijection of [0, 2^bits) restricted to [0, P)
    while (x >= pixels_);
    return x % paths_;
  }

 private:
  static constexpr int kRounds = 3;
  // Each step is invertible modulo 2^bits: odd multiply, add, xor with a right shift of itself.
  uint64_t permute(uint64_t x) const {
    for (int r = 0; r < kRounds; ++r) {
      x = (x * (keys_[r] | 1)) & mask_;
      x = (x + (keys_[r] >> 32)) & mask_;
      x ^= x >> ((bits_ + 1) / 2);
    }
    return x;
  }

  uint64_t pixels_ = 0, paths_ = 0;
  int bits_ = 1;
  uint64_t mask_ = 1;
  uint64_t keys_[kRounds] = {};
};

}  // namespace caustica::bidir
