#include "math/distribution.h"

#include <algorithm>

namespace freqlab {

Distribution2D::Distribution2D(const std::vector<float>& weights, int width, int height)
    : width_(width), height_(height) {
    const size_t n = size_t(width) * height;
    double sum = 0.0;
    for (size_t i = 0; i < n; ++i) sum += std::max(weights[i], 0.0f);
    pdf_.resize(n);
    alias_.resize(n);
    for (size_t i = 0; i < n; ++i) {
        // All-zero weights: fall back to uniform rather than divide by zero.
        pdf_[i] = sum > 0 ? float(std::max(weights[i], 0.0f) * double(n) / sum) : 1.0f;
        alias_[i] = AliasEntry{1.0f, uint32_t(i)};
    }
    // Vose's construction on scaled probabilities p_i * n (mean 1).
    std::vector<double> scaled(pdf_.begin(), pdf_.end());
    std::vector<uint32_t> small, large;
    for (size_t i = 0; i < n; ++i) (scaled[i] < 1.0 ? small : large).push_back(uint32_t(i));
    while (!small.empty() && !large.empty()) {
        const uint32_t s = small.back(), l = large.back();
        small.pop_back();
        alias_[s] = AliasEntry{float(scaled[s]), l};
        scaled[l] = (scaled[l] + scaled[s]) - 1.0;
        if (scaled[l] < 1.0) {
            large.pop_back();
            small.push_back(l);
        }
    }
    // Leftovers are 1 up to rounding: they keep themselves (keep = 1 already).
}

int Distribution2D::sample_texel(const vec4& u) const {
    const size_t i = alias_slot(u);
    const AliasEntry& e = alias_[i];
    return int(u.y >= e.keep ? e.alias : uint32_t(i));
}

vec2 Distribution2D::texel_point(int texel, const vec4& u) const {
    const int x = texel % width_, y = texel / width_;
    return vec2(std::min((x + u.z) / width_, 0x1.fffffep-1f),
                std::min((y + u.w) / height_, 0x1.fffffep-1f));
}

vec2 Distribution2D::sample(const vec4& u, float* pdf) const {
    const int i = sample_texel(u);
    *pdf = pdf_[size_t(i)];
    return texel_point(i, u);
}

float Distribution2D::pdf(vec2 uv) const {
    const int x = std::clamp(int(uv.x * width_), 0, width_ - 1);
    const int y = std::clamp(int(uv.y * height_), 0, height_ - 1);
    return pdf_[size_t(y) * width_ + x];
}

double Distribution2D::texel_probability(int x, int y) const {
    return double(pdf_[size_t(y) * width_ + x]) / double(pdf_.size());
}

}  // namespace freqlab
