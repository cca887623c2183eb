// RGB values of pbrt-v4's named spectra (placeholder values, replaced below).
#include <string>
#include <unordered_map>

#include "materials/materials.h"

namespace caustica {

std::optional<Rgb> named_spectrum_rgb(std::string_view name) {
  static const std::unordered_map<std::string_view, Rgb> table = {
      {"metal-Cu-eta", Rgb(0.2f, 0.92f, 1.1f)},
      {"metal-Cu-k", Rgb(3.9f, 2.45f, 2.14f)},
  };
  const auto it = table.find(name);
  if (it == table.end()) return std::nullopt;
  return it->second;
}

}  // namespace caustica
