#include "math/distribution.h"

#include <algorithm>

namespace freqlab {

namespace {

// guide[g] = the step i with cdf[i] <= g / steps < cdf[i + 1].
template <class Index>
void build_guide(const double* cdf, int steps, Index* guide) {
    int i = 0;
    for (int g = 0; g < steps; ++g) {
        const double t = double(g) / steps;
        while (i + 1 < steps && cdf[i + 1] <= t) ++i;
        guide[g] = Index(i);
    }
}

// The step i with cdf[i] <= u < cdf[i + 1] (so never a step of zero mass) and where u falls
// in it, for u in [0, 1) and cdf running from 0 to 1: walked from `start` (a guide's entry,
// never past the answer), or binary-searched when start < 0.
int invert_step(const double* cdf, int steps, int start, double u, float* fraction) {
    int i = start;
    if (i >= 0)
        while (i + 1 < steps && cdf[i + 1] <= u) ++i;
    else
        i = std::clamp(int(std::upper_bound(cdf, cdf + steps + 1, u) - cdf) - 1, 0, steps - 1);
    const double mass = cdf[i + 1] - cdf[i];
    *fraction = mass > 0.0 ? std::min(float((u - cdf[i]) / mass), 0x1.fffffep-1f) : 0.5f;
    return i;
}

size_t guide_slot(float u, int steps) {
    return size_t(std::min(int(u * float(steps)), steps - 1));
}

}  // namespace

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

    // The inversion tables, on the same (float) densities the alias table and pdf() use.
    row_cdf_.assign(size_t(height) + 1, 0.0);
    column_cdf_.assign(size_t(height) * (size_t(width) + 1), 0.0);
    for (int y = 0; y < height; ++y) {
        double* row = &column_cdf_[size_t(y) * (size_t(width) + 1)];
        for (int x = 0; x < width; ++x) row[x + 1] = row[x] + pdf_[size_t(y) * width + x];
        row_cdf_[size_t(y) + 1] = row_cdf_[size_t(y)] + row[width];
        if (row[width] > 0.0)
            for (int x = 1; x <= width; ++x) row[x] /= row[width];
    }
    for (double& v : row_cdf_) v /= row_cdf_.back();
    row_guide_.resize(size_t(height));
    build_guide(row_cdf_.data(), height, row_guide_.data());
    if (width <= 65535) {
        column_guide_.resize(size_t(height) * width);
        for (int y = 0; y < height; ++y)
            build_guide(&column_cdf_[size_t(y) * (size_t(width) + 1)], width,
                        &column_guide_[size_t(y) * width]);
    }
}

Distribution2D::Inversion Distribution2D::invert_begin(vec2 u) const {
    Inversion s;
    s.u_x = u.x;
    s.row = invert_step(row_cdf_.data(), height_, int(row_guide_[guide_slot(u.y, height_)]),
                        double(u.y), &s.within.y);
    s.column = -1;
    if (!column_guide_.empty())
        __builtin_prefetch(
            &column_guide_[size_t(s.row) * size_t(width_) + guide_slot(u.x, width_)]);
    return s;
}

void Distribution2D::invert_guide(Inversion& s) const {
    if (column_guide_.empty()) return;
    s.column = column_guide_[size_t(s.row) * size_t(width_) + guide_slot(s.u_x, width_)];
    __builtin_prefetch(&column_cdf_[size_t(s.row) * (size_t(width_) + 1) + size_t(s.column)]);
}

int Distribution2D::invert_finish(Inversion& s) const {
    const double* cdf = &column_cdf_[size_t(s.row) * (size_t(width_) + 1)];
    return s.row * width_ + invert_step(cdf, width_, s.column, double(s.u_x), &s.within.x);
}

int Distribution2D::sample_texel_inverted(vec2 u, vec2* within) const {
    Inversion s = invert_begin(u);
    invert_guide(s);
    const int texel = invert_finish(s);
    *within = s.within;
    return texel;
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
