#include "chi2.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

namespace caustica::test {

namespace {

Vec3 dir_from_cell(double cos_theta, double phi) {
  const double s = std::sqrt(std::max(0.0, 1 - cos_theta * cos_theta));
  return Vec3(float(s * std::cos(phi)), float(s * std::sin(phi)), float(cos_theta));
}

// Regularised upper incomplete gamma Q(a, x) (Numerical Recipes' series / continued fraction).
double gamma_q(double a, double x) {
  if (x <= 0) return 1;
  const double gln = std::lgamma(a);
  if (x < a + 1) {
    double sum = 1 / a, del = sum, ap = a;
    for (int n = 0; n < 1000; ++n) {
      ap += 1;
      del *= x / ap;
      sum += del;
      if (std::abs(del) < std::abs(sum) * 1e-14) break;
    }
    return 1 - sum * std::exp(-x + a * std::log(x) - gln);
  }
  double b = x + 1 - a, c = 1e300, d = 1 / b, h = d;
  for (int i = 1; i < 1000; ++i) {
    const double an = -i * (i - a);
    b += 2;
    d = an * d + b;
    if (std::abs(d) < 1e-300) d = 1e-300;
    c = b + an / c;
    if (std::abs(c) < 1e-300) c = 1e-300;
    d = 1 / d;
    const double del = d * c;
    h *= del;
    if (std::abs(del - 1) < 1e-14) break;
  }
  return std::exp(-x + a * std::log(x) - gln) * h;
}

}  // namespace

double integrate_sphere(const std::function<double(Vec3)>& f, int theta_res, int phi_res) {
  // Midpoint rule in (cos theta, phi): the measure dcos dphi is exactly solid angle.
  double sum = 0;
  const double dz = 2.0 / theta_res, dphi = 2 * M_PI / phi_res;
  for (int i = 0; i < theta_res; ++i)
    for (int j = 0; j < phi_res; ++j)
      sum += f(dir_from_cell(-1 + (i + 0.5) * dz, (j + 0.5) * dphi));
  return sum * dz * dphi;
}

Chi2Result chi2_test(const std::function<std::optional<DirectionSample>(Pcg32&)>& sample,
                     const std::function<float(Vec3)>& pdf, const Chi2Options& o) {
  Chi2Result res;
  const int nt = o.theta_bins, np = o.phi_bins;
  std::vector<double> observed(size_t(nt) * np, 0), expected(size_t(nt) * np, 0);
  Pcg32 rng(o.seed, 0x1234);
  int ok = 0;
  std::ostringstream diag;
  int pdf_mismatch = 0;
  for (int i = 0; i < o.sample_count; ++i) {
    auto s = sample(rng);
    if (!s) continue;
    const Vec3 w = normalize(s->w);
    ++ok;
    const double z = std::clamp(double(w.z), -1.0, 1.0);
    double phi = std::atan2(double(w.y), double(w.x));
    if (phi < 0) phi += 2 * M_PI;
    const int ti = std::min(nt - 1, int((z + 1) / 2 * nt));
    const int pi = std::min(np - 1, int(phi / (2 * M_PI) * np));
    observed[size_t(ti) * np + pi] += 1;
    // The pdf a sample reports must equal pdf() for the same direction.
    const float p = pdf(w);
    if (std::abs(p - s->pdf) > 1e-3f * std::max(1.f, std::max(p, s->pdf)) && pdf_mismatch++ < 3)
      diag << "sample pdf " << s->pdf << " != pdf() " << p << " at (" << w.x << "," << w.y << ","
           << w.z << "); ";
  }
  res.sampled_mass = double(ok) / o.sample_count;
  // Expected counts: integrate the pdf over each cell with a sub-grid.
  const int sub = 16;
  double total = 0;
  for (int ti = 0; ti < nt; ++ti)
    for (int pi = 0; pi < np; ++pi) {
      const double z0 = -1 + 2.0 * ti / nt, z1 = -1 + 2.0 * (ti + 1) / nt;
      const double p0 = 2 * M_PI * pi / np, p1 = 2 * M_PI * (pi + 1) / np;
      double acc = 0;
      for (int a = 0; a < sub; ++a)
        for (int b = 0; b < sub; ++b)
          acc += pdf(
              dir_from_cell(z0 + (a + 0.5) * (z1 - z0) / sub, p0 + (b + 0.5) * (p1 - p0) / sub));
      const double integral = acc * (z1 - z0) * (p1 - p0) / (sub * sub);
      expected[size_t(ti) * np + pi] = integral * o.sample_count;
      total += integral;
    }
  res.pdf_integral = total;
  // Pool low-expectation cells (sorted by expectation) so the chi-square approximation holds.
  std::vector<size_t> order(expected.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return expected[a] < expected[b]; });
  double pooled_obs = 0, pooled_exp = 0, chsq = 0;
  int dof = 0;
  for (size_t idx : order) {
    if (expected[idx] == 0) {
      if (observed[idx] > o.sample_count * 1e-5) {
        diag << "samples in a cell where pdf is zero (" << observed[idx] << "); ";
        res.message = diag.str();
        return res;
      }
      continue;
    }
    if (expected[idx] < o.min_expected) {
      pooled_obs += observed[idx];
      pooled_exp += expected[idx];
    } else {
      chsq += sqr(observed[idx] - expected[idx]) / expected[idx];
      ++dof;
    }
  }
  if (pooled_exp > 0 || pooled_obs > 0) {
    chsq += sqr(pooled_obs - pooled_exp) / std::max(pooled_exp, 1e-9);
    ++dof;
  }
  // The lost mass is a cell of its own: failed samples vs 1 - integral.
  const double lost_obs = o.sample_count - ok, lost_exp = std::max(0.0, 1 - total) * o.sample_count;
  if (lost_exp >= o.min_expected) {
    chsq += sqr(lost_obs - lost_exp) / lost_exp;
    ++dof;
  }
  dof -= 1;
  res.statistic = chsq;
  res.dof = dof;
  res.p_value = dof > 0 ? gamma_q(dof / 2.0, chsq / 2.0) : 1.0;
  res.passed = res.p_value >= o.significance && pdf_mismatch == 0 && total <= 1.0 + 1e-2;
  diag << "chi2=" << chsq << " dof=" << dof << " p=" << res.p_value << " pdf_integral=" << total
       << " sampled=" << res.sampled_mass;
  res.message = diag.str();
  return res;
}

}  // namespace caustica::test
