#include "io/pbrt/spectrum_param.h"

#include <charconv>
#include <fstream>
#include <sstream>

namespace caustica::pbrt {

namespace {

std::vector<double> read_spectrum_file(const Param& p, const std::string& path) {
  std::ifstream in(path);
  if (!in)
    param_error(
        p, "\"" + p.strings[0] + "\" is neither a built-in named spectrum nor a readable file");
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
      if (ec != std::errc() || ptr != w.data() + w.size())
        param_error(
            p, "\"" + path + "\": expected numbers (wavelength, value pairs), got \"" + w + "\"");
      values.push_back(v);
    }
  }
  if (values.size() < 2 || values.size() % 2 != 0)
    param_error(p, "\"" + path + "\": expected (wavelength, value) pairs, got " +
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
    case ParamType::Blackbody:
      return blackbody_rgb(float(p.numbers[0]));
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
