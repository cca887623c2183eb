#include "io/pbrt/spectrum_param.h"

#include <charconv>
#include <cmath>
#include <limits>
#include <sstream>

#include "io/input_file.h"

namespace caustica::pbrt {

namespace {

std::vector<double> read_spectrum_file(const Param& p, const std::string& path) {
  std::string text;
  try {
    text = read_input_file(path);
  } catch (const std::runtime_error& e) {
    param_error(p, quote_excerpt(p.strings[0]) +
                       " is not a built-in named spectrum, and the file " +
                       quote_excerpt(path, kPathExcerpt) + " cannot be read: " + e.what());
  }
  std::istringstream in(text);
  std::vector<double> values;
  std::string line;
  while (std::getline(in, line)) {
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream words(line);
    std::string w;
    while (words >> w) {
      double v = 0;
      const auto [ptr, ec] = std::from_chars(w.data(), w.data() + w.size(), v);
      // As in the scene file itself: "nan", "inf" and numbers beyond the float range are
      // not spectrum values.
      if (ec != std::errc() || ptr != w.data() + w.size() || !std::isfinite(v) ||
          std::abs(v) > std::numeric_limits<float>::max())
        param_error(p, quote_excerpt(path, kPathExcerpt) +
                           ": expected finite numbers (wavelength, value pairs), got " +
                           quote_excerpt(w));
      values.push_back(v);
    }
  }
  if (values.size() < 2 || values.size() % 2 != 0)
    param_error(p, quote_excerpt(path, kPathExcerpt) +
                       ": expected (wavelength, value) pairs, got " +
                       std::to_string(values.size()) + " numbers");
  return values;
}

}  // namespace

Rgb spectrum_param_rgb(const Param& p, SpectrumKind kind, LoaderContext& ctx) {
  switch (p.type) {
    case ParamType::Rgb: {
      Rgb rgb(float(p.numbers[0]), float(p.numbers[1]), float(p.numbers[2]));
      if (rgb.r < 0 || rgb.g < 0 || rgb.b < 0) param_error(p, "RGB values must not be negative");
      if (kind == SpectrumKind::Albedo && rgb.max_component() > 1) {
        ctx.warnings.warn(p.where, p.declaration() + ": reflectance above 1 clamped to 1");
        rgb = clamp(rgb, 0.f, 1.f);
      }
      // pbrt-v4 divides light spectra by the photometric value of the colour space's
      // illuminant, so RGB emission comes out as written.
      return rgb;
    }
    case ParamType::Blackbody: {
      const float kelvin = float(p.numbers[0]);
      if (!(kelvin > 0))
        param_error(
            p, "expected a positive temperature in kelvin, got " + format_number(p.numbers[0]));
      const Rgb rgb = blackbody_rgb(kelvin);
      // Only reached for a few kelvin, where Planck's law underflows to zero everywhere in
      // the visible range: such a light would silently be black.
      if (!rgb.is_finite() || !(rgb.luminance() > 0))
        param_error(p,
                    "a blackbody at " + format_number(p.numbers[0]) + " K emits no visible light");
      return rgb;
    }
    case ParamType::Spectrum: {
      if (p.strings.empty()) return sampled_spectrum_rgb(p.numbers, kind);
      if (std::optional<Rgb> named = named_spectrum(p.strings[0])) {
        if (kind == SpectrumKind::Illuminant && named->luminance() > 0)
          return *named / named->luminance();
        return *named;
      }
      return sampled_spectrum_rgb(read_spectrum_file(p, ctx.resolve(p.strings[0], p.where)), kind);
    }
    default:
      param_error(p, "expected type rgb, spectrum or blackbody");
  }
}

}  // namespace caustica::pbrt
