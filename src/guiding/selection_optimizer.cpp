#include "guiding/selection_optimizer.h"

#include <algorithm>
#include <cmath>

namespace caustica {

namespace {

// Müller 2019's hyperparameters (Adam's own defaults but the learning rate).
constexpr double kLearningRate = 0.01, kBeta1 = 0.9, kBeta2 = 0.999, kEpsilon = 1e-8;
constexpr double kRegularization = 0.001, kBatchWeight = 1, kThetaBound = 20;

double logistic(double x) { return 1 / (1 + std::exp(-x)); }

}  // namespace

void SelectionOptimizer::add(float product_over_pdf, float bsdf_pdf, float guide_pdf,
                             float statistical_weight) {
  const double alpha = logistic(theta_);
  const double mixture = alpha * bsdf_pdf + (1 - alpha) * guide_pdf;
  if (!(mixture > 0) || !std::isfinite(product_over_pdf)) return;
  const double d_alpha = -double(product_over_pdf) * (double(bsdf_pdf) - guide_pdf) / mixture;
  const double gradient =
      d_alpha * alpha * (1 - alpha) + kRegularization * theta_ * statistical_weight;
  if (!std::isfinite(gradient)) return;
  batch_gradient_ += gradient;
  batch_weight_ += statistical_weight;
  if (batch_weight_ > kBatchWeight) {
    step(batch_gradient_ / batch_weight_);
    batch_gradient_ = batch_weight_ = 0;
  }
}

void SelectionOptimizer::step(double gradient) {
  beta1_power_ *= kBeta1;
  beta2_power_ *= kBeta2;
  const double rate = kLearningRate * std::sqrt(1 - beta2_power_) / (1 - beta1_power_);
  first_moment_ = kBeta1 * first_moment_ + (1 - kBeta1) * gradient;
  second_moment_ = kBeta2 * second_moment_ + (1 - kBeta2) * gradient * gradient;
  theta_ -= rate * first_moment_ / (std::sqrt(second_moment_) + kEpsilon);
  theta_ = std::clamp(theta_, -kThetaBound, kThetaBound);
  fraction_ = float(logistic(theta_));
}

}  // namespace caustica
