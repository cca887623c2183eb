#include "io/pbrt/color.h"

#include <cmath>
#include <string>

#include "materials/materials.h"

namespace caustica::pbrt {

namespace {

double lobe(double lambda, double mu, double s1, double s2) {
  const double t = (lambda - mu) / (lambda < mu ? s1 : s2);
  return std::exp(-0.5 * t * t);
}

// CIE 1931 2-degree matching functions, Wyman et al. 2013, eq. 2-4.
void cie_xyz(double l, double* x, double* y, double* z) {
  *x = 1.056 * lobe(l, 599.8, 37.9, 31.0) + 0.362 * lobe(l, 442.0, 16.0, 26.7) -
       0.065 * lobe(l, 501.1, 20.4, 26.2);
  *y = 0.821 * lobe(l, 568.8, 46.9, 40.5) + 0.286 * lobe(l, 530.9, 16.3, 31.1);
  *z = 1.217 * lobe(l, 437.0, 11.8, 36.0) + 0.681 * lobe(l, 459.0, 26.0, 13.8);
}

Rgb xyz_to_rgb(double x, double y, double z) {
  return {float(3.2404542 * x - 1.5371385 * y - 0.4985314 * z),
          float(-0.9692660 * x + 1.8760108 * y + 0.0415560 * z),
          float(0.0556434 * x - 0.2040259 * y + 1.0572252 * z)};
}

// CIE standard illuminant D65, 380-780 nm in 10 nm steps.
constexpr double kD65[41] = {49.98,  54.65,  82.75,  91.49,  93.43,  86.68,  104.86, 117.01, 117.81,
                             114.86, 115.92, 108.81, 109.35, 107.80, 104.79, 107.69, 104.41, 104.05,
                             100.00, 96.33,  95.79,  88.69,  90.01,  89.60,  87.70,  83.29,  83.70,
                             80.03,  80.21,  82.28,  78.28,  69.72,  71.61,  74.35,  61.60,  69.89,
                             75.09,  63.59,  46.42,  66.81,  63.38};

double d65(double l) {
  const double f = (l - 380) / 10;
  if (f <= 0) return kD65[0];
  if (f >= 40) return kD65[40];
  const int i = int(f);
  return kD65[i] + (f - i) * (kD65[i + 1] - kD65[i]);
}

double planck(double lambda_nm, double kelvin) {
  const double c = 299792458., h = 6.62606957e-34, kb = 1.3806488e-23;
  const double l = lambda_nm * 1e-9;
  // expm1: for hot bodies the exponent is tiny and exp(x) - 1 would round to 0 (a division
  // by zero, then NaN colours), where expm1(x) = x keeps the Rayleigh-Jeans limit.
  return (2 * h * c * c) / (std::pow(l, 5) * std::expm1((h * c) / (l * kb * kelvin)));
}

template <typename F>
Rgb integrate(F spectrum, bool under_d65, bool normalise_luminance) {
  double x = 0, y = 0, z = 0, y_white = 0;
  for (double l = 360; l <= 830; l += 1) {
    double cx, cy, cz;
    cie_xyz(l, &cx, &cy, &cz);
    const double w = under_d65 ? d65(l) : 1.0;
    const double s = spectrum(l) * w;
    x += s * cx;
    y += s * cy;
    z += s * cz;
    y_white += w * cy;
  }
  const double norm = normalise_luminance ? (y != 0 ? 1 / y : 0) : 1 / y_white;
  return xyz_to_rgb(x * norm, y * norm, z * norm);
}

}  // namespace

Rgb blackbody_rgb(float kelvin) {
  if (!(kelvin > 0)) return Rgb(0.f);
  return integrate([&](double l) { return planck(l, kelvin); }, false, true);
}

Rgb sampled_spectrum_rgb(const std::vector<double>& pairs, SpectrumKind kind) {
  const size_t n = pairs.size() / 2;
  if (n == 0) return Rgb(0.f);
  auto eval = [&](double l) {
    if (l <= pairs[0]) return pairs[1];
    if (l >= pairs[2 * (n - 1)]) return pairs[2 * (n - 1) + 1];
    size_t i = 0;
    while (i + 1 < n && pairs[2 * (i + 1)] < l) ++i;
    const double l0 = pairs[2 * i], l1 = pairs[2 * (i + 1)];
    const double t = (l - l0) / (l1 - l0);
    return pairs[2 * i + 1] * (1 - t) + pairs[2 * i + 3] * t;
  };
  if (kind == SpectrumKind::Illuminant) return integrate(eval, false, true);
  Rgb rgb = integrate(eval, true, false);
  if (kind == SpectrumKind::Albedo) rgb = clamp(rgb, 0.f, 1.f);
  return rgb;
}

std::optional<Rgb> named_spectrum(std::string_view name) {
  if (name == "stdillum-D65") return Rgb(1.f);
  if (name == "stdillum-A") return blackbody_rgb(2856);
  if (name == "stdillum-D50") return blackbody_rgb(5003);
  if (name.substr(0, 10) == "stdillum-F") return blackbody_rgb(4200);
  return named_spectrum_rgb(name);
}

}  // namespace caustica::pbrt
