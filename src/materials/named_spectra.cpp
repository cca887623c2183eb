// RGB stand-ins for pbrt-v4's built-in named spectra (pbrt-v4 util/spectrum.cpp).
//
// How the numbers were obtained (offline, Python, no fitting):
//  * Metals (eta and k separately): each tabulated spectrum s(lambda) (piecewise linear, as
//    pbrt-v4 interpolates it) is averaged with weights w_c(lambda), one per linear sRGB channel:
//        w_c(lambda) ~ D(lambda) * [M_XYZ->sRGB * (xbar, ybar, zbar)(lambda)]_c,
//    normalised so that sum_lambda w_c = 1 (360..830 nm, 1 nm steps). D is a 6504 K Planck
//    spectrum standing in for D65 (the white of pbrt-v4's "rgb" lights and of sRGB), xbar, ybar,
//    zbar the CIE 1931 2-degree matching functions in the multi-lobe Gaussian fit of Wyman,
//    Sloan and Shirley (JCGT 2013). A spectrally flat value therefore maps to grey, and the
//    weights are the sRGB channel responses, so the result is "the spectrum as each channel
//    sees it". Check: Fresnel reflectance computed from these RGB eta/k versus the sRGB
//    projection of the spectral Fresnel reflectance differs by <= 0.011 (Ag, Al), <= 0.015
//    (Cu) and <= 0.043 (Au red at normal incidence: the spectral result is 1.01, out of gamut,
//    which no RGB eta/k can reproduce), at 0, 60 and 80 degrees.
//  * metal-CuZn-*: the CuZn tables were not in the pbrt-v4 snapshot available to us. The values
//    are a third-party projection of pbrt-v4's CuZn tables (CIE 1931 weights normalised by the
//    integral of ybar, i.e. equal-energy white -> sRGB (1.2048, 0.9483, 0.9088)) divided by
//    that white so that they follow the convention above; expect a few percent difference.
//  * Glasses: pbrt-v4 renders them with dispersion; here the IOR is grey, the value of pbrt-v4's
//    table linearly interpolated at 550 nm.
#include <string>
#include <unordered_map>

#include "materials/materials.h"

namespace caustica {

std::optional<Rgb> named_spectrum_rgb(std::string_view name) {
  static const std::unordered_map<std::string_view, Rgb> table = {
      {"metal-Ag-eta", Rgb(0.1286f, 0.1232f, 0.1518f)},
      {"metal-Ag-k", Rgb(4.0274f, 3.3009f, 2.3773f)},
      {"metal-Al-eta", Rgb(1.3861f, 0.9334f, 0.5801f)},
      {"metal-Al-k", Rgb(7.6874f, 6.6226f, 5.3422f)},
      {"metal-Au-eta", Rgb(0.1034f, 0.3915f, 1.5692f)},
      {"metal-Au-k", Rgb(3.3519f, 2.5146f, 1.7781f)},
      {"metal-Cu-eta", Rgb(0.1307f, 0.9723f, 1.2050f)},
      {"metal-Cu-k", Rgb(3.2442f, 2.6001f, 2.3616f)},
      {"metal-CuZn-eta", Rgb(0.4314f, 0.5151f, 1.1466f)},
      {"metal-CuZn-k", Rgb(3.5942f, 2.6870f, 1.7516f)},
      {"glass-BK7", Rgb(1.51854f)},
      {"glass-BAF10", Rgb(1.67305f)},
      {"glass-FK51A", Rgb(1.48780f)},
      {"glass-LASF9", Rgb(1.85581f)},
      {"glass-F5", Rgb(1.67709f)},
      {"glass-F10", Rgb(1.73357f)},
      {"glass-F11", Rgb(1.79112f)},
  };
  const auto it = table.find(name);
  if (it == table.end()) return std::nullopt;
  return it->second;
}

}  // namespace caustica
