// The learned probability of sampling the BSDF instead of the learned distribution at one spatial
// leaf (Müller 2019, "Practical Path Guiding in Production", the BSDF-sampling-fraction
// optimization): alpha = logistic(theta), theta trained by Adam (Kingma and Ba 2014) on the
// gradient of the KL divergence between the mixture density
//   p_alpha(w) = alpha p_bsdf(w) + (1 - alpha) p_guide(w)
// and the ideal density, proportional to f(w) |cos| L_i(w) ("the product"). With a sample w
// drawn from density p_s and the product P:
//   dD/dalpha ~= -(P / p_s) (p_bsdf - p_guide) / p_alpha,   dalpha/dtheta = alpha (1 - alpha),
// plus an L2 regularization 0.001 theta (per unit statistical weight) that keeps theta finite.
// Gradients are averaged in batches of statistical weight > 1 (path vertices weigh 1, next
// event samples 0), and each batch takes one Adam step (learning rate 0.01, theta in [-20, 20]).
//
// Determinism: add() is sequential; the field calls it for each leaf's records in a fixed order.
#pragma once

namespace caustica {

class SelectionOptimizer {
 public:
  // The probability of sampling the BSDF. Starts at 0.5 (theta = 0).
  float bsdf_fraction() const { return fraction_; }
  // One sample: the product over the density it was sampled with (P / p_s), and the BSDF's and
  // the learned distribution's densities at its direction (solid angle).
  void add(float product_over_pdf, float bsdf_pdf, float guide_pdf, float statistical_weight);
  double theta() const { return theta_; }

 private:
  void step(double gradient);

  double theta_ = 0;
  float fraction_ = 0.5f;  // logistic(theta_)
  double first_moment_ = 0, second_moment_ = 0;
  double beta1_power_ = 1, beta2_power_ = 1;  // beta1^steps, beta2^steps
  double batch_gradient_ = 0, batch_weight_ = 0;
};

}  // namespace caustica
