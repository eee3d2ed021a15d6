#include "image/colormap.h"

#include <algorithm>
#include <cmath>

namespace freqlab {

namespace {

vec3 hex(unsigned v) {
    return vec3(float((v >> 16) & 255), float((v >> 8) & 255), float(v & 255)) / 255.0f;
}

// Piecewise-linear through evenly spaced control colours (sRGB display values).
vec3 ramp(const unsigned* stops, int n, float t) {
    t = std::clamp(t, 0.0f, 1.0f) * float(n - 1);
    const int i = std::min(int(t), n - 2);
    return glm::mix(hex(stops[i]), hex(stops[i + 1]), t - float(i));
}

unsigned char to_byte(float v) {
    return (unsigned char)std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f);
}

}  // namespace

vec3 viridis(float t) {
    // matplotlib's viridis sampled at 9 evenly spaced points.
    static const unsigned stops[] = {0x440154, 0x472d7b, 0x3b528b, 0x2c728e, 0x21918c,
                                     0x28ae80, 0x5ec962, 0xaddc30, 0xfde725};
    return ramp(stops, 9, t);
}

vec3 diverging(float t) {
    static const unsigned stops[] = {0x3b4cc0, 0x8db0fe, 0xf7f7f7, 0xf49a7b, 0xb40426};
    return ramp(stops, 5, 0.5f * (t + 1.0f));
}

vec3 categorical(int index) {
    static const unsigned palette[] = {0x1f77b4, 0xff7f0e, 0x2ca02c, 0xd62728, 0x9467bd,
                                       0x8c564b, 0xe377c2, 0x7f7f7f, 0xbcbd22, 0x17becf};
    return hex(palette[((index % 10) + 10) % 10]);
}

std::vector<vec3> layer_palette(const Layer& layer) {
    if (!layer.palette.empty()) return layer.palette;
    std::vector<vec3> p(10);
    for (int i = 0; i < 10; ++i) p[size_t(i)] = categorical(i);
    return p;
}

vec3 category_colour(const Layer& layer, int index) {
    if (layer.palette.empty()) return categorical(index);
    const int n = int(layer.palette.size());
    return layer.palette[size_t(((index % n) + n) % n)];
}

float linear_to_srgb(float c) {
    c = std::clamp(c, 0.0f, 1.0f);
    return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

std::vector<double> colorbar_ticks(double lo, double hi, int max_ticks) {
    std::vector<double> ticks;
    if (!(hi > lo) || max_ticks < 2) return {lo, hi};
    const double raw = (hi - lo) / (max_ticks - 1);
    const double mag = std::pow(10.0, std::floor(std::log10(raw)));
    double step = mag;
    for (double m : {1.0, 2.0, 5.0, 10.0})
        if (m * mag >= raw) {
            step = m * mag;
            break;
        }
    // Ticks as k / (1/step) when step < 1 (1/step is an integer for 1-2-5 steps): 3 / 5 rounds
    // to 0.6 exactly where 3 * 0.2 does not.
    const double inverse = step < 1 ? std::round(1.0 / step) : 0.0;
    for (double k = std::ceil(lo / step); k * step <= hi + 1e-9 * step; k += 1) {
        const double t = inverse > 0 ? k / inverse : k * step;
        ticks.push_back(t == 0 ? 0.0 : t);
    }
    return ticks;
}

DisplayRange auto_range(const Layer& layer) {
    float lo = INFINITY, hi = -INFINITY;
    for (float v : layer.data)
        if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
    if (!(lo <= hi)) return {0.0f, 1.0f};
    if (layer.kind == LayerKind::Signed) {
        const float m = std::max(std::max(std::fabs(lo), std::fabs(hi)), 1e-20f);
        return {-m, m};
    }
    if (layer.channels == 1) {
        // Robust upper end: the 99.5th percentile, so one firefly (a sun glint in a variance
        // layer) does not flatten everything else into the bottom colour.
        std::vector<float> finite;
        finite.reserve(layer.data.size());
        for (float v : layer.data)
            if (std::isfinite(v)) finite.push_back(v);
        const size_t k = size_t(0.995 * double(finite.size() - 1));
        std::nth_element(finite.begin(), finite.begin() + long(k), finite.end());
        hi = finite[k];
    }
    if (hi <= lo) hi = lo + 1.0f;
    return {lo, hi};
}

std::vector<unsigned char> layer_to_rgb8(const LayerSet& set, const Layer& layer,
                                         const DisplayParams& params) {
    const size_t npix = set.pixel_count();
    std::vector<unsigned char> rgb(npix * 3);
    const DisplayRange range = params.auto_range ? auto_range(layer) : params.range;
    const float scale = std::exp2(params.exposure_ev);
    const vec3 magenta(1.0f, 0.0f, 1.0f);
    for (size_t p = 0; p < npix; ++p) {
        const float* v = &layer.data[p * layer.channels];
        bool finite = true;
        for (int c = 0; c < layer.channels; ++c) finite = finite && std::isfinite(v[c]);
        vec3 out;
        if (!finite) {
            out = magenta;
        } else if (layer.kind == LayerKind::Color) {
            for (int c = 0; c < 3; ++c)
                out[c] = linear_to_srgb(scale * v[std::min(c, layer.channels - 1)]);
        } else if (layer.kind == LayerKind::Categorical) {
            out = category_colour(layer, int(std::lround(v[0])));
        } else if (layer.channels >= 3) {
            // Vectors show component-wise, mapped from the range to [0, 1] (normal maps).
            for (int c = 0; c < 3; ++c) out[c] = (v[c] - range.lo) / (range.hi - range.lo);
        } else if (layer.kind == LayerKind::Signed) {
            out = diverging(v[0] / range.hi);
        } else {
            out = viridis((v[0] - range.lo) / (range.hi - range.lo));
        }
        for (int c = 0; c < 3; ++c) rgb[p * 3 + c] = to_byte(out[c]);
    }
    return rgb;
}

}  // namespace freqlab
