// Compact storage of light-subpath vertices: 40 bytes each.
//
// What a stored vertex must give back: its position (range search, connections), the direction
// toward its predecessor wo, the primitive it lies on (its BSDF is rebuilt from the hit record
// at connection time, Scene::interaction_at), its depth, the throughput and the MIS sums.
//
//   bytes  0-11  position: the hit point's three floats, exactly. Fixed point inside the scene
//                bounds (the former 32-byte layout) made the step grow with the scene's extent:
//                one far-away object put photons off their surface and merging went dark.
//   bytes 12-15  dense primitive index
//   bytes 16-19  wo: octahedral 2 x 16 bit (~5e-5 rad)
//   bytes 20-31  the four MIS sums (mis.h: dVCM and the three class sums) as 24-bit floats: sign,
//                8-bit exponent and 15 mantissa bits, rounded (relative error <= 2^-16)
//   bytes 32-39  depth (8) | throughput shared exponent (8) | mantissas 3 x 16 bit (relative error
//                <= 2^-17 of the largest channel)
// Why 40 and not 32: exact positions take 96 bits, the primitive and wo 64; the 96 left are not
// enough for the MIS sums at the precision the partition-of-unity test needs (1e-4) plus the
// throughput and depth. 40 bytes keeps a vertex within one cache line more often than not (8 of
// 8 consecutive vertices fit in 5 lines) and is 62% of SmallVCM's 64-byte vertex.
#pragma once

#include <cstdint>

#include "core/rgb.h"
#include "core/vec.h"
#include "integrators/bidir/mis.h"

namespace caustica::bidir {

struct LightVertex {
  float position[3];
  uint32_t primitive;
  uint32_t wo;      // octahedral
  uint8_t mis[12];  // four 24-bit floats
  uint64_t depth_and_throughput;

  Vec3 p() const { return {position[0], position[1], position[2]}; }
};
static_assert(sizeof(LightVertex) == 40, "light vertices are meant to be 40 bytes");

// Everything a light vertex holds, unpacked.
struct LightVertexData {
  Vec3 p;
  Vec3 wo;
  uint32_t primitive = 0;
  int depth = 0;  // segments from the light: y1 has depth 1
  Rgb throughput;
  MisSums mis;
};

LightVertex pack_light_vertex(const LightVertexData& v);
LightVertexData unpack_light_vertex(const LightVertex& v);
inline int light_vertex_depth(const LightVertex& v) { return int(v.depth_and_throughput & 0xff); }

// Helpers exposed for the tests.
uint32_t encode_octahedral(Vec3 w);
Vec3 decode_octahedral(uint32_t bits);

}  // namespace caustica::bidir
