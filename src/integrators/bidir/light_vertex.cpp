#include "integrators/bidir/light_vertex.h"

#include <algorithm>
#include <cmath>

namespace caustica::bidir {

namespace {
constexpr uint32_t kPositionMax = (1u << 21) - 1;
constexpr int kMantissaBits = 13;
constexpr uint64_t kMantissaMask = (1u << kMantissaBits) - 1;

// Shared-exponent RGB: the largest channel keeps 13 significant bits.
void encode_throughput(Rgb c, uint32_t* exponent, uint64_t* mantissas) {
  const float m = std::max(c.max_component(), 0.f);
  if (!(m > 0) || !std::isfinite(m)) {
    *exponent = 0;
    *mantissas = 0;
    return;
  }
  int e;
  std::frexp(m, &e);  // m = f * 2^e, f in [0.5, 1)
  auto quantise = [&](float v, int exp) {
    return uint64_t(std::lround(std::max(v, 0.f) * std::ldexp(1.f, kMantissaBits - exp)));
  };
  if (quantise(m, e) > kMantissaMask) ++e;  // rounding carried into the next binade
  e = std::clamp(e, -126, 127);
  *exponent = uint32_t(e + 128);
  *mantissas = std::min(quantise(c.r, e), kMantissaMask) |
               std::min(quantise(c.g, e), kMantissaMask) << kMantissaBits |
               std::min(quantise(c.b, e), kMantissaMask) << (2 * kMantissaBits);
}

Rgb decode_throughput(uint32_t exponent, uint64_t mantissas) {
  if (exponent == 0) return Rgb(0.f);
  const float scale = std::ldexp(1.f, int(exponent) - 128 - kMantissaBits);
  return {float(mantissas & kMantissaMask) * scale,
          float((mantissas >> kMantissaBits) & kMantissaMask) * scale,
          float((mantissas >> (2 * kMantissaBits)) & kMantissaMask) * scale};
}

uint32_t snorm16(float v) {
  return uint32_t(std::lround((std::clamp(v, -1.f, 1.f) * 0.5f + 0.5f) * 65535.f));
}
float from_snorm16(uint32_t b) { return float(b) / 65535.f * 2.f - 1.f; }
}  // namespace

PositionCodec::PositionCodec(Vec3 lo, Vec3 hi) {
  const Vec3 margin = (hi - lo) * 1e-3f + Vec3(1e-4f, 1e-4f, 1e-4f);
  lo_ = lo - margin;
  const Vec3 extent = hi + margin - lo_;
  for (int i = 0; i < 3; ++i) {
    step_[i] = extent[i] / float(kPositionMax);
    inv_step_[i] = 1.f / step_[i];
  }
}

uint64_t PositionCodec::encode(Vec3 p) const {
  uint64_t bits = 0;
  for (int i = 0; i < 3; ++i) {
    const float q = std::clamp((p[i] - lo_[i]) * inv_step_[i], 0.f, float(kPositionMax));
    bits |= uint64_t(std::lround(q)) << (21 * i);
  }
  return bits;
}

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

uint32_t encode_mis_value(float v) {
  if (!(v > 0)) return 0;                            // also NaN
  const uint32_t bits = std::bit_cast<uint32_t>(v);  // sign bit is 0
  return std::min((bits + 0x40u) >> 7, 0x7f7fffffu >> 7);
}

LightVertex pack_light_vertex(const LightVertexData& v, const PositionCodec& codec) {
  uint32_t exponent;
  uint64_t mantissas;
  encode_throughput(v.throughput, &exponent, &mantissas);
  LightVertex out;
  out.position = codec.encode(v.p);
  out.direction_and_primitive = uint64_t(encode_octahedral(v.wo)) | uint64_t(v.primitive) << 32;
  out.mis_a = uint64_t(encode_mis_value(v.mis.vcm)) | uint64_t(encode_mis_value(v.mis.vc)) << 24 |
              uint64_t(std::clamp(v.depth, 0, 255)) << 48 | uint64_t(exponent) << 56;
  out.mis_b = uint64_t(encode_mis_value(v.mis.vm)) | mantissas << 24;
  return out;
}

LightVertexData unpack_light_vertex(const LightVertex& v, const PositionCodec& codec) {
  LightVertexData d;
  d.p = codec.decode(v.position);
  d.wo = decode_octahedral(uint32_t(v.direction_and_primitive));
  d.primitive = uint32_t(v.direction_and_primitive >> 32);
  d.mis.vcm = decode_mis_value(uint32_t(v.mis_a & 0xffffff));
  d.mis.vc = decode_mis_value(uint32_t((v.mis_a >> 24) & 0xffffff));
  d.depth = light_vertex_depth(v);
  d.mis.vm = decode_mis_value(uint32_t(v.mis_b & 0xffffff));
  d.throughput = decode_throughput(uint32_t(v.mis_a >> 56), v.mis_b >> 24);
  return d;
}

}  // namespace caustica::bidir
