// Spectral values of pbrt-v4 scene files turned into our linear Rec.709 RGB: blackbody
// temperatures, (wavelength, value) tables and named spectra. Uses the CIE 1931 matching
// functions in the multi-lobe Gaussian fit of Wyman, Sloan and Shirley (JCGT 2013).
#pragma once

#include <optional>
#include <string_view>
#include <vector>

#include "core/rgb.h"

namespace caustica::pbrt {

// What a spectrum means, which decides its normalisation (pbrt-v4's SpectrumType).
enum class SpectrumKind {
  Albedo,      // reflectance in [0,1]: RGB of the spectrum under D65, divided by Y(D65)
  Unbounded,   // eta, k: same projection as Albedo, no clamping
  Illuminant,  // emission: photometrically normalised, so its luminance is 1 (pbrt-v4 lights)
};

// Linear sRGB of a blackbody at `kelvin`, with luminance Y = 1 (pbrt-v4 normalises light
// spectra by their photometric value, so only the colour of a blackbody matters).
Rgb blackbody_rgb(float kelvin);

// RGB of a piecewise-linear spectrum given as (wavelength nm, value) pairs.
Rgb sampled_spectrum_rgb(const std::vector<double>& lambda_value_pairs, SpectrumKind kind);

// Named spectra: pbrt-v4's built-in metals and glasses (from materials/), and the standard
// illuminants "stdillum-*" (as luminance-1 RGB). Nothing if unknown.
std::optional<Rgb> named_spectrum(std::string_view name);

}  // namespace caustica::pbrt
