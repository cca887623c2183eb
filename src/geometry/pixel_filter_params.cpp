#include "geometry/pixel_filter_params.h"

namespace caustica {

PixelFilterParams PixelFilterParams::defaults(PixelFilterKind kind) {
  PixelFilterParams p;
  p.kind = kind;
  // pbrt-v4 src/pbrt/filters.cpp, each filter's Create().
  switch (kind) {
    case PixelFilterKind::Box:
      p.radius = {0.5f, 0.5f};
      break;
    case PixelFilterKind::Gaussian:
      p.radius = {1.5f, 1.5f};
      break;
    case PixelFilterKind::Triangle:
    case PixelFilterKind::Mitchell:
      p.radius = {2.f, 2.f};
      break;
    case PixelFilterKind::Lanczos:
      p.radius = {4.f, 4.f};
      break;
  }
  return p;
}

const char* pixel_filter_name(PixelFilterKind kind) {
  switch (kind) {
    case PixelFilterKind::Box:
      return "box";
    case PixelFilterKind::Gaussian:
      return "gaussian";
    case PixelFilterKind::Triangle:
      return "triangle";
    case PixelFilterKind::Mitchell:
      return "mitchell";
    case PixelFilterKind::Lanczos:
      return "sinc";
  }
  return "?";
}

std::optional<PixelFilterKind> pixel_filter_kind(std::string_view name) {
  if (name == "box") return PixelFilterKind::Box;
  if (name == "gaussian") return PixelFilterKind::Gaussian;
  if (name == "triangle") return PixelFilterKind::Triangle;
  if (name == "mitchell") return PixelFilterKind::Mitchell;
  if (name == "sinc" || name == "lanczos") return PixelFilterKind::Lanczos;
  return std::nullopt;
}

}  // namespace caustica
