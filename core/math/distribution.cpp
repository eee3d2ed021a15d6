#include "math/distribution.h"

#include <algorithm>
#include <stdexcept>
#include <string>

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

double Distribution2D::tile_inflation(const std::vector<float>& weights, int width, int height,
                                      int tile) {
    double second = 0.0, sum = 0.0;
    for (int ty = 0; ty < height / tile; ++ty)
        for (int tx = 0; tx < width / tile; ++tx) {
            double tile_sum = 0.0, tile_squares = 0.0;
            for (int y = ty * tile; y < (ty + 1) * tile; ++y)
                for (int x = tx * tile; x < (tx + 1) * tile; ++x) {
                    const double w = std::max(weights[size_t(y) * width + x], 0.0f);
                    tile_sum += w;
                    tile_squares += w * w;
                }
            sum += tile_sum;
            if (tile_sum > 0.0) second += tile_squares * double(tile * tile) / tile_sum;
        }
    return sum > 0.0 ? second / sum : 1.0;
}

namespace {

int chosen_tile(const std::vector<float>& weights, int width, int height, double* inflation) {
    *inflation = 1.0;
    if (size_t(width) * size_t(height) < Distribution2D::kMinTiledTexels) return 1;
    for (int tile = Distribution2D::kMaxTile; tile > 1; tile /= 2) {
        if (width % tile != 0 || height % tile != 0) continue;
        const double k = Distribution2D::tile_inflation(weights, width, height, tile);
        if (k <= Distribution2D::kMaxTileInflation) {
            *inflation = k;
            return tile;
        }
    }
    return 1;
}

}  // namespace

Distribution2D::Distribution2D(const std::vector<float>& weights, int width, int height, int tile)
    : width_(width), height_(height) {
    if (tile == 0) {
        tile = chosen_tile(weights, width, height, &inflation_);
    } else {
        if (tile < 1 || (tile & (tile - 1)) != 0 || width % tile != 0 || height % tile != 0)
            throw std::invalid_argument("Distribution2D: tile " + std::to_string(tile) +
                                        " is not a power of two dividing " + std::to_string(width) +
                                        " x " + std::to_string(height));
        inflation_ = tile > 1 ? tile_inflation(weights, width, height, tile) : 1.0;
    }
    while ((1 << tile_shift_) < tile) ++tile_shift_;
    tiles_x_ = width >> tile_shift_;
    tiles_y_ = height >> tile_shift_;
    const size_t n = size_t(tiles_x_) * size_t(tiles_y_);
    std::vector<double> tile_weight(n, 0.0);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            tile_weight[tile_index(x, y)] += std::max(weights[size_t(y) * width + x], 0.0f);
    double sum = 0.0;
    for (size_t i = 0; i < n; ++i) sum += tile_weight[i];
    pdf_.resize(n);
    alias_.resize(n);
    for (size_t i = 0; i < n; ++i) {
        // All-zero weights: fall back to uniform rather than divide by zero.
        pdf_[i] = sum > 0 ? float(tile_weight[i] * double(n) / sum) : 1.0f;
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
    const int tw = tiles_x_, th = tiles_y_;
    row_cdf_.assign(size_t(th) + 1, 0.0);
    column_cdf_.assign(size_t(th) * (size_t(tw) + 1), 0.0);
    for (int y = 0; y < th; ++y) {
        double* row = &column_cdf_[size_t(y) * (size_t(tw) + 1)];
        for (int x = 0; x < tw; ++x) row[x + 1] = row[x] + pdf_[size_t(y) * tw + x];
        row_cdf_[size_t(y) + 1] = row_cdf_[size_t(y)] + row[tw];
        if (row[tw] > 0.0)
            for (int x = 1; x <= tw; ++x) row[x] /= row[tw];
    }
    for (double& v : row_cdf_) v /= row_cdf_.back();
    row_guide_.resize(size_t(th));
    build_guide(row_cdf_.data(), th, row_guide_.data());
    if (tw <= 65535) {
        column_guide_.resize(size_t(th) * tw);
        for (int y = 0; y < th; ++y)
            build_guide(&column_cdf_[size_t(y) * (size_t(tw) + 1)], tw,
                        &column_guide_[size_t(y) * tw]);
    }
}

int Distribution2D::texel_in_tile(int tile_x, int tile_y, vec2 within) const {
    const int f = 1 << tile_shift_;
    const int x = (tile_x << tile_shift_) + std::min(int(within.x * float(f)), f - 1);
    const int y = (tile_y << tile_shift_) + std::min(int(within.y * float(f)), f - 1);
    return y * width_ + x;
}

Distribution2D::Inversion Distribution2D::invert_begin(vec2 u) const {
    Inversion s;
    s.u_x = u.x;
    s.row = invert_step(row_cdf_.data(), tiles_y_, int(row_guide_[guide_slot(u.y, tiles_y_)]),
                        double(u.y), &s.within.y);
    s.column = -1;
    if (!column_guide_.empty())
        __builtin_prefetch(
            &column_guide_[size_t(s.row) * size_t(tiles_x_) + guide_slot(u.x, tiles_x_)]);
    return s;
}

void Distribution2D::invert_guide(Inversion& s) const {
    if (column_guide_.empty()) return;
    s.column = column_guide_[size_t(s.row) * size_t(tiles_x_) + guide_slot(s.u_x, tiles_x_)];
    __builtin_prefetch(&column_cdf_[size_t(s.row) * (size_t(tiles_x_) + 1) + size_t(s.column)]);
}

int Distribution2D::invert_finish(Inversion& s) const {
    const double* cdf = &column_cdf_[size_t(s.row) * (size_t(tiles_x_) + 1)];
    const int column = invert_step(cdf, tiles_x_, s.column, double(s.u_x), &s.within.x);
    return texel_in_tile(column, s.row, s.within);
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
    const int tile = int(u.y >= e.keep ? e.alias : uint32_t(i));
    if (tile_shift_ == 0) return tile;
    return texel_in_tile(tile % tiles_x_, tile / tiles_x_, vec2(u.z, u.w));
}

vec2 Distribution2D::texel_point(int texel, const vec4& u) const {
    const int x = (texel % width_) >> tile_shift_, y = (texel / width_) >> tile_shift_;
    return vec2(std::min((x + u.z) / tiles_x_, 0x1.fffffep-1f),
                std::min((y + u.w) / tiles_y_, 0x1.fffffep-1f));
}

vec2 Distribution2D::sample(const vec4& u, float* pdf) const {
    const int i = sample_texel(u);
    *pdf = texel_pdf(i);
    return texel_point(i, u);
}

float Distribution2D::pdf(vec2 uv) const {
    const int x = std::clamp(int(uv.x * width_), 0, width_ - 1);
    const int y = std::clamp(int(uv.y * height_), 0, height_ - 1);
    return pdf_[tile_index(x, y)];
}

double Distribution2D::texel_probability(int x, int y) const {
    return double(pdf_[tile_index(x, y)]) / (double(width_) * double(height_));
}

}  // namespace freqlab
