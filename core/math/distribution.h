// Piecewise-constant 1D and 2D distributions (inverse-CDF sampling), used for environment-map
// importance sampling. Built once per map; sampling is O(log n).
#pragma once

#include <vector>

#include "math/types.h"

namespace freqlab {

class Distribution1D {
  public:
    Distribution1D() = default;
    explicit Distribution1D(const float* weights, int n);  // weights >= 0; all-zero → uniform

    // Continuous sample in [0, 1); `pdf` is the density with respect to [0, 1); `index` the bin.
    float sample(float u, float* pdf, int* index) const;
    float pdf_of_bin(int i) const { return weights_[size_t(i)] / integral_; }
    float probability_of_bin(int i) const {
        return weights_[size_t(i)] / (integral_ * float(size()));
    }
    int size() const { return int(weights_.size()); }
    float integral() const { return integral_; }  // mean weight

  private:
    std::vector<float> weights_;
    std::vector<double> cdf_;  // size n + 1, cdf_[n] = 1
    float integral_ = 0.0f;
};

// Density over [0,1)^2 proportional to a width x height grid of weights (row 0 at v = 0).
class Distribution2D {
  public:
    Distribution2D() = default;
    Distribution2D(const std::vector<float>& weights, int width, int height);

    vec2 sample(vec2 u, float* pdf) const;
    float pdf(vec2 uv) const;
    int width() const { return width_; }
    int height() const { return height_; }
    // Probability mass of texel (x, y): what a chi-square test compares counts against.
    double texel_probability(int x, int y) const;

  private:
    int width_ = 0, height_ = 0;
    std::vector<Distribution1D> conditional_;  // one per row
    Distribution1D marginal_;                  // over rows
};

}  // namespace freqlab
