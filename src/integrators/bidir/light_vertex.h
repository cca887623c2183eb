// Compact storage of light-subpath vertices: 32 bytes each, two to a cache line.
//
// What a stored vertex must give back: its position (range search, connections), the direction
// toward its predecessor wo, the primitive it lies on (its BSDF is rebuilt from the hit record
// at connection time, Scene::interaction_at), its depth, the throughput and the MIS sums.
//
//   word 0  position: 3 x 21-bit fixed point inside the scene bounds (1e-6 of the extent;
//           connections re-project the point onto its primitive, merging never notices)
//   word 1  wo: octahedral 2 x 16 bit (~5e-5 rad) | dense primitive index (32 bit)
//   word 2  dVCM (24) | dVC (24) | depth (8) | throughput shared exponent (8)
//   word 3  dVM (24) | throughput mantissas 3 x 13 bit (relative error <= 2^-14 of the largest)
//
// The MIS sums are non-negative floats with the sign and the 7 lowest mantissa bits dropped
// (rounded): relative error 2^-17, far below the 1e-4 the partition-of-unity test allows.
#pragma once

#include <bit>
#include <cstdint>

#include "core/rgb.h"
#include "core/vec.h"
#include "integrators/bidir/mis.h"

namespace caustica::bidir {

struct LightVertex {
  uint64_t position;
  uint64_t direction_and_primitive;
  uint64_t mis_a;
  uint64_t mis_b;
};
static_assert(sizeof(LightVertex) == 32, "light vertices are meant to be 32 bytes");

// Everything a light vertex holds, unpacked.
struct LightVertexData {
  Vec3 p;
  Vec3 wo;
  uint32_t primitive = 0;
  int depth = 0;  // segments from the light: y1 has depth 1
  Rgb throughput;
  MisSums mis;
};

// Fixed-point positions in a box (the scene bounds, slightly enlarged).
class PositionCodec {
 public:
  PositionCodec() = default;
  PositionCodec(Vec3 lo, Vec3 hi);
  uint64_t encode(Vec3 p) const;
  Vec3 decode(uint64_t bits) const {
    constexpr uint64_t mask = (1u << 21) - 1;
    return {lo_.x + float(bits & mask) * step_.x, lo_.y + float((bits >> 21) & mask) * step_.y,
            lo_.z + float((bits >> 42) & mask) * step_.z};
  }

 private:
  Vec3 lo_, step_{1, 1, 1}, inv_step_{1, 1, 1};
};

LightVertex pack_light_vertex(const LightVertexData& v, const PositionCodec& codec);
LightVertexData unpack_light_vertex(const LightVertex& v, const PositionCodec& codec);
inline int light_vertex_depth(const LightVertex& v) { return int((v.mis_a >> 48) & 0xff); }

// Helpers exposed for the tests.
uint32_t encode_octahedral(Vec3 w);
Vec3 decode_octahedral(uint32_t bits);
uint32_t encode_mis_value(float v);  // 24 bits
inline float decode_mis_value(uint32_t bits) { return std::bit_cast<float>(bits << 7); }

}  // namespace caustica::bidir
