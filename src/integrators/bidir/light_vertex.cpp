#include "integrators/bidir/light_vertex.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include "core/compact_float.h"

namespace caustica::bidir {

namespace {
constexpr int kMantissaBits = 16;
constexpr uint64_t kMantissaMask = (1u << kMantissaBits) - 1;

// 2^k as a float, exactly as std::ldexp(1.f, k) gives it (subnormal below 2^-126), without the
// library call: k in [-149, 127].
float power_of_two(int k) {
  return k >= -126 ? std::bit_cast<float>(uint32_t(k + 127) << 23)
                   : std::bit_cast<float>(uint32_t(1) << (k + 149));
}
// std::lround of a value in [0, 2^31), without the library call: in double, x + 0.5 is exact.
uint32_t round_nonnegative(double x) { return uint32_t(x + 0.5); }

// Shared-exponent RGB: the largest channel keeps 16 significant bits.
uint64_t encode_throughput(Rgb c) {
  const float m = std::max(c.max_component(), 0.f);
  if (!(m > 0) || !std::isfinite(m)) return 0;
  int e;
  std::frexp(m, &e);  // m = f * 2^e, f in [0.5, 1)
  auto quantise = [&](float v, int exp) {
    // In double: frexp's exponent of a tiny channel makes 2^(16 - exp) too large for a float
    // (exp down to -148). Scaling by a power of two is exact, so this is the float product
    // wherever that one exists.
    const double scale = std::bit_cast<double>(uint64_t(kMantissaBits - exp + 1023) << 52);
    return uint64_t(round_nonnegative(double(std::max(v, 0.f)) * scale));
  };
  if (quantise(m, e) > kMantissaMask) ++e;  // rounding carried into the next binade
  e = std::clamp(e, -126, 127);
  return uint64_t(e + 128) | std::min(quantise(c.r, e), kMantissaMask) << 8 |
         std::min(quantise(c.g, e), kMantissaMask) << (8 + kMantissaBits) |
         std::min(quantise(c.b, e), kMantissaMask) << (8 + 2 * kMantissaBits);
}

Rgb decode_throughput(uint64_t bits) {
  const uint32_t exponent = uint32_t(bits & 0xff);
  if (exponent == 0) return Rgb(0.f);
  const float scale = power_of_two(int(exponent) - 128 - kMantissaBits);
  return {float((bits >> 8) & kMantissaMask) * scale,
          float((bits >> (8 + kMantissaBits)) & kMantissaMask) * scale,
          float((bits >> (8 + 2 * kMantissaBits)) & kMantissaMask) * scale};
}

uint32_t snorm16(float v) {
  return round_nonnegative((std::clamp(v, -1.f, 1.f) * 0.5f + 0.5f) * 65535.f);
}
float from_snorm16(uint32_t b) { return float(b) / 65535.f * 2.f - 1.f; }

}  // namespace

uint32_t encode_octahedral(Vec3 w) {
  // Cigolle et al. 2014, "A Survey of Efficient Representations for Independent Unit Vectors".
  const float l1 = std::abs(w.x) + std::abs(w.y) + std::abs(w.z);
  float u = w.x / l1, v = w.y / l1;
  if (w.z < 0) {
    const float uu = (1 - std::abs(v)) * std::copysign(1.f, u);
    const float vv = (1 - std::abs(u)) * std::copysign(1.f, v);
    u = uu;
    v = vv;
  }
  return snorm16(u) | snorm16(v) << 16;
}

Vec3 decode_octahedral(uint32_t bits) {
  const float u = from_snorm16(bits & 0xffff), v = from_snorm16(bits >> 16);
  Vec3 w(u, v, 1 - std::abs(u) - std::abs(v));
  if (w.z < 0) {
    const float x = (1 - std::abs(v)) * std::copysign(1.f, u);
    const float y = (1 - std::abs(u)) * std::copysign(1.f, v);
    w.x = x;
    w.y = y;
  }
  return normalize(w);
}

LightVertex pack_light_vertex(const LightVertexData& v) {
  LightVertex out;
  out.position[0] = v.p.x;
  out.position[1] = v.p.y;
  out.position[2] = v.p.z;
  out.primitive = v.primitive;
  out.wo = encode_octahedral(v.wo);
  put_float24(out.mis, v.mis.vcm);
  put_float24(out.mis + 3, v.mis.rest);
  put_float24(out.mis + 6, v.mis.conn);
  put_float24(out.mis + 9, v.mis.merge);
  out.depth_and_throughput = uint64_t(std::clamp(v.depth, 0, 255)) | encode_throughput(v.throughput)
                                                                         << 8;
  return out;
}

LightVertexData unpack_light_vertex(const LightVertex& v) {
  LightVertexData d;
  d.p = v.p();
  d.wo = decode_octahedral(v.wo);
  d.primitive = v.primitive;
  d.depth = light_vertex_depth(v);
  d.mis = {get_float24(v.mis), get_float24(v.mis + 3), get_float24(v.mis + 6),
           get_float24(v.mis + 9), d.depth == 1};
  d.throughput = decode_throughput(v.depth_and_throughput >> 8);
  return d;
}

}  // namespace caustica::bidir
