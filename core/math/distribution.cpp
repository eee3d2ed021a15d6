#include "math/distribution.h"

#include <algorithm>

namespace freqlab {

Distribution1D::Distribution1D(const float* w, int n) : weights_(w, w + n), cdf_(size_t(n) + 1) {
    double sum = 0.0;
    cdf_[0] = 0.0;
    for (int i = 0; i < n; ++i) cdf_[size_t(i) + 1] = sum += double(std::max(w[i], 0.0f));
    if (sum <= 0.0) {
        // Nothing to prefer: sample uniformly rather than divide by zero.
        std::fill(weights_.begin(), weights_.end(), 1.0f);
        for (int i = 0; i <= n; ++i) cdf_[size_t(i)] = double(i) / n;
        integral_ = 1.0f;
        return;
    }
    for (double& c : cdf_) c /= sum;
    cdf_[size_t(n)] = 1.0;
    integral_ = float(sum / n);
}

float Distribution1D::sample(float u, float* pdf, int* index) const {
    // Last bin whose cdf <= u, skipping zero-width bins.
    const auto it = std::upper_bound(cdf_.begin(), cdf_.end(), double(u));
    const int i = std::clamp(int(it - cdf_.begin()) - 1, 0, size() - 1);
    const double width = cdf_[size_t(i) + 1] - cdf_[size_t(i)];
    const double du = width > 0 ? (double(u) - cdf_[size_t(i)]) / width : 0.0;
    *pdf = pdf_of_bin(i);
    *index = i;
    return std::min(float((i + du) / size()), 0x1.fffffep-1f);
}

Distribution2D::Distribution2D(const std::vector<float>& weights, int width, int height)
    : width_(width), height_(height) {
    std::vector<float> row_integrals(static_cast<size_t>(height));
    conditional_.reserve(size_t(height));
    for (int y = 0; y < height; ++y) {
        conditional_.emplace_back(&weights[size_t(y) * width], width);
        // A row of zeros was made uniform by Distribution1D; its mass must still be zero.
        float sum = 0;
        for (int x = 0; x < width; ++x) sum += std::max(weights[size_t(y) * width + x], 0.0f);
        row_integrals[size_t(y)] = sum / width;
    }
    marginal_ = Distribution1D(row_integrals.data(), height);
}

vec2 Distribution2D::sample(vec2 u, float* pdf) const {
    float pdf_row, pdf_col;
    int row, col;
    const float v = marginal_.sample(u.y, &pdf_row, &row);
    const float x = conditional_[size_t(row)].sample(u.x, &pdf_col, &col);
    *pdf = pdf_row * pdf_col;
    return vec2(x, v);
}

float Distribution2D::pdf(vec2 uv) const {
    const int x = std::clamp(int(uv.x * width_), 0, width_ - 1);
    const int y = std::clamp(int(uv.y * height_), 0, height_ - 1);
    return marginal_.pdf_of_bin(y) * conditional_[size_t(y)].pdf_of_bin(x);
}

double Distribution2D::texel_probability(int x, int y) const {
    return double(marginal_.probability_of_bin(y)) * conditional_[size_t(y)].probability_of_bin(x);
}

}  // namespace freqlab
