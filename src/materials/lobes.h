// Which lobes a BxDF may sample or count in its pdf (pbrt-v4's BxDFReflTransFlags). The public
// BxDF interface always uses both; the layered BSDF restricts its interfaces with this.
#pragma once

#include <cstdint>

namespace caustica {

enum class Lobes : uint8_t { Reflection = 1, Transmission = 2, All = 3 };
inline bool has(Lobes set, Lobes l) { return (uint8_t(set) & uint8_t(l)) != 0; }

}  // namespace caustica
